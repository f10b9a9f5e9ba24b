"""Simulation: one camera frame = the pipeline's stages, in order.

``mask → contacts (sensing) → proxy targets (matching) → particle control and
Bullet steps (physics) → object states``. Use :func:`graspenv.make_simulation` to
build one from a scene file, a dict or the built-in default, then feed it masks from
a synthetic hand or a real table.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.config import SceneConfig, at_fidelity, load_config
from graspenv.contacts.extract import validate_mask
from graspenv.contacts.tracking import ContactFrame, ContactTracker
from graspenv.physics.world import ContactReport, ObjectStateChange, PhysicsWorld
from graspenv.proxies import PersistentProxies, RigidProxies, make_proxies
from graspenv.proxies.base import ProxyCommand
from graspenv.resources import Closeable
from graspenv.surface.geometry import Surface

__all__ = ["FrameReport", "Simulation", "make_simulation"]

STAGES = ("sensing", "matching", "control", "physics")


@dataclass(frozen=True)
class FrameReport:
    """What one camera frame did.

    Attributes:
        index: frame number since the last reset, from 0.
        contacts: the tracked contacts of this frame.
        command: the proxy targets sent to the physics.
        n_particles: particle bodies in the scene (bottom and stacked).
        timings: wall seconds per stage: ``sensing`` (mask to tracked contours),
            ``matching`` (proxy bookkeeping), ``control`` (the control law and the
            per-particle calls around Bullet) and ``physics`` (Bullet's own steps).
    """

    index: int
    contacts: ContactFrame
    command: ProxyCommand
    n_particles: int
    timings: dict[str, float]

    @property
    def n_contacts(self) -> int:
        return len(self.contacts.contacts)

    @property
    def n_new(self) -> int:
        return len(self.contacts.new)

    @property
    def n_removed(self) -> int:
        return len(self.contacts.removed)

    @property
    def total_time(self) -> float:
        return float(sum(self.timings.values()))


class Simulation(Closeable):
    """A touch table, its tracked contacts, their proxies and a PyBullet scene.

    Args:
        config: the scene; see :func:`graspenv.config.load_config`.

    Attributes:
        config: the scene configuration in force.
        surface: the table's geometry and world ↔ pixel transforms.
    """

    #: Default camera of :meth:`render_view`: yaw and pitch in degrees, and the
    #: distance as a multiple of the table's longer side (all of it in view at 50°).
    VIEW_YAW_DEG = 0.0
    VIEW_PITCH_DEG = -50.0
    VIEW_DISTANCE_PER_SIZE = 1.2

    def __init__(self, config: SceneConfig) -> None:
        self.config = config
        self.surface = Surface.from_config(config.surface)
        self._tracker = ContactTracker(self.surface, config.contact_settings)
        self._world = PhysicsWorld(config)
        self._proxies = make_proxies(self._world, config, self.surface)
        self._index = 0
        self._contacts: ContactFrame | None = None

    # -- the pipeline ------------------------------------------------------------------

    def step(self, mask: NDArray[np.generic]) -> FrameReport:
        """Advance one camera frame.

        Args:
            mask: (H, W) bool or uint8 contact image at the surface resolution,
                non-zero = touched, row 0 at the top (the camera's view).

        Returns:
            The frame's contacts, proxy command, particle count and stage timings.

        Raises:
            ValueError: the mask has the wrong shape, dtype or dimensionality.
        """
        clock = time.perf_counter
        t0 = clock()
        image = validate_mask(mask, self.surface.shape)
        contacts = self._tracker.update(image)
        t1 = clock()
        self._contacts = contacts
        command = self._proxies.update(contacts, image)
        t2 = clock()
        if command.bodies.size:
            self._world.step_bodies(command.bodies, command.body_targets)
        else:
            self._world.step_frame(command.particles, command.targets, command.spin)
        bullet = self._world.bullet_seconds
        t3 = clock()
        report = FrameReport(
            index=self._index,
            contacts=contacts,
            command=command,
            n_particles=self._world.pool.num_active + len(self._world.rigid_proxies),
            timings={
                "sensing": t1 - t0,
                "matching": t2 - t1,
                "control": (t3 - t2) - bullet,
                "physics": bullet,
            },
        )
        self._index += 1
        return report

    # -- state -------------------------------------------------------------------------

    @property
    def world(self) -> PhysicsWorld:
        """The physics world (for measurements; drive it through :meth:`step`)."""
        return self._world

    @property
    def object_names(self) -> tuple[str, ...]:
        return self._world.object_names

    @property
    def frame_index(self) -> int:
        """Frames stepped since the last reset."""
        return self._index

    def object_pose(self, name: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Position (3,) in metres and quaternion (x, y, z, w) of an object, world frame."""
        return self._world.object_pose(name)

    def object_velocity(self, name: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Linear (3,) m/s and angular (3,) rad/s velocity of an object, world frame."""
        return self._world.object_velocity(name)

    def particle_positions(self) -> NDArray[np.float64]:
        """Centres of the active particles, metres, world frame, shape (N, 3).

        Rows in increasing particle id (``world.pool.active_ids``).
        """
        return self._world.pool.positions(self._world.pool.active_ids)

    def particle_velocities(self) -> NDArray[np.float64]:
        """Linear velocities of the active particles, m/s, world frame, shape (N, 3).

        Rows in the order of :meth:`particle_positions`.
        """
        return self._world.pool.velocities(self._world.pool.active_ids)

    def contact_report(self, name: str) -> ContactReport:
        """Contacts on an object from the last physics sub-step (points, normals, forces).

        See :meth:`graspenv.physics.world.PhysicsWorld.contact_report`.
        """
        return self._world.contact_report(name)

    def particles_by_contact(self) -> dict[int, NDArray[np.int64]]:
        """Contact id → the particle ids that stand for it after the last frame.

        With the ``persistent`` method, every particle of every stack of each tracked
        contact (:meth:`PersistentProxies.particle_contacts`); with ``rigid``, each
        current contact maps to an empty array (its proxy is one body, not
        particles); with ``instant``, particles are not tied to contacts and the
        dict is empty. Empty before the first frame.

        Returns:
            Contact id → particle ids, int64, shape (n,).
        """
        if isinstance(self._proxies, PersistentProxies):
            return self._proxies.particle_contacts()
        if isinstance(self._proxies, RigidProxies) and self._contacts is not None:
            return {c.id: np.zeros(0, np.int64) for c in self._contacts.contacts}
        return {}

    # -- disturbances and initial states -----------------------------------------------

    def apply_force(self, name: str, force: ArrayLike, height: float | None = None) -> None:
        """Push an object with ``force`` (N, world frame, (3,)) for the next
        :meth:`step` only (every physics sub-step of that camera frame), at its centre
        of mass or along a line through ``height`` metres above the table.

        See :meth:`graspenv.physics.world.PhysicsWorld.apply_force`.
        """
        self._world.apply_force(name, force, height)

    def set_object_state(self, name: str, **change: Unpack[ObjectStateChange]) -> None:
        """Move an object and/or set its velocity now; what is not given keeps its
        current value.

        Position in metres ((3,), or (x, y) to rest it on the table), ``yaw`` in
        radians or any ``orientation`` (quaternion x, y, z, w), velocities in m/s and
        rad/s, all world frame; ``rolling=True`` spins a sphere to roll at its linear
        velocity. See :meth:`graspenv.physics.world.PhysicsWorld.set_object_state`.
        """
        self._world.set_object_state(name, **change)

    # -- pictures ----------------------------------------------------------------------

    def render_view(
        self,
        width: int = 320,
        height: int = 240,
        target: ArrayLike | None = None,
        distance: float | None = None,
        yaw_deg: float | None = None,
        pitch_deg: float | None = None,
        fov: float = 50.0,
    ) -> NDArray[np.uint8]:
        """A 3-D view of the table, objects and fingers' particles (RGB, headless).

        By default the camera looks at the table centre from the viewer's side of
        the table (looking along +y), 50° down, from 1.2 times the table's longer
        side away, so the whole table is in view.

        Args:
            width: image width, pixels.
            height: image height, pixels.
            target: point looked at, metres, world frame, (3,); table centre if None.
            distance: camera distance from the target, metres.
            yaw_deg: camera yaw, degrees (0: looking along +y, x to the right).
            pitch_deg: camera pitch, degrees (negative: looking down).
            fov: vertical field of view, degrees.

        Returns:
            RGB image, shape (height, width, 3), uint8.
        """
        return self._world.render(
            width,
            height,
            (0.0, 0.0, 0.0) if target is None else target,
            self.VIEW_DISTANCE_PER_SIZE * max(self.surface.size) if distance is None else distance,
            self.VIEW_YAW_DEG if yaw_deg is None else yaw_deg,
            self.VIEW_PITCH_DEG if pitch_deg is None else pitch_deg,
            fov,
        )

    # -- life cycle --------------------------------------------------------------------

    def reset(self, scene: SceneConfig | None = None) -> None:
        """Start again: objects at their start, no contacts, frame index 0.

        Args:
            scene: the scene for the new episode (objects may differ in number,
                shape, size, mass and friction; any section may change), or ``None``
                to put the current one back. With a scene, the physics world is
                rebuilt (:meth:`PhysicsWorld.rebuild`: 1–3 ms with the default
                pool batch), and so are the contact tracker and the proxies; the
                results are then bit-identical to a new ``Simulation(scene)`` fed the
                same masks, whatever ran before, also when the scene equals
                :attr:`config`. :attr:`surface` is replaced only when the surface
                section differs, so a reference to it stays valid otherwise. Without
                a scene this is the cheap :meth:`PhysicsWorld.reset` (0.05 ms), which
                is bit-identical to a fresh start in the common cases but not
                guaranteed to be (see there).
        """
        self._index = 0
        self._contacts = None
        if scene is None:
            self._world.reset()
            self._tracker.reset()
            self._proxies.reset()
            return
        if scene.surface != self.config.surface:
            self.surface = Surface.from_config(scene.surface)
        self._world.rebuild(scene)
        self._tracker = ContactTracker(self.surface, scene.contact_settings)
        self._proxies = make_proxies(self._world, scene, self.surface)
        self.config = scene

    def close(self) -> None:
        """Free the physics client; safe to call twice."""
        self._world.close()


def make_simulation(
    config: str | Path | dict[str, Any] | SceneConfig | None = None,
    *,
    fidelity: str = "default",
    error_budget: float | None = None,
    **overrides: Any,
) -> Simulation:
    """Build a :class:`Simulation` for users who bring their own masks.

    Args:
        config: a scene file in ``envs_configs/`` (TOML or JSON), a dict with the same
            keys, a :class:`SceneConfig`, or ``None`` for the built-in default scene.
        fidelity: the environments' presets (:data:`graspenv.config.FIDELITY_PRESETS`:
            ``fast``, ``default``, ``reference``), merged over ``config``; or
            ``"auto"``: the cheapest preset whose measured drift is within
            ``error_budget`` millimetres.
        error_budget: millimetres of drift against the reference, for ``"auto"``.
        **overrides: sections merged over both, e.g. ``proxy={"method": "rigid"}``.

    Raises:
        ConfigError: unknown keys or bad values, naming the key and the file.
        ValueError: an unknown fidelity, or ``"auto"`` without a budget.
    """
    scene = at_fidelity(load_config(config), fidelity, error_budget)
    return Simulation(scene.replace(**overrides) if overrides else scene)
