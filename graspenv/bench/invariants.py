"""Invariants every simulated frame must keep, whatever the hand does.

The stability suite (``tests/stability``) and the speed-against-error benchmark drive
hard cases through the whole pipeline (mask → contacts → proxies → Bullet) and
check after every frame that the state is still physical. :class:`InvariantChecker`
reads the state after each :meth:`~graspenv.simulation.Simulation.step`, keeps the
worst value of every invariant (:class:`Worst`) and the frames that broke one
(:class:`Violation`). The invariants and their bounds:

1. **Finite.** Every object position, quaternion, linear and angular velocity and
   every active particle's position and velocity is finite (no NaN or inf).
2. **Speed.** No object moves faster than a physical bound derived from the scene
   (:func:`speed_bound`). With restitution 0, a body pushed by the fingers never
   overtakes the fastest finger point; what the pipeline may add on top:

   - the *squeeze rebound*: a particle held off its contour point by a depth d
     commands v* = d / Δt towards it (Δt: ``physics.control_time``, or the sub-step
     if longer); the deepest a particle is held before the default penetration
     limit lifts it is the default ``proxy.penetration_margin``
     (:data:`REBOUND_DEPTH`, 7 mm), so the rebound is ``REBOUND_DEPTH / Δt``
     (1.68 m/s at the default Δt of 1/240 s);
   - *gravity*: an object that has dropped by Δz below its start may have gained
     sqrt(2 g Δz) by falling (off the table edge, 0.75 m to the floor: 3.8 m/s).

   The bound is ``finger_speed + REBOUND_DEPTH / Δt + sqrt(2 g max(0, z0 − z))``,
   applied to the centre's speed |v| and to the surface speed of the spin,
   |ω| · r_in (r_in: the smallest distance from the centre to the surface: the
   smallest half extent of a box, a sphere's radius, the smaller of a cylinder's
   radius and half height). No guard setting enters it (force, speed and
   penetration limits, CCD; the rebound uses the *default* margin, not the
   scene's), so loosening a guard cannot loosen the bound.
3. **Particles above the table.** No active particle whose centre lies over the
   table top is lower than its radius minus ``Tolerances.below_table`` (1 mm, half
   the default particle radius). Continuous collision detection lets a fast
   particle into the table by up to ``physics.allowed_ccd_penetration`` (0.5 mm)
   before it acts, and a particle dropping off an object's top lands that fast;
   one that tunnels ends a whole diameter or more below (11 mm with CCD off).
   Particles that slid past the table's edge may fall and are not judged.
4. **Particles outside objects.** No active particle overlaps an object by more than
   ``Tolerances.inside_object`` (1 mm, half the default particle radius): the
   overlap is the particle radius minus the exact signed distance from its centre
   to the object's surface as Bullet has it (box, sphere or upright cylinder in
   the object's current pose, a box's and a cylinder's edges rounded by Bullet's
   1 mm collision margin, :data:`~graspenv.physics.EDGE_RADIUS`: a particle over an
   edge of the sharp box is up to 0.73 mm nearer than over Bullet's). A firm
   squeeze presses particles 0.3–0.6 mm into a 0.2 kg box;
   past half its radius a particle is on its way through the face (with its
   centre inside, the object can no longer push it back out).
5. **No tunnelling through the table.** An object's centre stays at least its
   lowest resting height (r_in above) minus ``Tolerances.sink`` (2 mm) above the
   table top while the centre lies over the table at least that resting height in
   from the edge (nearer the edge an object may tip over it and fall, which is
   allowed). Particles pressing on an object's top push it into the table: up to
   1.55 mm for a 20 g can under a flat hand.
6. **Determinism.** The same case run twice gives bit-identical object poses in
   every frame: compare :attr:`InvariantChecker.poses` with :func:`first_difference`.

Example:
    >>> with make_simulation(scene) as sim:  # doctest: +SKIP
    ...     checker = InvariantChecker(sim, finger_speed=hand_speed(hands))
    ...     for mask in masks:
    ...         sim.step(mask)
    ...         checker.check()
    ...     checker.assert_ok()
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from graspenv.config import ObjectConfig, ProxyConfig, SceneConfig
from graspenv.geometry import inscribed_radius
from graspenv.physics import EDGE_RADIUS
from graspenv.simulation import Simulation
from graspenv.surface.hand import Hand

__all__ = [
    "INVARIANTS",
    "REBOUND_DEPTH",
    "InvariantChecker",
    "InvariantsBroken",
    "Tolerances",
    "Violation",
    "Worst",
    "first_difference",
    "hand_speed",
    "inscribed_radius",
    "object_penetration",
    "speed_bound",
]

#: Names of the invariants checked every frame, as used in :class:`Violation`.
INVARIANTS = ("finite", "speed", "spin", "below_table", "inside_object", "tunnelling")

#: The deepest squeeze the default penetration limit lets a particle be held at,
#: metres: the default ``proxy.penetration_margin``. It sets the squeeze rebound.
REBOUND_DEPTH = ProxyConfig().penetration_margin


@dataclass(frozen=True)
class Tolerances:
    """How far past the ideal each invariant may go, metres.

    Attributes:
        below_table: how far a particle centre over the table may sit below its
            radius (invariant 3).
        inside_object: how far a particle may overlap an object (invariant 4).
        sink: how far an object's centre may sit below its lowest resting height
            (invariant 5).
    """

    below_table: float = 1e-3
    inside_object: float = 1e-3
    sink: float = 2e-3


@dataclass(frozen=True)
class Violation:
    """One frame that broke an invariant.

    Attributes:
        frame: frame index (checks since the checker was made), from 0.
        invariant: one of :data:`INVARIANTS`.
        subject: the object's name, or ``particle <id>``.
        value: the measured value (m/s for speeds, metres otherwise; NaN for
            ``finite``).
        bound: the bound it broke.
    """

    frame: int
    invariant: str
    subject: str
    value: float
    bound: float

    def __str__(self) -> str:
        return (
            f"frame {self.frame}: {self.invariant} broken by {self.subject}: "
            f"{self.value:.6g} against {self.bound:.6g}"
        )


@dataclass
class Worst:
    """The worst value of each invariant over the frames checked.

    Attributes:
        speed_ratio: largest object centre speed over its bound.
        spin_ratio: largest |ω| · r_in over the same bound.
        max_speed: largest object centre speed, m/s.
        speed_bound: the bound in force at the frame of ``speed_ratio``, m/s.
        lowest_particle: lowest particle centre over the table minus its radius,
            metres (negative: below the table top); +inf with no particle.
        deepest_in_object: largest particle overlap with an object, metres
            (negative: no particle touches one).
        height_margin: smallest object centre height above its lowest resting
            height, metres, where that is checked (negative: sunk); +inf if never.
        non_finite: frames with a non-finite state.
    """

    speed_ratio: float = 0.0
    spin_ratio: float = 0.0
    max_speed: float = 0.0
    speed_bound: float = math.nan
    lowest_particle: float = math.inf
    deepest_in_object: float = -math.inf
    height_margin: float = math.inf
    non_finite: int = 0

    def as_dict(self) -> dict[str, float]:
        """The worst values in millimetres and m/s, for tables and messages."""
        return {
            "speed_ratio": self.speed_ratio,
            "spin_ratio": self.spin_ratio,
            "max_speed_m_s": self.max_speed,
            "speed_bound_m_s": self.speed_bound,
            "lowest_particle_mm": 1000 * self.lowest_particle,
            "deepest_in_object_mm": 1000 * self.deepest_in_object,
            "height_margin_mm": 1000 * self.height_margin,
            "non_finite_frames": float(self.non_finite),
        }


def hand_speed(hands: Iterable[Hand]) -> float:
    """The fastest any point of a touching shape moves, over a sequence of hands.

    ``|v| + |ω| · r`` per shape (r its bounding radius), which no point of its rigid
    motion exceeds (a fingertip's growth with its press is not counted: it is slow).

    Args:
        hands: the hand in each frame (e.g. from :meth:`Script.frames`).

    Returns:
        m/s; 0 for no touching shape.
    """
    fastest = 0.0
    for hand in hands:
        for _, shape, touching in hand:
            if touching:
                speed = float(np.hypot(*shape.linear_velocity))
                speed += abs(shape.angular_velocity) * shape.bounding_radius
                fastest = max(fastest, speed)
    return fastest


def speed_bound(scene: SceneConfig, finger_speed: float) -> float:
    """The object speed bound before any fall: finger speed plus the squeeze rebound.

    Args:
        scene: gives the control law's Δt (``physics.control_time``, or the
            sub-step if longer; the scene's own, ``SceneConfig.sub_steps``).
        finger_speed: the fastest finger point of the case, m/s.

    Returns:
        ``finger_speed + REBOUND_DEPTH / Δt``, m/s; add ``sqrt(2 g Δz)`` for an
        object that has dropped by Δz.
    """
    substep = 1.0 / (scene.surface.fps * scene.sub_steps)
    control_dt = max(scene.physics.control_time, substep)
    return finger_speed + REBOUND_DEPTH / control_dt


def _rotation(quaternion: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotation matrix (object to world) of a quaternion (x, y, z, w), (3, 3)."""
    x, y, z, w = quaternion / np.linalg.norm(quaternion)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _signed_distance(
    config: ObjectConfig, local: NDArray[np.float64], edge_radius: float = 0.0
) -> NDArray[np.float64]:
    """Exact signed distance (metres, negative inside) of points in the object's frame;
    a box's and a cylinder's edges rounded by ``edge_radius`` (the shape shrunk by it,
    then grown by it again: the faces stay where they are)."""
    if config.shape == "sphere":
        result: NDArray[np.float64] = np.linalg.norm(local, axis=1) - config.size[0]
        return result
    if config.shape == "box":
        q = np.abs(local) - (0.5 * np.asarray(config.size) - edge_radius)
    else:
        radius, height = config.size
        q = np.column_stack(
            [
                np.hypot(local[:, 0], local[:, 1]) - (radius - edge_radius),
                np.abs(local[:, 2]) - (0.5 * height - edge_radius),
            ]
        )
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = np.minimum(q.max(axis=1), 0.0)
    result = outside + inside - edge_radius
    return result


def object_penetration(
    config: ObjectConfig,
    position: NDArray[np.float64],
    quaternion: NDArray[np.float64],
    centres: NDArray[np.float64],
    radius: float,
    edge_radius: float = 0.0,
) -> NDArray[np.float64]:
    """How far each sphere overlaps an object.

    Args:
        config: the object's shape and size.
        position: its centre, metres, world frame, (3,).
        quaternion: its orientation (x, y, z, w), (4,).
        centres: sphere centres, metres, world frame, (N, 3).
        radius: sphere radius, metres.
        edge_radius: how far a box's or cylinder's edges are rounded, metres (the
            checker passes Bullet's, :data:`~graspenv.physics.EDGE_RADIUS`).

    Returns:
        radius minus the signed distance from each centre to the object's surface,
        metres, (N,): positive where the sphere overlaps the object.
    """
    local = (np.asarray(centres, dtype=float) - position) @ _rotation(quaternion)
    return radius - _signed_distance(config, local, edge_radius)


def first_difference(a: NDArray[np.float64], b: NDArray[np.float64]) -> str | None:
    """Where two runs' pose records (:attr:`InvariantChecker.poses`) first differ.

    Args:
        a: one run's record, float64, shape (T, ...).
        b: the other's.

    Returns:
        None when they are bit-identical (same shape, every bit of every number
        equal: NaN matches only the same NaN, 0.0 does not match -0.0), otherwise a
        description of the first frame that differs and by how much.
    """
    if a.shape != b.shape:
        return f"the runs have different shapes {a.shape} and {b.shape}"
    bits_a = np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)
    bits_b = np.ascontiguousarray(b, dtype=np.float64).view(np.uint64)
    differs = np.any(bits_a != bits_b, axis=tuple(range(1, a.ndim)))
    if not np.any(differs):
        return None
    frame = int(np.argmax(differs))
    gap = float(np.nanmax(np.abs(a[frame] - b[frame]), initial=0.0))
    return f"poses first differ in frame {frame} (by up to {gap:.3g})"


@dataclass(frozen=True)
class _Object:
    """What the checker keeps about an object: its shape and where it started."""

    config: ObjectConfig
    r_in: float
    start_z: float


@dataclass(frozen=True)
class _State:
    """An object's state after a frame (metres, quaternion, m/s, rad/s)."""

    obj: _Object
    position: NDArray[np.float64]
    quaternion: NDArray[np.float64]
    linear: NDArray[np.float64]
    angular: NDArray[np.float64]

    @property
    def finite(self) -> bool:
        arrays = (self.position, self.quaternion, self.linear, self.angular)
        return all(bool(np.all(np.isfinite(a))) for a in arrays)


class InvariantsBroken(AssertionError):
    """A run broke at least one invariant (raised by :meth:`InvariantChecker.assert_ok`)."""


class InvariantChecker:
    """Checks the invariants of the module docstring after every frame of a run.

    Call :meth:`check` right after each :meth:`Simulation.step`.

    Args:
        sim: the simulation, before the first frame of the case (objects where the
            case starts them).
        finger_speed: the fastest finger point of the case, m/s (:func:`hand_speed`).
        tolerances: the allowances of invariants 3–5.

    Attributes:
        worst: the worst value of every invariant so far.
        violations: every (frame, invariant, subject) that broke its bound, in order.
    """

    def __init__(
        self, sim: Simulation, finger_speed: float, tolerances: Tolerances | None = None
    ) -> None:
        self.sim = sim
        self.tolerances = Tolerances() if tolerances is None else tolerances
        self.worst = Worst()
        self.violations: list[Violation] = []
        scene = sim.config
        self._base_bound = speed_bound(scene, finger_speed)
        self._gravity = scene.physics.gravity
        self._half_table = 0.5 * np.asarray(scene.surface.size, dtype=float)
        self._radius = scene.proxy.particle_radius
        self._objects = [
            _Object(config, inscribed_radius(config), float(sim.object_pose(config.name)[0][2]))
            for config in scene.objects
        ]
        self._poses: list[NDArray[np.float64]] = []

    @property
    def poses(self) -> NDArray[np.float64]:
        """Object (x, y, z, qx, qy, qz, qw) per frame checked, (T, n_objects, 7)."""
        return np.array(self._poses, dtype=float).reshape(len(self._poses), len(self._objects), 7)

    @property
    def frames(self) -> int:
        """Frames checked so far."""
        return len(self._poses)

    def check(self) -> None:
        """Read the state after a frame and record the worst values and violations."""
        frame = len(self._poses)
        states = [self._state(obj) for obj in self._objects]
        self._poses.append(
            np.array([np.concatenate([s.position, s.quaternion]) for s in states]).reshape(-1, 7)
        )
        ids = self.sim.world.pool.active_ids
        positions = self.sim.particle_positions().reshape(-1, 3)
        velocities = self.sim.particle_velocities().reshape(-1, 3)
        if not self._check_finite(frame, states, ids, positions, velocities):
            return  # nothing else can be judged on NaN
        for state in states:
            self._check_speed(frame, state)
            self._check_height(frame, state)
            if len(positions):
                self._check_overlap(frame, state, ids, positions)
        self._check_particles_above_table(frame, ids, positions)

    def broken(self) -> set[str]:
        """The invariants broken at least once."""
        return {v.invariant for v in self.violations}

    def summary(self) -> str:
        """The worst values and the first violation of each broken invariant."""
        figures = ", ".join(f"{k}={v:.4g}" for k, v in self.worst.as_dict().items())
        first: dict[str, Violation] = {}
        count: dict[str, int] = {}
        for violation in self.violations:
            first.setdefault(violation.invariant, violation)
            count[violation.invariant] = count.get(violation.invariant, 0) + 1
        lines = [f"{self.frames} frames; worst: {figures}"]
        lines += [f"  {v} ({count[k]} violations)" for k, v in first.items()]
        return "\n".join(lines)

    def assert_ok(self) -> None:
        """Raise :class:`InvariantsBroken`, with :meth:`summary`, if any invariant broke."""
        if self.violations:
            raise InvariantsBroken("invariants broken: " + self.summary())

    # -- the invariants ----------------------------------------------------------------

    def _state(self, obj: _Object) -> _State:
        position, quaternion = self.sim.object_pose(obj.config.name)
        linear, angular = self.sim.object_velocity(obj.config.name)
        return _State(obj, position, quaternion, linear, angular)

    def _violate(
        self, frame: int, invariant: str, subject: str, value: float, bound: float
    ) -> None:
        self.violations.append(Violation(frame, invariant, subject, value, bound))

    def _check_finite(
        self,
        frame: int,
        states: list[_State],
        ids: NDArray[np.int64],
        positions: NDArray[np.float64],
        velocities: NDArray[np.float64],
    ) -> bool:
        bad_objects = [s.obj.config.name for s in states if not s.finite]
        bad = ~(np.isfinite(positions).all(axis=1) & np.isfinite(velocities).all(axis=1))
        subjects = bad_objects + [f"particle {i}" for i in ids[bad].tolist()]
        for subject in subjects:
            self._violate(frame, "finite", subject, math.nan, math.nan)
        if subjects:
            self.worst.non_finite += 1
        return not subjects

    def _check_speed(self, frame: int, state: _State) -> None:
        worst, obj = self.worst, state.obj
        drop = max(0.0, obj.start_z - float(state.position[2]))
        bound = self._base_bound + math.sqrt(2.0 * self._gravity * drop)
        speed = float(np.linalg.norm(state.linear))
        spin = float(np.linalg.norm(state.angular)) * obj.r_in
        if speed / bound > worst.speed_ratio:
            worst.speed_ratio = speed / bound
            worst.speed_bound = bound
        worst.max_speed = max(worst.max_speed, speed)
        worst.spin_ratio = max(worst.spin_ratio, spin / bound)
        if speed > bound:
            self._violate(frame, "speed", obj.config.name, speed, bound)
        if spin > bound:
            self._violate(frame, "spin", obj.config.name, spin, bound)

    def _check_height(self, frame: int, state: _State) -> None:
        obj = state.obj
        # Nearer the edge than its resting height, an object may tip over it and fall.
        if np.any(np.abs(state.position[:2]) > self._half_table - obj.r_in):
            return
        margin = float(state.position[2]) - obj.r_in
        self.worst.height_margin = min(self.worst.height_margin, margin)
        if margin < -self.tolerances.sink:
            self._violate(frame, "tunnelling", obj.config.name, margin, -self.tolerances.sink)

    def _check_overlap(
        self,
        frame: int,
        state: _State,
        ids: NDArray[np.int64],
        positions: NDArray[np.float64],
    ) -> None:
        config = state.obj.config
        overlap = object_penetration(
            config, state.position, state.quaternion, positions, self._radius, EDGE_RADIUS
        )
        deepest = int(np.argmax(overlap))
        depth = float(overlap[deepest])
        self.worst.deepest_in_object = max(self.worst.deepest_in_object, depth)
        if depth > self.tolerances.inside_object:
            subject = f"particle {int(ids[deepest])} in {config.name}"
            self._violate(frame, "inside_object", subject, depth, self.tolerances.inside_object)

    def _check_particles_above_table(
        self, frame: int, ids: NDArray[np.int64], positions: NDArray[np.float64]
    ) -> None:
        # Particles that slid past the table's edge may fall; they are not judged.
        over_table = np.all(np.abs(positions[:, :2]) <= self._half_table, axis=1)
        if not np.any(over_table):
            return
        height = positions[over_table, 2] - self._radius
        lowest = int(np.argmin(height))
        self.worst.lowest_particle = min(self.worst.lowest_particle, float(height[lowest]))
        if height[lowest] < -self.tolerances.below_table:
            subject = f"particle {int(ids[over_table][lowest])}"
            bound = -self.tolerances.below_table
            self._violate(frame, "below_table", subject, float(height[lowest]), bound)
