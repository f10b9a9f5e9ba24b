"""Rigid proxy bodies: one driven prism per contact (the ``rigid`` baseline).

A body is a convex prism with the contact's footprint at touch-down, ``proxy.
rigid_height`` tall, floating a hair above the table: it collides with objects only,
so table friction does not fight the drive. It is driven by the same law as the
particles, with the mass and force limit of all the particles its contour would
have had, so the two methods push equally hard.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from graspenv.config import PhysicsConfig, ProxyConfig
from graspenv.geometry import yaw_of
from graspenv.physics.meshes import mesh_collision_shape
from graspenv.physics.pool import OBJECT_GROUP, PARTICLE_GROUP
from graspenv.physics.view import RIGID_PROXY_RGBA

__all__ = ["RigidBodies"]

# Clearance between a body's bottom face and the table, metres.
_HOVER = 0.0005


class RigidBodies:
    """Driven rigid bodies, one per contact, created at touch-down.

    Unlike particles these have the shape of their contact, so they are created when
    a contact touches down and removed at lift-off (once per touch, not per frame).

    Args:
        client: PyBullet client id.
        proxy: particle mass (per contour point), friction and ``rigid_height``.
        physics: force and speed limits.
    """

    def __init__(self, client: int, proxy: ProxyConfig, physics: PhysicsConfig) -> None:
        self._client = client
        self._proxy = proxy
        self._physics = physics
        self._bodies: dict[int, int] = {}  # handle -> Bullet body id
        self._next = 0

    def __len__(self) -> int:
        return len(self._bodies)

    def add(self, footprint: ArrayLike, position: ArrayLike) -> int:
        """Create a body with a footprint around a position; returns its handle.

        Args:
            footprint: the contact's outline relative to ``position``, metres, shape
                (N, 2); the body is its convex hull.
            position: (x, y) of the body's origin, metres, world frame.
        """
        outline = np.asarray(footprint, dtype=float).reshape(-1, 2)
        xy = np.asarray(position, dtype=float).reshape(2)
        half = self._proxy.rigid_height / 2
        vertices = np.concatenate(
            [np.column_stack([outline, np.full(len(outline), z)]) for z in (-half, half)]
        )
        c = self._client
        # Bullet keeps each mesh shape (about 6 KB) until the world is rebuilt:
        # removeCollisionShape refuses a shape a removed body once used.
        shape = mesh_collision_shape(c, vertices)
        mass = self._proxy.particle_mass * len(outline)
        body = pb.createMultiBody(mass, shape, -1, [xy[0], xy[1], half + _HOVER], physicsClientId=c)
        pb.changeDynamics(
            body,
            -1,
            mass=mass,
            lateralFriction=self._proxy.particle_friction,
            linearDamping=0.0,
            angularDamping=0.0,
            activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING,
            physicsClientId=c,
        )
        # Objects only: the drive holds the height, the table would only add drag.
        pb.setCollisionFilterGroupMask(body, -1, PARTICLE_GROUP, OBJECT_GROUP, physicsClientId=c)
        # Drawn from its collision shape (white) unless given a colour.
        pb.changeVisualShape(body, -1, rgbaColor=RIGID_PROXY_RGBA, physicsClientId=c)
        handle = self._next
        self._next += 1
        self._bodies[handle] = body
        return handle

    def remove(self, handle: int) -> None:
        """Remove a body (lift-off)."""
        body = self._bodies.pop(handle)
        pb.removeBody(body, physicsClientId=self._client)

    def clear(self) -> None:
        for handle in list(self._bodies):
            self.remove(handle)

    def poses(self, handles: ArrayLike) -> NDArray[np.float64]:
        """(x, y, yaw) of bodies, metres and radians, world frame, shape (B, 3)."""
        rows = []
        for handle in np.asarray(handles, dtype=np.int64).reshape(-1).tolist():
            position, orientation = pb.getBasePositionAndOrientation(
                self._bodies[handle], self._client
            )
            rows.append((position[0], position[1], yaw_of(orientation)))
        return np.array(rows, dtype=float).reshape(-1, 3)

    def drive(self, handles: ArrayLike, goals: ArrayLike, h: float, tau: float) -> None:
        """Set each body's velocity for one sub-step towards its goal pose.

        The planar law is the particles' (v* = (x* − x)/Δt, a change of at most
        F_max·h/m), the yaw and the height follow at the rate that closes them in Δt.

        Args:
            handles: body handles, shape (B,).
            goals: (x, y, yaw) goals, metres and radians, world frame, shape (B, 3).
            h: sub-step, seconds.
            tau: the control law's Δt, seconds.
        """
        c = self._client
        half = self._proxy.rigid_height / 2 + _HOVER
        v_max = self._physics.max_particle_speed
        for handle, goal in zip(
            np.asarray(handles, dtype=np.int64).tolist(), np.asarray(goals).tolist(), strict=True
        ):
            body = self._bodies[handle]
            position, orientation = pb.getBasePositionAndOrientation(body, c)
            velocity, _ = pb.getBaseVelocity(body, c)
            yaw = yaw_of(orientation)
            v_star = np.array([goal[0] - position[0], goal[1] - position[1]]) / tau
            speed = float(np.hypot(*v_star))
            if speed > v_max:
                v_star *= v_max / speed
            dv = (h / tau) * (v_star - np.asarray(velocity[:2]))
            dv_max = self._physics.max_particle_force * h / self._proxy.particle_mass
            size = float(np.hypot(*dv))
            if size > dv_max:
                dv *= dv_max / size
            vx, vy = np.asarray(velocity[:2]) + dv
            vz = (half - position[2]) / tau
            spin = math.remainder(goal[2] - yaw, 2 * math.pi) / tau
            # Tilting is not part of the drive: the body is stood upright each sub-step
            # (before its velocity is set, which a pose reset would not keep).
            pb.resetBasePositionAndOrientation(
                body, position, pb.getQuaternionFromEuler([0.0, 0.0, yaw]), c
            )
            pb.resetBaseVelocity(body, [vx, vy, vz], [0.0, 0.0, spin], c)
