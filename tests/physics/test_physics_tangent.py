"""The law along an object's side (``physics.stiff_tangent``): the side's normal from
the footprints, the law stiffer along it than across it, and what that buys a grip."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from graspenv.config import load_config
from graspenv.geometry import SHAPE_CODES, footprint_sides
from graspenv.physics import PhysicsWorld
from graspenv.physics.control import ParticleDrive, SupportPlanes
from tests.physics._helpers import squeeze_and_turn

NEAR = 0.004


def _rotation(yaw: float, roll: float = 0.0) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    about_z = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    cr, sr = math.cos(roll), math.sin(roll)
    about_x = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return (about_z @ about_x).reshape(1, 9)


def _normals(
    points: list[list[float]], shape: str, size: tuple[float, ...], rotation: np.ndarray
) -> np.ndarray:
    return footprint_sides(
        np.array(points, float),
        np.array([SHAPE_CODES[shape]]),
        np.array([[*size, 0.0, 0.0][:3]], float),
        np.array([[0.01, -0.02, 0.015]]),
        rotation,
        NEAR,
    )[2]


def test_a_box_side_gives_its_own_outward_normal_inside_and_just_outside() -> None:
    yaw = 0.5
    c, s = math.cos(yaw), math.sin(yaw)
    x_axis, y_axis = np.array([c, s]), np.array([-s, c])
    centre = np.array([0.01, -0.02])
    # Just inside and just outside the +x side, inside the -y side, 3 mm beyond the
    # +y side, and 6 mm beyond the -x side (farther than NEAR).
    points = [
        centre + 0.028 * x_axis + 0.01 * y_axis,
        centre + 0.032 * x_axis - 0.005 * y_axis,
        centre - 0.027 * y_axis + 0.01 * x_axis,
        centre + 0.033 * y_axis,
        centre - 0.036 * x_axis,
    ]
    normals = _normals([list(p) for p in points], "box", (0.06, 0.06, 0.03), _rotation(yaw))
    # Each pointing out of the box.
    for row, axis in zip(normals[:4], (x_axis, x_axis, -y_axis, y_axis), strict=True):
        assert row @ axis == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_array_equal(normals[4], [0.0, 0.0])


def test_an_upright_cylinder_gives_the_radial_direction_and_a_leaning_one_none() -> None:
    points = [[0.01 + 0.02, -0.02 + 0.021], [0.01, -0.02], [0.01 - 0.032, -0.02]]
    normals = _normals(points, "cylinder", (0.03, 0.05), _rotation(0.3))
    np.testing.assert_allclose(normals[0], np.array([0.02, 0.021]) / math.hypot(0.02, 0.021))
    np.testing.assert_array_equal(normals[1], [0.0, 0.0])  # at the centre: no direction
    np.testing.assert_allclose(normals[2], [-1.0, 0.0])
    leaning = _normals(points, "cylinder", (0.03, 0.05), _rotation(0.3, roll=0.2))
    np.testing.assert_array_equal(leaning, np.zeros((3, 2)))


def _drive(
    normal: list[float],
    tangent_dt: float | None,
    start: np.ndarray | None = None,
    goal: np.ndarray | None = None,
) -> ParticleDrive:
    """A drive at eight sub-steps a frame for one particle whose target goes from
    ``start`` to ``goal`` (default: both the origin)."""
    scene = load_config()
    goal = np.zeros(2) if goal is None else goal
    return ParticleDrive.for_frame(
        np.array([goal if start is None else start]),
        np.array([goal]),
        1,
        1 / 60,
        8,
        scene.proxy,
        scene.physics,
        top_press=scene.proxy.down_force,
        control_dt=1 / 240,
        normals=np.array([normal]),
        tangent_dt=tangent_dt,
    )


def _velocity(drive: ParticleDrive, offset: list[float]) -> np.ndarray:
    r = load_config().proxy.particle_radius
    position = np.array([[*offset, r]])
    rest = SupportPlanes(np.array([r]), position[:, :2].copy(), np.zeros((1, 2)))
    return drive.velocities(1, position, np.zeros((1, 3)), rest, np.zeros(1))[0, :2]


@pytest.mark.parametrize("normal", [[1.0, 0.0], [0.6, 0.8]])
def test_the_law_is_stiffer_along_the_side_and_unchanged_across_it(normal: list[float]) -> None:
    """At eight sub-steps (h = Δt/2) and the tangent's Δt at the sub-step, a particle
    held off its target across the side is driven as before; along the side it is
    driven to land on the target in one sub-step (the paper's law, h/Δt_t = 1)."""
    n = np.array(normal)
    t = np.array([-n[1], n[0]])
    h, tau = 1 / 480, 1 / 240
    stiff, plain = _drive(normal, 1 / 480), _drive(normal, None)
    across, along = list(-1e-3 * n), list(-1e-3 * t)
    np.testing.assert_allclose(_velocity(stiff, across), _velocity(plain, across), atol=1e-12)
    np.testing.assert_allclose(_velocity(plain, along), 1e-3 * t * h / tau**2, atol=1e-12)
    np.testing.assert_allclose(_velocity(stiff, along), 1e-3 * t / h, atol=1e-12)
    # A particle with no side beside it keeps the plain law both ways.
    free = _drive([0.0, 0.0], 1 / 480)
    np.testing.assert_array_equal(_velocity(free, along), _velocity(plain, along))


@pytest.mark.parametrize("normal", [[1.0, 0.0], [0.6, 0.8]])
@pytest.mark.parametrize("heading", ["along", "across", "oblique"])
def test_a_free_particle_follows_a_moving_target_without_lag_either_way(
    normal: list[float], heading: str
) -> None:
    """The feed forward along the side and across it: a free particle on a target
    moving at 0.1 m/s lands on it at the end of every frame, with the tangent's Δt
    shorter than the law's or not (the sub-steps integrated here, no Bullet)."""
    n = np.array(normal)
    t = np.array([-n[1], n[0]])
    u = 0.1 * {"along": t, "across": n, "oblique": (n + 2 * t) / math.sqrt(5)}[heading]
    frame_dt, substeps = 1 / 60, 8
    r = load_config().proxy.particle_radius
    rest = SupportPlanes(np.array([r]), np.zeros((1, 2)), np.zeros((1, 2)))
    for tangent_dt in (1 / 480, None):
        position, velocity = np.array([[0.0, 0.0, r]]), np.zeros((1, 3))
        velocity[0, :2] = u
        for frame in range(1, 6):
            goal = u * frame * frame_dt
            drive = _drive(normal, tangent_dt, start=goal - u * frame_dt, goal=goal)
            for s in range(1, substeps + 1):
                velocity[0, :2] = drive.velocities(s, position, velocity, rest, np.zeros(1))[0, :2]
                position[0, :2] += velocity[0, :2] * frame_dt / substeps
            np.testing.assert_allclose(position[0, :2], goal, atol=1e-12)
            np.testing.assert_allclose(velocity[0, :2], u, atol=1e-9)


def test_at_four_sub_steps_it_changes_nothing(make_world: Callable[..., PhysicsWorld]) -> None:
    """The default's sub-step is the law's Δt: along the side and across it alike."""
    plain = squeeze_and_turn(make_world())
    stiff = squeeze_and_turn(make_world(physics={"stiff_tangent": True}))
    assert stiff[0] == plain[0]
    np.testing.assert_array_equal(stiff[1], plain[1])


def test_at_eight_sub_steps_the_turned_box_lags_its_grip_less(
    make_world: Callable[..., PhysicsWorld],
) -> None:
    """On a table of friction 1 the box's friction torque holds it behind its grip by
    the spring's give; four times as stiff along its sides, it lags less."""
    physics = {"substeps": 8, "solver_iterations": 300, "table_friction": 1.0}
    plain, _ = squeeze_and_turn(make_world(physics=physics))
    stiff, _ = squeeze_and_turn(make_world(physics={**physics, "stiff_tangent": True}))
    assert abs(stiff - 90.0) < 0.5 * abs(plain - 90.0)
