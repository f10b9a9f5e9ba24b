"""PhysicsWorld.apply_force and set_object_state: disturbances and initial states."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from graspenv.geometry import yaw_of
from graspenv.physics import PhysicsWorld

BALL = {"name": "ball", "shape": "sphere", "size": [0.02], "mass": 0.1, "position": [-0.1, 0.0]}


def _lift(world: PhysicsWorld, name: str) -> None:
    """Put an object high above the table so that nothing but gravity acts on it."""
    world.set_object_state(name, position=[0.0, 0.0, 2.0])


@pytest.mark.parametrize("path", ["no particles", "particles", "rigid bodies"])
def test_force_acts_for_exactly_one_frame(world: PhysicsWorld, path: str) -> None:
    _lift(world, "box")
    mass = world.scene.objects[0].mass
    frame: Callable[[], None]
    if path == "particles":
        ids = world.pool.acquire(3)
        world.pool.place(ids, [[0.2, 0.1 + 0.01 * i, world.pool.radius] for i in range(3)])
        targets = world.pool.last_targets(ids)

        def frame() -> None:
            world.step_frame(ids, targets)

    elif path == "rigid bodies":
        handle = world.rigid_proxies.add([[0.01, 0.0], [0.0, 0.01], [-0.01, 0.0]], (0.2, 0.0))

        def frame() -> None:
            world.step_bodies([handle], [[0.2, 0.0, 0.0]])

    else:

        def frame() -> None:
            world.step_frame([], np.zeros((0, 2)))

    world.apply_force("box", [0.3, -0.1, 0.0])
    world.apply_force("box", [0.2, 0.0, 0.0])  # forces before one frame add up
    frame()
    linear, angular = world.object_velocity("box")
    # Momentum gained over one frame: F · frame_dt (free fall only changes z).
    np.testing.assert_allclose(linear[:2], np.array([0.5, -0.1]) * world.frame_dt / mass, rtol=1e-9)
    np.testing.assert_allclose(angular, 0.0, atol=1e-12)  # pushed at its centre
    frame()
    after, _ = world.object_velocity("box")
    np.testing.assert_allclose(after[:2], linear[:2], rtol=1e-12)  # gone the next frame


def test_force_slides_a_box_against_table_friction(world: PhysicsWorld) -> None:
    config = world.scene.objects[0]
    mu = config.friction * world.scene.physics.table_friction  # Bullet multiplies them
    push = 3.0 * mu * config.mass * world.scene.physics.gravity
    frames = 10  # 8 cm of slide: stays well on the table
    for _ in range(frames):
        world.apply_force("box", [push, 0.0, 0.0])
        world.step_frame([], np.zeros((0, 2)))
    linear, _ = world.object_velocity("box")
    expected = (push - mu * config.mass * world.scene.physics.gravity) / config.mass
    assert linear[0] == pytest.approx(expected * frames * world.frame_dt, rel=0.03)
    position, quaternion = world.object_pose("box")
    assert abs(position[2] - config.height / 2) < 1e-3  # slid, did not tip
    assert abs(yaw_of(quaternion)) < 0.03  # Bullet's four box-on-table contacts turn it ~1°


def test_reset_drops_pending_forces(world: PhysicsWorld) -> None:
    world.apply_force("box", [100.0, 0.0, 0.0])
    world.reset()
    world.step_frame([], np.zeros((0, 2)))
    linear, _ = world.object_velocity("box")
    assert abs(linear[0]) < 1e-4  # resting jitter; 100 N for one frame would give 8 m/s


def test_set_object_state_sets_what_is_given(world: PhysicsWorld) -> None:
    world.set_object_state(
        "box",
        position=[0.1, -0.05, 0.2],
        yaw=0.7,
        linear_velocity=[0.1, 0.2, 0.3],
        angular_velocity=[0.0, 0.0, 1.5],
    )
    position, quaternion = world.object_pose("box")
    np.testing.assert_allclose(position, [0.1, -0.05, 0.2])
    assert yaw_of(quaternion) == pytest.approx(0.7)
    linear, angular = world.object_velocity("box")
    np.testing.assert_allclose(linear, [0.1, 0.2, 0.3])
    np.testing.assert_allclose(angular, [0.0, 0.0, 1.5])

    # None keeps the current value; (x, y) rests the object on the table.
    world.set_object_state("box", position=[0.05, 0.05])
    position, quaternion = world.object_pose("box")
    np.testing.assert_allclose(position, [0.05, 0.05, world.scene.objects[0].height / 2])
    assert yaw_of(quaternion) == pytest.approx(0.7)
    np.testing.assert_allclose(world.object_velocity("box")[0], [0.1, 0.2, 0.3])
    world.set_object_state("box", linear_velocity=[0.0, 0.0, 0.0])
    np.testing.assert_allclose(world.object_velocity("box")[1], [0.0, 0.0, 1.5])


def test_a_rolling_ball_keeps_its_speed_a_sliding_one_slows(
    make_world: Callable[..., PhysicsWorld],
) -> None:
    speeds = {}
    for rolling in (True, False):
        world = make_world(objects=[BALL])
        world.set_object_state("ball", linear_velocity=[0.3, 0.1, 0.0], rolling=rolling)
        if rolling:
            _, angular = world.object_velocity("ball")
            np.testing.assert_allclose(angular, [-0.1 / 0.02, 0.3 / 0.02, 0.0])
        for _ in range(30):
            world.step_frame([], np.zeros((0, 2)))
        linear, _ = world.object_velocity("ball")
        speeds[rolling] = float(np.hypot(*linear[:2]))
    v0 = float(np.hypot(0.3, 0.1))
    assert speeds[True] == pytest.approx(v0, rel=0.01)
    # A sliding sphere ends up rolling at 5/7 of its speed (solid sphere, Coulomb).
    assert speeds[False] == pytest.approx(5 / 7 * v0, rel=0.03)


def test_bad_forces_and_states_are_refused(make_world: Callable[..., PhysicsWorld]) -> None:
    world = make_world(objects=[BALL, {"name": "box", "shape": "box", "size": [0.05] * 3}])
    with pytest.raises(KeyError, match="no object named 'cup'"):
        world.apply_force("cup", [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="3 finite numbers"):
        world.apply_force("box", [1.0, 0.0])
    with pytest.raises(ValueError, match="3 finite numbers"):
        world.apply_force("box", [np.nan, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"position for 'box'.*\(2,\) or \(3,\)"):
        world.set_object_state("box", position=[0.0])
    with pytest.raises(ValueError, match="linear_velocity"):
        world.set_object_state("box", linear_velocity=[0.0, np.inf, 0.0])
    with pytest.raises(ValueError, match="yaw"):
        world.set_object_state("box", yaw=float("nan"))
    with pytest.raises(ValueError, match="rolling needs a sphere; 'box' is a box"):
        world.set_object_state("box", linear_velocity=[0.1, 0.0, 0.0], rolling=True)
    with pytest.raises(ValueError, match="not both"):
        world.set_object_state("ball", angular_velocity=[0.0, 0.0, 1.0], rolling=True)
