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
from types import TracebackType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from graspenv.config import SceneConfig, load_config
from graspenv.contacts.extract import validate_mask
from graspenv.contacts.tracking import ContactFrame, ContactTracker
from graspenv.physics.world import PhysicsWorld
from graspenv.proxies import make_proxies
from graspenv.proxies.base import ProxyCommand
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


class Simulation:
    """A touch table, its tracked contacts, their proxies and a PyBullet scene.

    Args:
        config: the scene; see :func:`graspenv.config.load_config`.

    Attributes:
        config: the scene configuration in force.
        surface: the table's geometry and world ↔ pixel transforms.
    """

    def __init__(self, config: SceneConfig) -> None:
        self.config = config
        self.surface = Surface.from_config(config.surface)
        self._tracker = ContactTracker(self.surface, config.contacts)
        self._world = PhysicsWorld(config)
        self._proxies = make_proxies(self._world, config, self.surface)
        self._index = 0

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
        """Centres of the active particles, metres, world frame, shape (N, 3)."""
        return self._world.pool.positions(self._world.pool.active_ids)

    # -- life cycle --------------------------------------------------------------------

    def reset(self) -> None:
        """Back to the initial scene: objects at their start, no contacts."""
        self._world.reset()
        self._tracker.reset()
        self._proxies.reset()
        self._index = 0

    def close(self) -> None:
        """Free the physics client; safe to call twice."""
        self._world.close()

    def __enter__(self) -> Simulation:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


def make_simulation(
    config: str | Path | dict[str, Any] | SceneConfig | None = None, **overrides: Any
) -> Simulation:
    """Build a :class:`Simulation` for users who bring their own masks.

    Args:
        config: a scene file in ``envs_configs/`` (TOML or JSON), a dict with the same
            keys, a :class:`SceneConfig`, or ``None`` for the built-in default scene.
        **overrides: sections merged over it, e.g. ``proxy={"method": "rigid"}``.

    Raises:
        ConfigError: unknown keys or bad values, naming the key and the file.
    """
    return Simulation(load_config(config, **overrides))
