"""A camera frame's physics sub-steps, and the pushes on objects they carry.

The world steps Bullet only through a :class:`FrameStepper`: for each sub-step it
drives the proxies (a callback), re-applies the pending pushes on objects (Bullet
clears external forces after every ``stepSimulation``), steps Bullet and lets the
caller observe the result. :meth:`FrameStepper.substeps_for` chooses how many
sub-steps a frame takes: ``physics.substeps``, or more, shorter ones when an
object's point or a particle would move more than ``physics.substep_travel`` a step
(up to ``physics.max_substeps``; :func:`~graspenv.physics.control.frame_substeps`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
import pybullet as pb
from numpy.typing import NDArray

from graspenv.config import PhysicsConfig
from graspenv.geometry import SHAPE_CODES
from graspenv.physics.bodies import SceneBodies
from graspenv.physics.control import frame_substeps
from graspenv.physics.pool import ParticlePool
from graspenv.physics.reports import ObjectStates

__all__ = ["FrameStepper"]


class FrameStepper:
    """Runs the sub-steps of each frame and keeps the pushes pending for the next.

    Args:
        client: the PyBullet client.
        bodies: the scene's bodies (pushes act on ``bodies.objects`` by index).
        pool: the particle pool, whose ``physics_steps`` counts every Bullet step.
        physics: the Bullet settings (sub-step counts and travel); its ``substeps``
            are the scene's own (:attr:`~graspenv.config.SceneConfig.sub_steps`).
        substep_dt: seconds per physics step at ``physics.substeps`` (Bullet's time
            step after a frame of that many; after one of more, that frame's).

    Attributes:
        bullet_seconds: wall seconds spent inside Bullet's ``stepSimulation`` by the
            last frame.
        last_substeps: physics steps the last frame took (``physics.substeps`` or
            more).
    """

    def __init__(
        self,
        client: int,
        bodies: SceneBodies,
        pool: ParticlePool,
        physics: PhysicsConfig,
        substep_dt: float,
    ) -> None:
        self._client = client
        self._bodies = bodies
        self._pool = pool
        self._physics = physics
        self._substeps = physics.substeps
        self._substep_dt = substep_dt
        # Bullet's time step now: the length of the last sub-step taken (run).
        self._bullet_dt = substep_dt
        # Force and torque on each object (by index) for every sub-step of the next
        # frame, N and N·m, world frame.
        self._pending_force: dict[int, NDArray[np.float64]] = {}
        self._pending_torque: dict[int, NDArray[np.float64]] = {}
        self.bullet_seconds = 0.0
        self.last_substeps = physics.substeps

    def push(self, index: int, force: NDArray[np.float64]) -> None:
        """Add a force at object ``index``'s centre of mass for the next frame, N."""
        pending = self._pending_force.get(index)
        self._pending_force[index] = force.copy() if pending is None else pending + force

    def twist(self, index: int, torque: NDArray[np.float64]) -> None:
        """Add a torque on object ``index`` for the next frame, N·m, world frame."""
        pending = self._pending_torque.get(index)
        self._pending_torque[index] = torque if pending is None else pending + torque

    def drop_pending(self) -> None:
        """Forget every pending push."""
        self._pending_force, self._pending_torque = {}, {}

    def substeps_for(
        self,
        frame_dt: float,
        states: Callable[[], ObjectStates],
        target_steps: NDArray[np.float64] | None = None,
        velocities: NDArray[np.float64] | None = None,
    ) -> int:
        """This frame's sub-steps (:func:`~graspenv.physics.control.frame_substeps`)
        from how far its particles go (each its target's step, metres, (n, 2), or
        its own speed, m/s, (n, 3), over the frame, whichever is more) and from the
        objects' speed and spin at the frame's start (``states()``, read only when
        the count can change): a box's or cylinder's fastest point (the spin at its
        bounding radius), a ball's lowest point (a ball rolling on the table needs
        no short steps: the point it rests on is still)."""
        physics = self._physics
        if physics.max_substeps <= self._substeps:
            return self._substeps  # a fixed count: nothing to measure
        travel = 0.0
        if target_steps is not None and velocities is not None:
            travel = math.sqrt(
                max(
                    float(np.max(np.sum(target_steps**2, axis=1))),
                    float(np.max(np.sum(velocities**2, axis=1))) * frame_dt**2,
                )
            )
        if self._bodies.objects:
            now = states()
            spin = now.angular
            radii = self._bodies.bounding_radii
            # A ball's lowest point moves at v + ω × (0, 0, −r).
            lowest = (
                now.linear
                + np.column_stack([-spin[:, 1], spin[:, 0], np.zeros(len(spin))]) * radii[:, None]
            )
            speed = np.where(
                self._bodies.shape_codes == SHAPE_CODES["sphere"],
                np.sqrt(np.sum(lowest**2, axis=1)),
                np.sqrt(np.sum(now.linear**2, axis=1)) + radii * np.sqrt(np.sum(spin**2, axis=1)),
            )
            travel = max(travel, float(np.max(speed)) * frame_dt)
        return frame_substeps(travel, physics)

    def run(
        self,
        frame_dt: float,
        substeps: int,
        drive: Callable[[int], None] | None = None,
        observe: Callable[[], None] | None = None,
    ) -> None:
        """The frame's ``substeps`` physics sub-steps of ``frame_dt / substeps``
        seconds: for each s = 1..S, drive the proxies, push the objects, step Bullet,
        then observe. Pending pushes are dropped afterwards; :attr:`bullet_seconds`
        gets the time in Bullet's step and :attr:`last_substeps` the count.

        Bullet's time step is left at this frame's sub-step. PyBullet reports a
        contact's forces as the impulses of the last step over the time step set when
        they are read, so setting the configured step back after a frame of more
        sub-steps understated every force read after it by the ratio of the steps
        (a slide of the random sample, five to seven sub-steps a frame: the default's
        grip on a 3.1 cm cylinder read 2.77 N instead of 4.57 N)."""
        client = self._client
        h = frame_dt / substeps
        self._set_step(h)
        clock = time.perf_counter
        step = pb.stepSimulation
        bullet = 0.0
        self.last_substeps = substeps
        for s in range(1, substeps + 1):
            if drive is not None:
                drive(s)
            self._apply_pending()
            tic = clock()
            step(client)
            bullet += clock() - tic
            self._pool.physics_steps += 1
            if observe is not None:
                observe()
        self.drop_pending()
        self.bullet_seconds = bullet

    def use_configured_step(self) -> None:
        """Set Bullet's time step to the configured sub-step, for a step taken
        outside :meth:`run` (placing the objects)."""
        self._set_step(self._substep_dt)

    def _set_step(self, h: float) -> None:
        if h != self._bullet_dt:
            pb.setTimeStep(h, physicsClientId=self._client)
            self._bullet_dt = h

    def _apply_pending(self) -> None:
        """Apply this frame's pushes for the coming sub-step (Bullet forgets them)."""
        client = self._client
        objects = self._bodies.objects
        for index in sorted(self._pending_force):
            body = objects[index]
            # WORLD_FRAME takes the point in world coordinates: the centre of mass, so
            # the push adds no torque (checked on a tilted maximal-coordinate box).
            position, _ = pb.getBasePositionAndOrientation(body, physicsClientId=client)
            pb.applyExternalForce(
                body,
                -1,
                self._pending_force[index].tolist(),
                position,
                pb.WORLD_FRAME,
                physicsClientId=client,
            )
        for index in sorted(self._pending_torque):
            pb.applyExternalTorque(
                objects[index],
                -1,
                self._pending_torque[index].tolist(),
                pb.WORLD_FRAME,
                physicsClientId=client,
            )
