"""Scene configuration: frozen dataclasses for every stage and their loader.

A configuration is a TOML or JSON file in ``envs_configs/``, a plain dict, or ``None``
for the built-in default scene. The defaults written here are the same as the files
ship, so an installed wheel works without the folder. Unknown keys and bad values
raise :class:`ConfigError` naming the key and the file.

All quantities are SI (metres, kilograms, seconds, newtons, radians).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import tomllib
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, TypeVar

__all__ = [
    "FIDELITY_PRESETS",
    "MOST_VOTE_FRAMES",
    "PRESET_DRIFT_MM",
    "SPECK_AREA",
    "ConfigError",
    "ContactConfig",
    "ObjectConfig",
    "PhysicsConfig",
    "ProxyConfig",
    "SceneConfig",
    "SurfaceConfig",
    "at_fidelity",
    "build_section",
    "choose_fidelity",
    "load_config",
    "read_config",
    "read_config_file",
    "refined_contour",
    "resolve_fidelity",
    "scene_from",
]

#: The specks ``contacts.min_area = "auto"`` drops: smaller than four pixels of the
#: default 0.61 × 0.46 m table at 640 × 480, m².
SPECK_AREA = 4.0 * (0.61 / 640) * (0.46 / 480)

#: The most masks ``contacts.vote_frames`` may vote over: a quarter of a second at
#: 60 Hz, a lag of seven frames on every motion.
MOST_VOTE_FRAMES = 15

#: Particle sphere radius, metres, by default (``proxy.particle_radius``).
DEFAULT_PARTICLE_RADIUS = 0.002
#: Pairs of shrink-free passes along each outline that the ``reference`` preset's
#: finer contour needs (``ContactConfig.outline_smoothing``; the default has none).
OUTLINE_SMOOTHING = 6

ShapeName = Literal["box", "sphere", "cylinder"]
ProxyName = Literal["persistent", "instant", "rigid"]
MatcherName = Literal["auto", "fast", "exhaustive"]


T = TypeVar("T")


class ConfigError(ValueError):
    """A configuration key is unknown or its value is not what the key expects."""


@dataclass(frozen=True)
class SurfaceConfig:
    """The imaging table.

    Attributes:
        size: table top (width, height) in metres.
        resolution: camera image (columns W, rows H) in pixels.
        fps: camera frames per second.
    """

    size: tuple[float, float] = (0.61, 0.46)
    resolution: tuple[int, int] = (640, 480)
    fps: float = 60.0

    def __post_init__(self) -> None:
        _positive("surface.size", self.size)
        _positive("surface.resolution", self.resolution)
        _positive("surface.fps", (self.fps,))


@dataclass(frozen=True)
class ContactConfig:
    """How a mask becomes tracked contours.

    Attributes:
        spacing: arc-length spacing of resampled contour points, metres, or
            ``"auto"``: one particle diameter (``2 · proxy.particle_radius``, 4 mm at
            the defaults), so neighbouring particles just touch: closer, the spheres
            overlap and add bodies that grip no better; farther, a corner can slip
            between them. A scene resolves it from its own particle radius
            (:class:`SceneConfig`); a tracker on its own, from the default radius.
        match_radius: largest centroid travel, metres per frame, for a contact to keep
            its id from one frame to the next.
        min_area: components with fewer pixels than this are dropped as sensor
            noise, as table software drops specks below a minimum blob size (0 keeps
            single pixels); or ``"auto"``: :data:`SPECK_AREA` (3.65 mm², four pixels
            of the default 640 × 480 table) in this table's pixels, so the filter
            keeps its size in millimetres when the resolution changes. On the default
            table it removes isolated flipped pixels and most pairs, while the
            smallest real contact, a light 5 mm fingertip, covers about 85 pixels:
            measured on the canonical turn with 0.05 % of pixels flipped, it takes
            the specks from 155 to 0 contacts a frame and the turn's error from 50°
            to 0.3° (2026-12-07). At 320 × 240 it is one pixel and drops nothing: there a
            fingertip cut by dropout holes leaves fragments of a few pixels that
            matter to the grip (README, "Model only what a scene needs").
        close_px: width of the elliptical kernel of a morphological closing (OpenCV)
            applied to each mask before it is traced, pixels, odd (an even kernel
            has no centre and shifts the mask); 0 (the default) leaves
            the mask as it is. It fills dropout holes that cut a contact's edge and
            smooths jittered edges, but joins contacts closer than about its width
            (two fingertips 4 mm apart at 5 px on the default table). Measured
            against noise level with ``graspenv bench --noise`` (README, "A real
            sensor's masks").
        fill_px: fill a frame's dropouts from the previous frame's mask, but only
            within this many pixels of what is touched now (after the closing;
            specks smaller than ``min_area`` do not count, so a flipped pixel beside
            a lifted finger keeps nothing of it); 0 (the default) turns it off. A
            hole that flickers from frame to frame (a camera's dropout) is filled;
            one that stays is not, and a finger that moves leaves at most this much
            of its trailing edge behind for a frame.
        vote_frames: take each pixel as touched where it was touched in most of the
            last this many masks (odd, at most :data:`MOST_VOTE_FRAMES`), before the
            closing and the fill; 1 (the default) turns it off. A component of the
            frame's own mask of which the vote keeps less than half (a finger
            touching down, or one moving more than about two fifths of its width in
            a frame) is taken as it is, without the voted pixels where it was.
            It averages out edge jitter that changes from frame to frame, which the
            closing and the fill do not, at the price of a lag of (n − 1)/2 frames on
            a contact's motion and on a lift (README, "A real sensor's masks").
        outline_smoothing: pairs of Taubin's shrink-free smoothing passes along each
            traced outline, after its own [-1, 4, 10, 4, -1] / 16 filter
            (:mod:`graspenv.contacts.extract`); 0 (the default) turns it off. They
            damp what is left of the pixel staircase, which the contour's points
            would otherwise follow from frame to frame as the fingers cross the
            pixels, without shrinking a fingertip's outline (its scatter about a
            true ellipse's edge 0.177 → 0.143 px RMS, its mean −0.016 → −0.005 px
            at six, ``python -m graspenv.bench.outline``). A contour sampled finer
            than the default's needs them: without, a 2 mm contour lags the turn on
            small objects; the ``reference`` preset's has six
            (:data:`OUTLINE_SMOOTHING`). At the default's 4 mm contour six gain
            little (over the grid the turn 0.008° nearer, two more cylinders of 100
            within 5 % of Coulomb) and are not taken (docs/accuracy.md, "A reference
            that converges").
    """

    spacing: float | Literal["auto"] = "auto"
    match_radius: float = 0.03
    min_area: float | Literal["auto"] = "auto"
    close_px: int = 0
    fill_px: int = 0
    vote_frames: int = 1
    outline_smoothing: int = 0

    def __post_init__(self) -> None:
        if self.spacing != "auto":
            _positive("contacts.spacing", (self.spacing,))
        _positive("contacts.match_radius", (self.match_radius,))
        if self.min_area != "auto" and self.min_area < 0:
            raise ConfigError(f"contacts.min_area must be >= 0 or 'auto', got {self.min_area}")
        for key in ("close_px", "fill_px", "outline_smoothing"):
            value = getattr(self, key)
            if not isinstance(value, int) or isinstance(value, bool) or value < 0:
                raise ConfigError(f"contacts.{key} must be a whole number >= 0, got {value!r}")
        if self.close_px % 2 == 0 and self.close_px > 0:
            # An even kernel has no centre: OpenCV's closing then shifts the mask.
            raise ConfigError(f"contacts.close_px must be 0 or odd, got {self.close_px}")
        votes = self.vote_frames
        if not (
            isinstance(votes, int)
            and not isinstance(votes, bool)
            and 1 <= votes <= MOST_VOTE_FRAMES
            and votes % 2 == 1
        ):
            raise ConfigError(
                f"contacts.vote_frames must be an odd whole number from 1 to "
                f"{MOST_VOTE_FRAMES}, got {votes!r}"
            )

    def min_area_pixels(self, pixel_area: float) -> float:
        """The smallest component kept, pixels, on a table whose pixels cover
        ``pixel_area`` m² (:attr:`min_area`, ``"auto"`` resolved)."""
        if isinstance(self.min_area, str):
            return SPECK_AREA / pixel_area
        return self.min_area

    def contour_spacing(self, particle_radius: float = DEFAULT_PARTICLE_RADIUS) -> float:
        """The spacing in metres: ``spacing``, or one diameter of particles of this
        radius (metres) for ``"auto"``."""
        return 2.0 * particle_radius if isinstance(self.spacing, str) else self.spacing

    def resolved(self, particle_radius: float = DEFAULT_PARTICLE_RADIUS) -> ContactConfig:
        """This configuration with the spacing in metres (:meth:`contour_spacing`)."""
        return dataclasses.replace(self, spacing=self.contour_spacing(particle_radius))


#: How many numbers each shape's ``size`` has: a box's full extents (x, y, z), a
#: sphere's radius, a cylinder's radius and height.
SIZE_VALUES: dict[str, int] = {"box": 3, "sphere": 1, "cylinder": 2}


@dataclass(frozen=True)
class ObjectConfig:
    """A rigid object that starts resting on the table.

    Attributes:
        name: unique name used by ``Simulation.object_pose(name)``.
        shape: ``box``, ``sphere`` or ``cylinder``.
        size: full extents ``[x, y, z]`` (box), ``[radius]`` (sphere) or
            ``[radius, height]`` (cylinder), metres.
        mass: kilograms.
        position: centre (x, y) on the table, metres, world frame.
        yaw: rotation about z, radians.
        friction: lateral friction coefficient (Bullet multiplies the two bodies').
        rolling_friction: Bullet's rolling friction coefficient.
        spinning_friction: Bullet's spinning (torsional) friction coefficient.
        restitution: coefficient of restitution.
    """

    name: str
    shape: ShapeName
    size: tuple[float, ...]
    mass: float = 0.2
    position: tuple[float, float] = (0.0, 0.0)
    yaw: float = 0.0
    friction: float = 0.5
    rolling_friction: float = 0.0
    spinning_friction: float = 0.0
    restitution: float = 0.0

    def __post_init__(self) -> None:
        expected = SIZE_VALUES[self.shape]
        if len(self.size) != expected:
            raise ConfigError(
                f"objects[{self.name}].size for a {self.shape} needs {expected} value(s), "
                f"got {list(self.size)}"
            )
        _positive(f"objects[{self.name}].size", self.size)
        _positive(f"objects[{self.name}].mass", (self.mass,))
        for key in ("friction", "rolling_friction", "spinning_friction", "restitution"):
            if getattr(self, key) < 0:
                raise ConfigError(f"objects[{self.name}].{key} must be >= 0")

    @property
    def height(self) -> float:
        """Height of the object's top above the table when resting, metres."""
        if self.shape == "box":
            return self.size[2]
        if self.shape == "sphere":
            return 2.0 * self.size[0]
        return self.size[1]

    def level_push_mass(self, height: float) -> float:
        """The object's mass as a level push at ``height`` metres above the table
        feels it, kilograms: 1 / (1/m + h²/I), with h the push's line below the centre
        of mass and I the least moment of inertia about a level axis through it
        (uniform density). Pushed below its centre, an object turns as well as
        moves, so it gives way as a lighter one would. A sphere's is its mass: a
        push along a normal passes through its centre."""
        if self.shape == "sphere":
            return self.mass
        below = max(0.0, self.height / 2.0 - height)
        return 1.0 / (1.0 / self.mass + below**2 / self.level_inertia)

    @property
    def level_inertia(self) -> float:
        """The least moment of inertia about a level axis through the centre of mass,
        kg·m² (uniform density)."""
        if self.shape == "box":
            width, depth, tall = self.size
            return self.mass * (min(width, depth) ** 2 + tall**2) / 12
        if self.shape == "cylinder":
            radius, tall = self.size
            return self.mass * (3 * radius**2 + tall**2) / 12
        return 0.4 * self.mass * self.size[0] ** 2


@dataclass(frozen=True)
class ProxyConfig:
    """How contact contours become particle bodies.

    Attributes:
        method: ``persistent`` (Wilson ITS 2009), ``instant`` (UIST 2008) or ``rigid``.
        particle_radius: sphere radius, metres.
        particle_mass: kilograms per sphere in a scene whose lightest object weighs
            200 g (or in any scene with ``mass_ratio`` 0), the mass at which
            ``physics.max_particle_force`` and ``down_force`` are given. With
            ``physics.control_time`` it sets the grip stiffness m/Δt² (1152 N/m per
            particle at the defaults): stiff enough that a firm squeeze holds a box
            against a third finger's push (under 2 mm), soft enough that the 20 N force
            clamp is reached only past about 17 mm.
        mass_ratio: what a particle weighs as a share of the scene's lightest object
            (0 turns it off and every particle weighs ``particle_mass``). The
            particles' force clamp (``physics.max_particle_force``) and press on the
            table (``down_force``) scale with their mass, so the lightest object is
            gripped with the same margin over its weight whatever it weighs:
            scaling every mass and force of a grasp by one factor leaves its motion
            as it was. Without it, 20 g
            particles squeezing a 5 g box outweigh it fourfold and it jumps out of
            the grip, and a 2 kg box lags a turn by 2.25° (docs/design.md, section
            3b). The press on an object's top is not scaled (it is the finger's, and
            rubs a light object along). :attr:`SceneConfig.particle_settings`
            resolves it.
        effective_mass_ratio: the most a particle may weigh, at the law's own
            step (``physics.control_time``), as a share of an object's mass as a
            level push at a particle's centre feels it
            (:meth:`ObjectConfig.level_push_mass`); where it weighs more, the
            scene's frames take more, shorter sub-steps, the step shrinking by the
            excess (:attr:`SceneConfig.sub_steps`; 0 turns it off). A push below
            an object's centre of mass meets a lighter object, one that also turns:
            1.5 g particles (a tenth of its mass) squeezing a 15 g cylinder 3.1 cm
            wide and 4.4 cm tall, which a push there feels as 5.3 g, tipped it out
            of the grip at half of Coulomb's force at four sub-steps and held it at
            eight (docs/accuracy.md, "A tall object's sub-steps"). Lighter particles held it
            too, but gripped it more softly; the shorter step keeps the grip's
            stiffness. 0.15 is a little above the canonical 6 × 6 × 3 cm box's own
            share (20 g against the 138 g it feels), so its scenes and those of
            flatter objects are as they were.
        particle_friction: lateral friction of a particle. Bullet multiplies it by the
            object's: the default 2.0 gives a finger–object coefficient of 1.0 on a 0.5
            object, which a firm squeeze needs to resist a third finger's push; a
            bottom particle's friction acts only in the table plane.
        window: n of the windowed sum of squared distances over points i = -n/2..n/2
            (n + 1 points; an odd n acts as n - 1).
        matcher: ``exhaustive`` (the paper's search over every shift), ``fast`` (FFT
            alignment then a local search) or ``auto`` (exhaustive while it is the
            cheaper of the two, up to 256 × 256 point pairs, fast beyond).
        search: half-width S of the fast matcher's local search, contour indices.
        stack_layers: spheres per contour point (1 = single layer), or ``"auto"``:
            stacks of ``round_stack_layers`` in a scene with an object whose sides are
            not vertical (a sphere: one layer cannot cradle a ball, it squeezes it out
            of the grasp), single particles otherwise (boxes and cylinders stand with
            vertical sides, which a stack would only add bodies to). Model only what
            the scene needs; :attr:`SceneConfig.stack_layers` resolves it.
        round_stack_layers: the stack height ``"auto"`` uses for round objects.
        stack_spacing: height between stacked spheres, metres.
        down_force: constant downward force on each bottom particle resting on an
            object (a finger's press on its top), newtons; on the table it is scaled
            with the particle's mass (``mass_ratio``).
        penetration_limit: place a contact that appears deep inside an object's
            footprint on its top face.
        penetration_margin: how deep inside a footprint, metres, a contour point must
            be for the penetration limit to put its particle on the top face (from
            the nearest side, or, a particle radius deeper, from the side its
            particle is at). Keep it
            about 1 mm above the deepest squeeze that should hold an object: 7 mm, for
            the grasp-space grid's deepest squeeze of 6 mm (at 5 mm the deepest points
            of a 6 mm squeeze went on top, unevenly on the two sides, and the box slid
            2.4 % off its path).
        cull: give a physics body only to contour points that could touch an object
            soon; the others stay plain contour points, still matched from frame to
            frame, and get a body as they come near (model only what a scene needs).
        cull_margin: safety distance of culling, metres. A point gets a body once it
            is nearer an object's footprint than the particle radius plus twice its
            contact's travel in the last frame plus the fastest object's travel in a
            frame plus this margin, and loses it beyond that reach plus this margin
            again (so a point near the boundary does not flicker).
        track_hand_rotation: estimate one rigid rotation of the hand from all its
            contacts' centroids and apply it to previous points before matching.
        predicted_resampling: resample a continuing contour starting from the
            predicted previous points, so points do not jitter along the contour.
        follow_points: with ``predicted_resampling``, move each predicted point
            onto the new outline along the contour's normal (filling gaps and
            dropping crowded points) instead of resampling evenly from the first
            one. Evenly spaced points slide along a round fingertip's outline as its
            pixelated perimeter changes from frame to frame (about 0.15 mm a frame
            on an 8 mm tip), drift by degrees over a turn, and shear the object
            (README, "Points that land where the contact moved them").
        smoothing: gain of an alpha-beta filter on each followed contour point (1 =
            off, the points as the contour gives them): a point moves this share of
            the way from where its own velocity predicts it to where it is seen. For
            a noisy table, whose edges wobble by a pixel a frame (docs/design.md,
            section 3b); a steady motion is followed without lag.
        smoothing_gate: a contact whose centroid lands further than this from
            where the filter expects it, metres, is taken as seen (a strike or a
            sudden start is motion, not noise).
        hold_time: the side hold's time constant, seconds (0: off; an option, off in
            every preset): over about this long, a contact's targets shift along the
            object side its particles press until they stand where the hand puts
            them, as a rigid fingertip's would (step 7 of
            :mod:`graspenv.proxies.persistent`). Without it a grip gives along the
            side by its load over the law's stiffness, up to the friction coefficient
            times the squeeze depth before it slips, and on a curved side that give
            costs normal force. Each frame's increments are the rigid motion of
            each object that best fits its particles' shortfalls. At 0.05 s and
            ``reference`` the grid's cylinders slipped within 5 % of Coulomb in 79
            of 100 cells instead of 44, its turns erred 0.086° instead of 0.143° on
            average and the two-hand carry ended 0.85 mm off instead of 1.27, but
            under dropout holes the turn errs more than without it (docs/accuracy.md, "The
            side hold"). A hold time of a frame or less takes up the whole
            shortfall each frame; only the ``persistent`` method has it.
        share_side_load: a fingertip's particles pressing one object's side share
            its load along the side by how deep they press, as one rigid contact
            (step 8 of :mod:`graspenv.proxies.persistent`): without it each stuck
            particle carries the same load, the least pressed slip first and the
            grip creeps before it slips, and round a curved side that creep costs
            or gains normal force (docs/accuracy.md, "A fingertip shares its side load").
            Only the ``persistent`` method has it.
        instant_stride: pixel subsample of the instant method's gradient pixels.
        rigid_height: height of the rigid method's contact bodies, metres.
    """

    method: ProxyName = "persistent"
    particle_radius: float = DEFAULT_PARTICLE_RADIUS
    particle_mass: float = 0.02
    mass_ratio: float = 0.1
    effective_mass_ratio: float = 0.15
    particle_friction: float = 2.0
    window: int = 4
    matcher: MatcherName = "auto"
    search: int = 3
    stack_layers: int | Literal["auto"] = "auto"
    round_stack_layers: int = 3
    stack_spacing: float = 0.004
    down_force: float = 0.05
    penetration_limit: bool = True
    penetration_margin: float = 0.007
    cull: bool = True
    cull_margin: float = 0.004
    rigid_height: float = 0.01
    track_hand_rotation: bool = True
    predicted_resampling: bool = True
    follow_points: bool = True
    smoothing: float = 1.0
    smoothing_gate: float = 0.003
    hold_time: float = 0.0
    share_side_load: bool = True
    instant_stride: int = 2

    def __post_init__(self) -> None:
        _positive("proxy.particle_radius", (self.particle_radius,))
        _positive("proxy.particle_mass", (self.particle_mass,))
        if self.stack_layers != "auto":
            _positive("proxy.stack_layers", (self.stack_layers,))
        _positive("proxy.round_stack_layers", (self.round_stack_layers,))
        _positive("proxy.instant_stride", (self.instant_stride,))
        _positive("proxy.rigid_height", (self.rigid_height,))
        for key in ("window", "search"):
            if getattr(self, key) < 0:
                raise ConfigError(f"proxy.{key} must be >= 0, got {getattr(self, key)}")
        if self.particle_friction < 0 or self.down_force < 0 or self.stack_spacing < 0:
            raise ConfigError("proxy.particle_friction, down_force, stack_spacing must be >= 0")
        for key in ("mass_ratio", "effective_mass_ratio"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value >= 0):
                raise ConfigError(f"proxy.{key} must be finite and >= 0, got {value}")
        if self.cull_margin < 0:
            raise ConfigError(f"proxy.cull_margin must be >= 0, got {self.cull_margin}")
        if self.penetration_margin < 0:
            raise ConfigError(
                f"proxy.penetration_margin must be >= 0, got {self.penetration_margin}"
            )
        if not 0.0 < self.smoothing <= 1.0:
            raise ConfigError(f"proxy.smoothing must be in (0, 1], got {self.smoothing}")
        if not (math.isfinite(self.hold_time) and self.hold_time >= 0):
            raise ConfigError(f"proxy.hold_time must be finite and >= 0, got {self.hold_time}")
        if not self.smoothing_gate > 0:
            raise ConfigError(f"proxy.smoothing_gate must be > 0, got {self.smoothing_gate}")


@dataclass(frozen=True)
class PhysicsConfig:
    """Bullet settings.

    Attributes:
        substeps: physics steps per camera frame; the particle force law is recomputed
            on every one of them (Bullet's own ``numSubSteps`` would reapply a stale force).
            A frame in which something moves fast gets more (``substep_travel``).
        max_substeps: the most physics steps a fast frame gets; at ``substeps`` (or
            below) every frame gets exactly ``substeps``. At 16 one of 10 000 fuzz
            episodes broke (a light box rattling in stick-slip on a table of friction
            1.8 let a particle 1.03 mm into it in a frame at the cap); at 32 none
            did, before the particles of heavy objects were made heavier (then one
            did, in a frame of 7 sub-steps, until ``substep_travel`` became 0.25 mm).
            Slow frames never reach it; the coarse setting
            (envs_configs/coarse.toml, the old ``fast``) keeps 16.
        substep_travel: the farthest an object's point or a particle may move in one
            physics step, metres: a frame whose fastest point would move further
            gets as many more steps as that needs, up to ``max_substeps``. Bullet's
            box contacts tip and sink a turned box at longer steps, and a particle
            moving further than this in a step ends deeper in what it meets
            (docs/design.md, section 3b). The reduced-coordinate objects need 0.3
            mm at most: at 0.5 mm a box on a table of friction 2 rattles in
            stick-slip and a particle ends 1.15 mm inside it (1 mm allowed). At
            0.3 mm one of 10 000 long-fuzz episodes broke (a 99 g particle driven
            1.79 mm into a 991 g box squeezed by four fingers); at the default,
            0.25 mm, none do.
        solver_iterations: Bullet's constraint solver iterations (the most; an
            island stops earlier once converged). A firm grip's island converges
            slowly: at 50 a box squeezed 4.5 mm deep rocked out of a still grip and
            stacked particles slipped 7 % short of Coulomb; at 150 both are within
            1.5 % (docs/accuracy.md, "The solver's iterations and the force clamp").
        gravity: metres per second squared, pointing down.
        table_friction: the table's lateral friction coefficient.
        max_particle_force: clamp on each particle's planar control force, newtons,
            for particles of ``proxy.particle_mass`` (it scales with their mass).
            Under the old 5 N a 20 g particle pressed 3 mm in had 3.6 N left for
            friction and the grip slipped early; at 10 N a box of friction 1 (2 with
            the fingertip) still slipped 10-13 % short of Coulomb's force, at 20 N
            within 2 % (docs/accuracy.md, "The solver's iterations and the force clamp").
        max_particle_speed: clamp on each particle's commanded speed, m/s.
        ccd: continuous collision detection for particles (swept sphere): the
            guard against hard strikes (tests/stability). Off in ``fast``; it cost
            half the default's frame while it swept the whole particle, about a
            tenth since (docs/speed.md, "How fast: the lean frame").
        ccd_sphere: the radius of the sphere CCD sweeps, as a share of the
            particle's radius (Bullet's ``ccdSweptSphereRadius``; its motion
            threshold is half that). Bullet wants a sphere embedded in the shape,
            smaller than it. At a whole radius the sweep of a squeezed particle
            hits the object it presses at once, and CCD stopped the particle's
            motion along the side too: a 3.1 cm, 15 g cylinder squeezed 5.5 mm by
            broad fingertips turned 0.3-2.1° short (five placements), and the
            default's cylinders slipped nearer Coulomb than ``reference``'s only
            because their particles were held. At a quarter CCD leaves a grasp
            nearly alone (every error of the bench the same as ``fast``'s to the
            digit, the grid's and the sample's within a few hundredths) and still
            stops a 3 m/s strike (tests/stability/test_guards.py). Unused when
            ``ccd`` is off.
        allowed_ccd_penetration: Bullet's allowed CCD penetration, metres.
        contact_breaking_threshold: how far from an object or the table a particle's
            contacts form, metres: within it the solver stops a particle before it
            touches instead of pushing it back out after (Bullet's own threshold is
            relative to the shapes' sizes and is set from this one,
            :func:`graspenv.physics.bodies.bullet_breaking_threshold`). Passed to
            Bullet as it was, 1 mm made the contacts 3.5 µm deep, and a particle
            closing faster than that in a sub-step ended inside what it struck.
        reduced_objects: build objects as one-link multibodies (reduced
            coordinates) instead of maximal-coordinate rigid bodies. PyBullet's
            maximal-coordinate path lets a box gripped away from the height of its
            centre of mass spin about the grip's normal (a 3 cm box held 2 mm up slips
            at 3 % of Coulomb's force); in reduced coordinates it holds, but the
            contacts are softer (hence ``contact_erp`` 0.4) and need the shorter
            ``substep_travel`` (docs/design.md, section 3b). Off in the coarse
            setting (envs_configs/coarse.toml).
        contact_erp: the share of a contact's penetration Bullet corrects in one
            step (its ``contactERP``; PyBullet's own default is 0.08). It sets how
            far a squeezing particle sinks into an object; reduced-coordinate
            objects need 0.4 (docs/design.md, section 3b).
        control_time: Δt of the particle control law (v* = (x* − x)/Δt,
            a* = (v* − v)/Δt), seconds. A particle held off its contour point by a
            depth d pushes with m·d/Δt², so this and ``proxy.particle_mass`` set the
            grip stiffness. It is kept apart from the sub-step so that more sub-steps
            resolve the same law more finely instead of stiffening it; the law uses
            the sub-step instead when that is longer (the law is unstable otherwise).
        stiff_tangent: an experiment, off in every preset: along an object's side
            (for a particle whose target lies inside a footprint or within two
            radii of one, the side of that footprint nearest it: on a box's top
            too, where it is the nearest edge's) the law's Δt is the configured
            sub-step where that is shorter than ``control_time`` (at eight
            sub-steps, four times as stiff), across it ``control_time``, so the
            squeeze keeps its force while the grip gives less under a load along
            the side (the table's friction on a turn, a push on a held cylinder).
            No change at four sub-steps or fewer. At ``reference`` it took the
            canonical turn from 0.13° to 0.09° and slipped 21 of the grid's 25
            cylinders within 5 % of Coulomb instead of 14, but slipped the 3 cm
            cylinders 23–75 % short (their contacts, held where they touched a
            side curved within a fingertip's width, used most of their friction
            before any push) and the noisy turn grew (docs/speed.md, "Speed
            against error").
        critical_damping: an experiment, off in every preset: the law's damping
            against the particle's velocity relative to its target's is (2 − h/Δt)·m/Δt
            instead of m/Δt in the table plane, which keeps a free particle's approach
            to its point critically damped at any sub-step h ≤ Δt (at h = Δt the law is the same
            to the bit; below it the law otherwise rings, a damping ratio of 0.5 in
            the limit). It measures what the ring does to the grid (docs/accuracy.md, "The
            slide's last tenth of a millimetre").
        pool_batch: particle bodies created at start and at each growth of the pool.
    """

    substeps: int = 4
    max_substeps: int = 32
    substep_travel: float = 0.00025
    solver_iterations: int = 150
    gravity: float = 9.81
    table_friction: float = 0.5
    max_particle_force: float = 20.0
    max_particle_speed: float = 5.0
    ccd: bool = True
    ccd_sphere: float = 0.25
    allowed_ccd_penetration: float = 0.0005
    contact_breaking_threshold: float = 0.001
    reduced_objects: bool = True
    contact_erp: float = 0.4
    control_time: float = 1.0 / 240.0
    stiff_tangent: bool = False
    critical_damping: bool = False
    pool_batch: int = 64

    def __post_init__(self) -> None:
        _positive("physics.substeps", (self.substeps,))
        _positive("physics.max_substeps", (self.max_substeps,))
        _positive("physics.substep_travel", (self.substep_travel,))
        _positive("physics.control_time", (self.control_time,))
        _positive("physics.pool_batch", (self.pool_batch,))
        _positive("physics.solver_iterations", (self.solver_iterations,))
        _positive("physics.max_particle_force", (self.max_particle_force,))
        _positive("physics.max_particle_speed", (self.max_particle_speed,))
        _positive("physics.contact_breaking_threshold", (self.contact_breaking_threshold,))
        if self.gravity < 0 or self.table_friction < 0:
            raise ConfigError("physics.gravity and physics.table_friction must be >= 0")
        if not 0.0 < self.contact_erp <= 1.0:
            raise ConfigError(f"physics.contact_erp must be in (0, 1], got {self.contact_erp}")
        if not 0.0 < self.ccd_sphere <= 1.0:
            raise ConfigError(f"physics.ccd_sphere must be in (0, 1], got {self.ccd_sphere}")


def _default_objects() -> tuple[ObjectConfig, ...]:
    return (ObjectConfig(name="box", shape="box", size=(0.06, 0.06, 0.03), mass=0.2),)


@dataclass(frozen=True)
class SceneConfig:
    """Everything one simulation needs; the built-in default is a 6 cm box."""

    surface: SurfaceConfig = field(default_factory=SurfaceConfig)
    contacts: ContactConfig = field(default_factory=ContactConfig)
    objects: tuple[ObjectConfig, ...] = field(default_factory=_default_objects)
    proxy: ProxyConfig = field(default_factory=ProxyConfig)
    physics: PhysicsConfig = field(default_factory=PhysicsConfig)

    def __post_init__(self) -> None:
        names = [o.name for o in self.objects]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise ConfigError(f"objects: names must be unique, repeated: {duplicates}")

    @property
    def contact_settings(self) -> ContactConfig:
        """The contacts section with an ``"auto"`` spacing made this scene's particle
        diameter (what the tracker and the proxies use)."""
        return self.contacts.resolved(self.proxy.particle_radius)

    @property
    def stack_layers(self) -> int:
        """Particles per contour point in this scene: ``proxy.stack_layers``, with
        ``"auto"`` resolved by the objects' shapes (see :class:`ProxyConfig`)."""
        layers = self.proxy.stack_layers
        if layers != "auto":
            return layers
        round_sided = any(o.shape == "sphere" for o in self.objects)
        return self.proxy.round_stack_layers if round_sided else 1

    @property
    def particle_scale(self) -> float:
        """The factor ``proxy.mass_ratio`` puts on the particles' mass, table press and
        force clamp in this scene: 1 when the lightest object weighs
        ``particle_mass / mass_ratio`` (200 g at the defaults), below 1 for lighter
        scenes and above it for heavier ones. It has no upper bound: the scaling
        argument holds at any mass, but the long fuzz (``graspenv bench --fuzz``)
        checks it only up to 5 kg (particles of 500 g and a 500 N clamp)."""
        proxy = self.proxy
        if proxy.mass_ratio == 0 or not self.objects:
            return 1.0
        scale = proxy.mass_ratio * min(o.mass for o in self.objects) / proxy.particle_mass
        # Rounding (0.1 · 0.2 kg is not 0.02 kg in binary) must not perturb a scene
        # whose particles already weigh the ratio's share.
        return 1.0 if math.isclose(scale, 1.0, rel_tol=1e-9) else scale

    @property
    def particle_settings(self) -> tuple[ProxyConfig, PhysicsConfig]:
        """The proxy and physics sections the physics uses: the particles' mass,
        press on the table and force clamp scaled by :attr:`particle_scale` (the sections
        themselves when it is 1)."""
        scale = self.particle_scale
        if scale == 1.0:
            return self.proxy, self.physics
        proxy = dataclasses.replace(
            self.proxy,
            particle_mass=self.proxy.particle_mass * scale,
            down_force=self.proxy.down_force * scale,
        )
        physics = dataclasses.replace(
            self.physics, max_particle_force=self.physics.max_particle_force * scale
        )
        return proxy, physics

    @property
    def sub_steps(self) -> int:
        """The sub-steps a frame takes at least: ``physics.substeps``, or more where a
        particle outweighs ``proxy.effective_mass_ratio`` of the mass an object feels
        at a particle's centre (:meth:`ObjectConfig.level_push_mass`), so that the
        step is ``physics.control_time`` times that share over the particle's, up to
        ``physics.max_substeps``."""
        proxy, physics = self.proxy, self.physics
        if proxy.effective_mass_ratio == 0 or not self.objects:
            return physics.substeps
        particle = proxy.particle_mass * self.particle_scale
        felt = min(o.level_push_mass(proxy.particle_radius) for o in self.objects)
        share = proxy.effective_mass_ratio * felt / particle
        if share >= 1.0:
            return physics.substeps
        # Each sub-step a particle hands the object the momentum it gains over the
        # step towards its point, reach·m/Δt·(h/Δt): what that moves an object
        # feeling M is the canonical scene's share of it when h shrinks by the
        # particle's excess over that share.
        step = physics.control_time * share
        # A hair under a whole number of steps is that number (rounding).
        needed = math.ceil(1.0 / (self.surface.fps * step) - 1e-9)
        return max(physics.substeps, min(needed, physics.max_substeps))

    def replace(self, **sections: Any) -> SceneConfig:
        """A copy with whole sections or section fields replaced (dicts are merged)."""
        return _build(SceneConfig, _merge(to_dict(self), sections), "scene", "<overrides>")


#: The reference samples the scene's contour this many times as finely, each particle
#: this many times lighter (:func:`refined_contour`).
REFERENCE_REFINEMENT = 2

#: Fidelity presets: section overrides from the cheapest to the most faithful, chosen
#: from the speed-against-error frontier that ``graspenv bench`` measures and the
#: grasp-space grid (docs/speed.md, "Speed against error"; docs/accuracy.md).
#: ``reference`` is the setting the benchmark's drift is measured against: the
#: scene refined in time and in space. In time, pinned here so that a scene file
#: cannot make its reference coarser: the default's body model (objects in reduced
#: coordinates, contact ERP 0.4, the 20 N clamp, CCD) with twice the sub-steps and
#: solver iterations. In space, relative to the scene (:func:`refined_contour`, which
#: :func:`at_fidelity` applies): the scene's own contour sampled
#: :data:`REFERENCE_REFINEMENT` times as finely (2 mm at the default's 4 mm), each
#: particle as many times lighter so that the grip is as stiff per millimetre of
#: contour, its outline smoothed by :data:`OUTLINE_SMOOTHING` pairs of shrink-free
#: passes, which the default does without. The clamp stays 20 N a particle, so a
#: fingertip's particles together may push twice as hard. Without
#: the shrink-free outline smoothing (``contacts.outline_smoothing``) the finer
#: contour followed the pixels' staircase and turned further off (0.254° against
#: 0.159° over the grid at seed 0); with it, over the grid at four placements, paired
#: with the default: turn 0.138° against 0.166°, slide 0.100 % against 0.115 %, slip
#: 0.44 % against 0.63 %, every cylinder within 5 % of Coulomb (docs/accuracy.md,
#: "A reference that converges").
FIDELITY_PRESETS: dict[str, dict[str, dict[str, Any]]] = {
    # The default's model without continuous collision detection, which cost half
    # of the default's frame (docs/speed.md; Bullet's stage of the canonical turn: 1.31 ms a frame
    # with it, 0.33 ms without; per-stage minima of one bench run, CCD then sweeping
    # the whole particle). Every error within twice the default's (2026-12-06: turn
    # 0.18° against 0.11°, the slide, the slip, the two-hand carry and the noisy
    # turn level, every drift within 0.06 mm of the reference of then); since CCD sweeps a
    # quarter of the particle (``physics.ccd_sphere``) every error of the bench is
    # the default's to the digit, CCD acting only on strikes. The sub-steps that
    # follow the motion keep fast strikes out of objects without CCD, up to the cap
    # of 32 a frame (tests/stability/test_guards.py). The old preset (two sub-steps,
    # 6 mm spacing, maximal-coordinate objects: 22× real time, but its turn 1.8°
    # off) is envs_configs/coarse.toml, and ``coarse`` in the benchmark.
    "fast": {"physics": {"ccd": False}},
    "default": {},
    # Refined in space as well by :func:`refined_contour` (:func:`at_fidelity`).
    "reference": {
        "physics": {
            "substeps": 8,
            "substep_travel": 0.00025,
            "max_substeps": 32,
            "solver_iterations": 300,
            "reduced_objects": True,
            "contact_erp": 0.4,
            "max_particle_force": 20.0,
            "ccd": True,
            "ccd_sphere": 0.25,
        },
    },
}

#: Each preset's measured error: the worst drift, millimetres, of the final object
#: poses of the benchmark's scenarios against the reference preset, each the mean
#: over three sub-pixel placements (``graspenv bench``, docs/speed.md, "Speed
#: against error"). Since the reference samples the contour at 2 mm (2026-12-07,
#: ``graspenv bench``), the worst for both is the noisy turn's, 1.67 mm: its masks'
#: holes and jitter send a finer contour's grip elsewhere (that turn's error spreads
#: by degrees over placements at every preset); on clean masks both end within
#: 0.7 mm of the reference (the flick's 0.68 mm; the turn's, the slide's and the
#: two-hand carry's within 0.09 mm). When the reference had the default's contour
#: both were within 0.053 mm (the flick). ``fast`` drifts no more than the default,
#: so ``auto`` picks ``fast`` for any budget of 1.67 mm or more (the old ``fast``, now
#: envs_configs/coarse.toml, drifts 20 mm on the flick).
PRESET_DRIFT_MM: dict[str, float] = {"fast": 1.67, "default": 1.67, "reference": 0.0}


def choose_fidelity(error_budget_mm: float) -> str:
    """The cheapest preset whose measured drift (:data:`PRESET_DRIFT_MM`) is within
    ``error_budget_mm``; ``reference`` when none is.

    ``fast`` drifts no more than the default (their drifts agree to 0.001 mm in
    every scenario), so a budget of its drift or more gives ``fast``, which has no
    CCD (the guard against hard strikes), and a smaller one gives ``reference``:
    the default is chosen by name only.

    Raises:
        ValueError: the budget is not a positive number.
    """
    if not (isinstance(error_budget_mm, int | float) and error_budget_mm > 0):
        raise ValueError(f"error_budget must be a positive number of mm, got {error_budget_mm!r}")
    for name in FIDELITY_PRESETS:
        if PRESET_DRIFT_MM[name] <= error_budget_mm:
            return name
    return "reference"


def resolve_fidelity(fidelity: str, error_budget: float | None = None) -> str:
    """The preset a ``fidelity`` argument names: one of :data:`FIDELITY_PRESETS`, or
    ``"auto"``, the cheapest whose measured drift is within ``error_budget`` mm
    (:func:`choose_fidelity`).

    Raises:
        ValueError: an unknown name, ``"auto"`` without a budget, or a budget with
            another name.
    """
    if fidelity == "auto":
        if error_budget is None:
            raise ValueError("fidelity='auto' needs error_budget (mm of drift)")
        return choose_fidelity(error_budget)
    if error_budget is not None:
        raise ValueError("error_budget is only used with fidelity='auto'")
    if fidelity not in FIDELITY_PRESETS:
        raise ValueError(f"fidelity must be one of {[*FIDELITY_PRESETS, 'auto']}, got {fidelity!r}")
    return fidelity


def at_fidelity(
    scene: SceneConfig, fidelity: str = "default", error_budget: float | None = None
) -> SceneConfig:
    """``scene`` with the preset ``fidelity`` names (:func:`resolve_fidelity`) merged
    over it; ``scene`` itself at the default.

    Raises:
        ValueError: as :func:`resolve_fidelity`.
    """
    name = resolve_fidelity(fidelity, error_budget)
    preset = FIDELITY_PRESETS[name]
    scene = scene.replace(**preset) if preset else scene
    return refined_contour(scene) if name == "reference" else scene


def refined_contour(scene: SceneConfig, factor: float = REFERENCE_REFINEMENT) -> SceneConfig:
    """``scene`` with its contour sampled ``factor`` times as finely and each
    particle ``factor`` times lighter (its mass, its share of the lightest object and
    its press on the table: the same ``particle_scale``), so that the grip is as stiff
    per metre of contour; its outline smoothed by at least :data:`OUTLINE_SMOOTHING`
    pairs of shrink-free passes, without which a finer contour follows the pixels'
    staircase. The ``reference`` preset's refinement in space (:data:`FIDELITY_PRESETS`)."""
    contacts, proxy = scene.contacts, scene.proxy
    return scene.replace(
        contacts={
            "spacing": contacts.contour_spacing(proxy.particle_radius) / factor,
            "outline_smoothing": max(contacts.outline_smoothing, OUTLINE_SMOOTHING),
        },
        proxy={
            "particle_mass": proxy.particle_mass / factor,
            "mass_ratio": proxy.mass_ratio / factor,
            "down_force": proxy.down_force / factor,
        },
    )


def to_dict(config: Any) -> Any:
    """Plain dicts, lists and scalars of a configuration (for run folders and JSON)."""
    if dataclasses.is_dataclass(config) and not isinstance(config, type):
        return {f.name: to_dict(getattr(config, f.name)) for f in dataclasses.fields(config)}
    if isinstance(config, tuple | list):
        return [to_dict(v) for v in config]
    return config


def read_config_file(path: str | Path) -> dict[str, Any]:
    """The tables of a ``.toml`` or ``.json`` configuration file.

    Raises:
        FileNotFoundError: no such file.
        ConfigError: the file cannot be parsed (naming the file).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"configuration file not found: {path}")
    text = path.read_text()
    try:
        data: dict[str, Any] = json.loads(text) if path.suffix == ".json" else tomllib.loads(text)
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as err:
        raise ConfigError(f"{path}: cannot parse: {err}") from err
    return data


def read_config(config: str | Path | Mapping[str, Any] | None) -> tuple[dict[str, Any], str]:
    """The tables of a configuration file, a dict or the built-in default (none),
    and the name errors give it: the path, ``<dict>`` or ``<default>``.

    Raises:
        FileNotFoundError: no such file.
        ConfigError: the file cannot be parsed (naming the file).
    """
    if config is None:
        return {}, "<default>"
    if isinstance(config, Mapping):
        return dict(config), "<dict>"
    return read_config_file(config), str(config)


def build_section(
    cls: type[T], data: Mapping[str, Any] | None, prefix: str, source: str, defaults: T
) -> T:
    """A configuration dataclass from a table merged over defaults, validated.

    Args:
        cls: the dataclass.
        data: the table's keys (may be None or empty).
        prefix: the table's name in error messages (e.g. ``task``).
        source: the file (or ``<dict>``) in error messages.
        defaults: the instance whose values fill missing keys.
    """
    merged = _merge(to_dict(defaults), dict(data or {}))
    result: T = _build(cls, merged, prefix, source)
    return result


def scene_from(data: Mapping[str, Any], source: str) -> SceneConfig:
    """A :class:`SceneConfig` from the scene tables of a file, errors naming it."""
    result: SceneConfig = _build(SceneConfig, data, "", source)
    return result


def load_config(
    config: str | Path | Mapping[str, Any] | SceneConfig | None = None, **overrides: Any
) -> SceneConfig:
    """Build a :class:`SceneConfig` from a file, a dict or the built-in default.

    Args:
        config: path to a ``.toml`` or ``.json`` file, a mapping with the same keys,
            a ready ``SceneConfig``, or ``None`` for the default scene.
        **overrides: sections merged over the configuration, e.g.
            ``proxy={"method": "rigid"}`` or ``objects=[...]``.

    Raises:
        ConfigError: a key is unknown or a value is not what its key expects; the
            message names the key and the file.
        FileNotFoundError: the path does not exist.
    """
    if isinstance(config, SceneConfig):
        data, source = to_dict(config), "<SceneConfig>"
    else:
        data, source = read_config(config)
    if overrides:
        data = _merge(data, overrides)
    return _build(SceneConfig, data, "", source)


# -- validation ----------------------------------------------------------------------


def _positive(key: str, values: tuple[float, ...] | tuple[int, ...]) -> None:
    for v in values:
        if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
            raise ConfigError(f"{key} must be finite and > 0, got {list(values)}")


def _merge(base: Mapping[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    merged = dict(base)
    for key, value in extra.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = _merge(merged[key], value)
        else:
            merged[key] = value
    return merged


@functools.cache
def _fields_of(cls: type) -> tuple[dict[str, Any], dict[str, dataclasses.Field[Any]]]:
    """A configuration class's type hints and fields (evaluating the string
    annotations costs more than the rest of a build: every episode builds a scene)."""
    return typing.get_type_hints(cls), {f.name: f for f in dataclasses.fields(cls)}


def _build(cls: type, data: Any, prefix: str, source: str) -> Any:
    if not isinstance(data, Mapping):
        raise ConfigError(f"{source}: '{prefix or 'scene'}' must be a table, got {data!r}")
    hints, fields = _fields_of(cls)
    unknown = sorted(set(data) - set(fields))
    if unknown:
        where = f"'{prefix}.{unknown[0]}'" if prefix else f"'{unknown[0]}'"
        raise ConfigError(f"{source}: unknown key {where}; expected one of {sorted(fields)}")
    kwargs = {}
    for name, value in data.items():
        key = f"{prefix}.{name}" if prefix else name
        kwargs[name] = _convert(hints[name], value, key, source)
    try:
        return cls(**kwargs)
    except (ConfigError, ValueError) as err:
        raise ConfigError(f"{source}: {err}") from None
    except TypeError as err:  # a required key is missing
        raise ConfigError(f"{source}: '{prefix or 'scene'}': {err}") from None


def _convert(hint: Any, value: Any, key: str, source: str) -> Any:
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return _build(hint, value, key, source)
    if origin is Literal:
        if value not in args:
            raise ConfigError(f"{source}: '{key}' must be one of {list(args)}, got {value!r}")
        return value
    if origin is tuple:
        if not isinstance(value, list | tuple):
            raise ConfigError(f"{source}: '{key}' must be a list, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(args[0], v, f"{key}[{i}]", source) for i, v in enumerate(value))
        if len(value) != len(args):
            raise ConfigError(f"{source}: '{key}' must have {len(args)} values, got {list(value)}")
        return tuple(
            _convert(a, v, f"{key}[{i}]", source)
            for i, (a, v) in enumerate(zip(args, value, strict=True))
        )
    if origin in (typing.Union, types.UnionType):
        for arg in args:
            try:
                return _convert(arg, value, key, source)
            except ConfigError:
                continue
        raise ConfigError(f"{source}: '{key}' has an unexpected value {value!r}")
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{source}: '{key}' must be true or false, got {value!r}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{source}: '{key}' must be an integer, got {value!r}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(f"{source}: '{key}' must be a number, got {value!r}")
        if not math.isfinite(value):
            raise ConfigError(f"{source}: '{key}' must be finite, got {value!r}")
        return float(value)
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(f"{source}: '{key}' must be a string, got {value!r}")
        return value
    return value
