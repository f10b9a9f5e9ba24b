"""Teleporting an object: moving it and setting its velocity between physics steps.

``PhysicsWorld.set_object_state`` checks the values it is given and hands them to
:func:`teleport`, which sets the body's pose and velocity in Bullet (a sphere may be
set rolling without slipping). Everything is checked before anything changes, so a
bad value leaves the object as it was.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from graspenv.config import ObjectConfig

__all__ = ["teleport"]


def teleport(
    client: int,
    body: int,
    config: ObjectConfig,
    position: ArrayLike | None = None,
    yaw: float | None = None,
    linear_velocity: ArrayLike | None = None,
    angular_velocity: ArrayLike | None = None,
    *,
    rolling: bool = False,
    orientation: ArrayLike | None = None,
) -> bool:
    """Set an object body's pose and/or velocity now; ``None`` keeps the current value.

    The arguments are those of ``PhysicsWorld.set_object_state`` (graspenv/physics/world.py
    documents them), for the body ``body`` built from ``config``.

    Returns:
        Whether anything was given to set (if not, Bullet is not touched).

    Raises:
        ValueError: a value has the wrong shape or is not finite, or ``rolling``
            is asked of something that is not a sphere or together with
            ``angular_velocity``.
    """
    name = config.name
    # Check everything before changing anything: a bad value leaves the object be.
    given_position = None if position is None else _finite(name, "position", position, ((2,), (3,)))
    if yaw is not None and not math.isfinite(yaw):
        raise ValueError(f"yaw for {name!r} must be finite (radians), got {yaw!r}")
    given_orientation = (
        None if orientation is None else _finite(name, "orientation", orientation, ((4,),))
    )
    if given_orientation is not None:
        if yaw is not None:
            raise ValueError("pass either yaw or orientation, not both")
        length = float(np.linalg.norm(given_orientation))
        if length == 0.0:
            raise ValueError(f"orientation for {name!r} must be a non-zero quaternion")
        given_orientation /= length
    given_linear = (
        None
        if linear_velocity is None
        else _finite(name, "linear_velocity", linear_velocity, ((3,),))
    )
    given_angular = (
        None
        if angular_velocity is None
        else _finite(name, "angular_velocity", angular_velocity, ((3,),))
    )
    if rolling:
        if config.shape != "sphere":
            raise ValueError(f"rolling needs a sphere; {name!r} is a {config.shape}")
        if angular_velocity is not None:
            raise ValueError("pass either rolling=True or angular_velocity, not both")
    moves = position is not None or yaw is not None or given_orientation is not None
    if not moves and given_linear is None and given_angular is None and not rolling:
        return False
    now_linear, now_angular = pb.getBaseVelocity(body, physicsClientId=client)
    linear = np.array(now_linear) if given_linear is None else given_linear
    angular = np.array(now_angular) if given_angular is None else given_angular
    if rolling:
        radius = config.size[0]
        # No slip where the sphere touches the table: v + ω × (−r ẑ) = 0.
        angular = np.array([-linear[1] / radius, linear[0] / radius, 0.0])
    if moves:
        now_position, quaternion = pb.getBasePositionAndOrientation(body, physicsClientId=client)
        xyz = np.array(now_position)
        if given_position is not None:
            xyz = given_position
            if xyz.shape == (2,):
                xyz = np.append(xyz, config.height / 2)
        if yaw is not None:
            quaternion = pb.getQuaternionFromEuler((0.0, 0.0, float(yaw)))
        elif given_orientation is not None:
            quaternion = tuple(given_orientation.tolist())
        # This also zeroes the body's velocity, which is set again below.
        pb.resetBasePositionAndOrientation(body, xyz.tolist(), quaternion, physicsClientId=client)
    pb.resetBaseVelocity(body, linear.tolist(), angular.tolist(), physicsClientId=client)
    return True


def _finite(
    name: str, what: str, value: ArrayLike, shapes: tuple[tuple[int, ...], ...]
) -> NDArray[np.float64]:
    """``value`` as a float array of one of ``shapes``, all finite, or a ValueError."""
    array = np.asarray(value, dtype=float)
    if array.shape not in shapes or not np.all(np.isfinite(array)):
        expected = " or ".join(str(s) for s in shapes)
        raise ValueError(f"{what} for {name!r} must be finite with shape {expected}, got {value!r}")
    return array.copy()
