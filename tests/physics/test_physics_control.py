"""The per-frame control step: Wilson's force law, stacks, spin, and a real grasp."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pybullet as pb
import pytest
from numpy.typing import NDArray

from graspenv.physics import PhysicsWorld
from graspenv.physics.control import ParticleDrive, SupportPlanes
from tests.physics._helpers import BOX_HALF, BOX_HEIGHT, squeeze_and_turn


def test_control_law_drives_a_free_particle_to_its_target(world: PhysicsWorld) -> None:
    r = world.scene.proxy.particle_radius
    ids = world.pool.acquire(1)
    world.pool.place(ids, [[0.1, 0.1, r]])
    target = np.array([[0.15, 0.12]])
    for _ in range(10):
        end = world.step_frame(ids, target)
    # Table friction on the pressed particle (2 × 0.5 × 0.05 N) against the control
    # spring (m/Δt² = 576 N/m) leaves it up to 0.09 mm short.
    np.testing.assert_allclose(end[0, :2], target[0], atol=1.5e-4)
    assert np.linalg.norm(world.pool.velocities(ids)[0, :2]) < 1e-3


def test_particle_follows_a_moving_target_without_lag(world: PhysicsWorld) -> None:
    r = world.scene.proxy.particle_radius
    ids = world.pool.acquire(1)
    world.pool.place(ids, [[-0.2, 0.1, r]])
    speed = 0.3  # m/s along x
    for f in range(1, 31):
        end = world.step_frame(ids, [[-0.2 + speed * f * world.frame_dt, 0.1]])
    # no velocity lag (u·Δt would be 1.25 mm), only the friction lag of under 0.1 mm
    assert end[0, 0] == pytest.approx(-0.2 + speed * 30 * world.frame_dt, abs=1e-4)
    assert world.pool.velocities(ids)[0, 0] == pytest.approx(speed, rel=1e-3)


def test_force_clamp_limits_a_far_jump(make_world: Callable[..., PhysicsWorld]) -> None:
    world = make_world(physics={"max_particle_force": 1.0, "max_particle_speed": 100.0})
    r = world.scene.proxy.particle_radius
    ids = world.pool.acquire(1)
    world.pool.place(ids, [[0.0, 0.1, r]])
    world.step_frame(ids, [[0.2, 0.1]])
    # at most F/m acceleration for one frame: v <= (1 N / 10 g) · (1/60 s)
    assert world.pool.velocities(ids)[0, 0] <= 1.0 / 0.01 / 60 + 1e-9


def test_spin_is_held_exactly(world: PhysicsWorld) -> None:
    r = world.scene.proxy.particle_radius
    ids = world.pool.acquire(1)
    world.pool.place(ids, [[0.1, 0.1, r]])
    for _ in range(5):
        world.step_frame(ids, [[0.12, 0.1]], spin=1.5)
    body = int(world.pool.body_ids(ids)[0])
    angular = pb.getBaseVelocity(body, physicsClientId=world.client)[1]
    np.testing.assert_allclose(angular, [0.0, 0.0, 1.5], rtol=0, atol=1e-12)


def test_stack_layers_are_held_above_the_bottom_one(
    make_world: Callable[..., PhysicsWorld],
) -> None:
    world = make_world(proxy={"stack_layers": 3, "stack_spacing": 0.005})
    r = world.scene.proxy.particle_radius
    ids = world.pool.acquire(6).reshape(2, 3)
    xyz = [[0.1, 0.1, r + 0.005 * layer] for layer in range(3)]
    xyz += [[0.0, 0.0, BOX_HEIGHT + r + 0.005 * layer] for layer in range(3)]
    world.pool.place(ids.ravel(), xyz)
    for _ in range(20):
        end = world.step_frame(ids, [[0.12, 0.1], [0.005, 0.0]])
    assert end.shape == (2, 3, 3)
    np.testing.assert_allclose(end[:, :, 2] - end[:, :1, 2], [[0, 0.005, 0.01]] * 2, atol=2e-4)
    np.testing.assert_allclose(end[:, 0, 2], [r, BOX_HEIGHT + r], atol=3e-4)


def test_bottom_particle_rides_on_top_and_drops_off_the_edge(world: PhysicsWorld) -> None:
    r = world.scene.proxy.particle_radius
    ids = world.pool.acquire(1)
    world.pool.place(ids, [[0.0, 0.0, BOX_HEIGHT + r]])
    for _ in range(5):
        end = world.step_frame(ids, [[0.01, 0.0]])
    assert end[0, 2] == pytest.approx(BOX_HEIGHT + r, abs=3e-4)
    for _ in range(20):
        end = world.step_frame(ids, [[BOX_HALF + 0.02, 0.0]])
    assert end[0, 2] == pytest.approx(r, abs=3e-4)


def test_squeeze_and_turn_with_ideal_targets_reaches_the_yaw(world: PhysicsWorld) -> None:
    """Two round fingertips squeeze the box 3 mm deep and turn 90° about it in 1.5 s."""
    yaw, position = squeeze_and_turn(world)
    assert yaw == pytest.approx(90.0, abs=1.0)
    assert np.hypot(position[0], position[1]) < 0.002
    assert position[2] == pytest.approx(BOX_HEIGHT / 2, abs=1e-3)


@pytest.mark.parametrize("side", [1.0, -1.0])
@pytest.mark.parametrize("offset", [-4e-4, -2e-4, 0.0, 1e-9, 2e-4])
def test_a_particle_resting_against_a_face_stays_finite(
    make_world: Callable[..., PhysicsWorld], side: float, offset: float
) -> None:
    """A bottom particle held still against a box's side, on the face's centre line.

    Its only motion along the face is the press, straight down; planar friction with
    no vertical part at all would then make the friction direction of that contact
    zero, and Bullet's solver divides by it (the whole world became NaN in the first
    frame for a third of these placements).
    """
    world = make_world()
    r = world.scene.proxy.particle_radius
    x = side * (BOX_HALF + r + offset)
    ids = world.pool.acquire(1)
    world.pool.place(ids, [[x, 0.0, r]])
    for _ in range(5):
        world.step_frame(ids, [[x, 0.0]])
        assert np.isfinite(world.pool.positions(ids)).all()
        assert all(np.isfinite(part).all() for part in world.object_pose("box"))


def test_a_light_scene_scales_the_table_press_but_not_the_press_on_an_object() -> None:
    from graspenv.config import load_config

    light = load_config(
        None, objects=[{"name": "box", "shape": "box", "size": [0.06, 0.06, 0.03], "mass": 0.005}]
    )
    proxy, physics = light.particle_settings
    r = proxy.particle_radius
    start = np.zeros((2, 2))
    drive = ParticleDrive.for_frame(
        start, start, 1, 1 / 60, 4, proxy, physics, top_press=light.proxy.down_force
    )
    h = 1 / 240
    position = np.array([[0.0, 0.0, r], [0.0, 0.0, 0.03 + r]])  # on the table, on the box
    rest = SupportPlanes(np.array([r, 0.03 + r]), position[:, :2], np.zeros((2, 2)))
    v = drive.velocities(1, position, np.zeros((2, 3)), rest, drive.presses(rest.rest_z))
    g = physics.gravity
    # The press (weight cancelled) as a velocity change: scaled beside the box, the
    # finger's whole 0.05 N on it (0.5 g particles: 2.5 N/kg against 100 N/kg).
    press = light.proxy.down_force
    assert v[0, 2] == pytest.approx((g - press * light.particle_scale / proxy.particle_mass) * h)
    assert v[1, 2] == pytest.approx((g - press / proxy.particle_mass) * h)
    # A scene of 200 g objects presses both the same, to the last bit.
    default = load_config(None)
    drive = ParticleDrive.for_frame(
        start, start, 1, 1 / 60, 4, *default.particle_settings, top_press=default.proxy.down_force
    )
    assert drive.top_press_dv == drive.press_dv


def test_a_frame_gets_the_sub_steps_its_fastest_point_needs() -> None:
    from graspenv.config import PhysicsConfig
    from graspenv.physics.control import frame_substeps

    physics = PhysicsConfig(substeps=4, max_substeps=16, substep_travel=0.001)
    assert frame_substeps(0.0, physics) == 4
    assert frame_substeps(0.004, physics) == 4  # 1 mm a sub-step at four
    assert frame_substeps(0.0041, physics) == 5
    assert frame_substeps(0.0105, physics) == 11
    assert frame_substeps(1.0, physics) == 16  # capped
    fixed = PhysicsConfig(substeps=4, max_substeps=2)
    assert frame_substeps(1.0, fixed) == 4  # at or below substeps: a fixed count


def _one_bottom_particle(substeps: int = 4) -> tuple[ParticleDrive, float, float]:
    """The default scene's law for one particle held still at the origin, its
    radius and its sub-step."""
    from graspenv.config import load_config

    scene = load_config(None)
    proxy, physics = scene.particle_settings
    start = np.zeros((1, 2))
    drive = ParticleDrive.for_frame(
        start, start, 1, 1 / 60, substeps, proxy, physics, top_press=scene.proxy.down_force
    )
    return drive, proxy.particle_radius, 1 / 60 / substeps


def test_a_particle_far_above_its_support_is_pulled_down_a_sub_step_travel_at_most() -> None:
    from graspenv.config import PhysicsConfig

    drive, r, h = _one_bottom_particle()
    travel = PhysicsConfig().substep_travel
    rest = SupportPlanes(np.array([0.03 + r]), np.zeros((1, 2)), np.zeros((1, 2)))
    press = drive.presses(rest.rest_z)

    def pull(above: float) -> float:
        """The velocity change beyond the press (which alone acts on a particle at
        rest on its support) of a particle ``above`` metres over it."""
        position = np.array([[0.0, 0.0, 0.03 + r + above]])
        v = drive.velocities(1, position, np.zeros((1, 3)), rest, press)
        return float(v[0, 2] - press[0])

    assert pull(0.0001) == 0.0  # within the 0.2 mm tolerance
    # 0.4 mm above: the law's own pull, (0.4 - 0.2) mm over its Δt; 20 mm above (a
    # support that vanished under it): no faster than physics.substep_travel a sub-step.
    assert 0.0 < -pull(0.0004) <= travel / h + 1e-12
    assert -pull(0.02) == pytest.approx(travel / h)


def test_a_falling_particle_carries_at_most_the_pull_speed_and_the_press_adds_on() -> None:
    """Pressed off the edge its support was measured on, a particle falls below that
    support: its downward speed carried into the next sub-step is capped at
    ``physics.substep_travel`` a sub-step, the press added on top; one resting on its
    support (at rest, or rising) keeps its velocity and gets the press alone."""
    from graspenv.config import PhysicsConfig

    drive, r, h = _one_bottom_particle()
    pull_max = PhysicsConfig().substep_travel / h
    rest = SupportPlanes(np.array([0.03 + r]), np.zeros((1, 2)), np.zeros((1, 2)))
    press = drive.presses(rest.rest_z)
    below = np.array([[0.0, 0.0, 0.02 + r]])  # 10 mm under the stale support

    def vz(speed: float, position: np.ndarray = below) -> float:
        v = drive.velocities(1, position, np.array([[0.0, 0.0, speed]]), rest, press)
        return float(v[0, 2])

    assert vz(-1.0) == pytest.approx(-pull_max + press[0])
    assert vz(-0.5 * pull_max) == pytest.approx(-0.5 * pull_max + press[0])
    assert vz(0.0) == pytest.approx(press[0])
    assert vz(0.1) == pytest.approx(0.1 + press[0])
    on_support = np.array([[0.0, 0.0, 0.03 + r]])
    assert vz(0.0, on_support) == pytest.approx(press[0])


def test_the_support_is_followed_along_its_slope() -> None:
    drive, r, _ = _one_bottom_particle()
    # A face rising 1 in 2 along +x, measured under the particle at x = 0.
    rest = SupportPlanes(np.array([0.04 + r]), np.zeros((1, 2)), np.array([[0.5, 0.0]]))
    press = drive.presses(rest.rest_z)
    # 4 mm uphill the support is 2 mm higher: a particle resting there is not pulled
    # into the face (measured at x = 0 it would be 2 mm above it).
    on_face = np.array([[0.004, 0.0, 0.042 + r]])
    v = drive.velocities(1, on_face, np.zeros((1, 3)), rest, press)
    assert v[0, 2] == pytest.approx(press[0])
    # 1 mm above the face there, it is pulled back.
    above = on_face + np.array([0.0, 0.0, 0.001])
    assert drive.velocities(1, above, np.zeros((1, 3)), rest, press)[0, 2] < press[0]


def _ball_and_box(make_world: Callable[..., PhysicsWorld], radius: float) -> PhysicsWorld:
    """A ball of ``radius`` at x = 0.1 m and the 6 × 6 × 3 cm box at x = −0.1 m."""
    return make_world(
        objects=[
            {"name": "ball", "shape": "sphere", "size": [radius], "position": [0.1, 0.0]},
            {"name": "box", "shape": "box", "size": [0.06, 0.06, 0.03], "position": [-0.1, 0.0]},
        ]
    )


def test_the_support_plane_of_a_ball_is_its_tangent_and_a_box_top_is_level(
    make_world: Callable[..., PhysicsWorld],
) -> None:
    from graspenv.physics.rays import SUPPORT_CLEARANCE

    radius = 0.04
    world = _ball_and_box(make_world, radius)
    r = world.scene.proxy.particle_radius
    rays = world._rays
    # On the ball, 15 mm from its top (x) and 5 mm (y): the slope of the sphere there.
    dx, dy = -0.015, 0.005
    z = radius + math.sqrt(radius**2 - dx**2 - dy**2)
    points = np.array(
        [
            [0.1 + dx, dy, z + r],  # on the ball's shoulder
            [-0.1, 0.0, 0.03 + r],  # on the box's level top
            [-0.1 + 0.03, 0.0, 0.03 + r],  # over the box's edge: rays meet top and table
        ]
    )
    height, slope = rays.support_planes(points, clearance=SUPPORT_CLEARANCE * r)
    surface = z - radius
    expected = [-dx / surface, -dy / surface]
    np.testing.assert_allclose(slope[0], expected, rtol=0.05)
    # The highest of the disc's rays: the uphill one, 0.9 radius out.
    uphill = 0.9 * r * math.hypot(*expected)
    assert z < height[0] <= z + 1.05 * uphill
    np.testing.assert_array_equal(slope[1:], 0.0)
    np.testing.assert_allclose(height[1:], 0.03, atol=1e-4)


def test_a_particle_put_down_beside_a_ball_or_a_box_rests_on_the_table(
    make_world: Callable[..., PhysicsWorld],
) -> None:
    radius = 0.03
    world = _ball_and_box(make_world, radius)
    r = world.pool.radius
    # Centres 1 mm outside the ball's equator and the box's side: each disc's ring
    # ray meets the object. The ball overhangs the table there (a particle on the
    # table misses it by far), so the particle rests on the table where it is; the
    # box is solid down to the table, so the particle is moved out until it clears
    # the side and rests on the table (on the top face, its centre off it, it would
    # roll off the edge).
    beside_ball = [0.1 + radius + 0.001, 0.0]
    face = -0.1 + 0.03
    beside_box = [face + 0.001, 0.0]
    on_ball = [0.1 + 0.3 * radius, 0.0]  # a shoulder with too little room under it
    on_box = [face - 0.005, 0.0]
    at = world.put_down([beside_ball, beside_box, on_ball, on_box])
    np.testing.assert_allclose(at[0], [*beside_ball, r])
    np.testing.assert_allclose(at[1], [face + r, 0.0, r], atol=1e-9)
    shoulder = radius + math.sqrt(radius**2 - (0.3 * radius) ** 2)
    np.testing.assert_allclose(at[2, :2], on_ball)
    assert shoulder < at[2, 2] - r < shoulder + r
    np.testing.assert_allclose(at[3], [*on_box, 0.03 + r], atol=1e-4)
    # As the instant proxies put particles down: on the top face beside the side.
    kept = world.put_down([beside_ball, beside_box], clear_sides=False)
    np.testing.assert_allclose(kept[:, :2], [beside_ball, beside_box])
    np.testing.assert_allclose(kept[:, 2], [r, 0.03 + r], atol=1e-4)
    # Without fit_under (a particle's own support, its rays starting at it) the
    # flank below the ring ray is the support, as before.
    start = np.array([[*beside_ball, 2 * radius]])
    assert world._rays.support_heights(start)[0] > radius


def _run_on(
    substeps: int,
    critical: bool,
    direction: tuple[float, float] = (1.0, 0.0),
    normal: tuple[float, float] | None = None,
    tangent_dt: float | None = None,
    frames_moving: int = 20,
) -> NDArray[np.float64]:
    """The law alone (no Bullet) on one free particle whose target moves at 6.7 cm/s
    along ``direction`` for ``frames_moving`` frames and then stops dead: the
    particle's signed distance past the stopped target along ``direction`` after
    each sub-step of the next 20 frames, metres. With ``normal`` the target lies
    beside an object's side of that table-plane normal, the law's Δt along it
    ``tangent_dt``."""
    from graspenv.config import load_config

    scene = load_config(None).replace(physics={"substeps": substeps, "critical_damping": critical})
    proxy, physics = scene.particle_settings
    frame_dt = 1 / scene.surface.fps
    way = np.array(direction)
    speed = 0.067
    r = proxy.particle_radius
    rest = SupportPlanes(np.array([r]), np.zeros((1, 2)), np.zeros((1, 2)))
    normals = None if normal is None else np.array([normal])
    position = np.array([[0.0, 0.0, r]])
    velocity = np.array([[*(speed * way), 0.0]])
    h = frame_dt / substeps
    press = np.array([0.0])  # the vertical velocity is zeroed below
    past = []
    for frame in range(frames_moving + 20):
        start = speed * frame_dt * min(frame, frames_moving) * way[None, :]
        goal = speed * frame_dt * min(frame + 1, frames_moving) * way[None, :]
        drive = ParticleDrive.for_frame(
            start,
            goal,
            1,
            frame_dt,
            substeps,
            proxy,
            physics,
            top_press=proxy.down_force,
            normals=normals,
            tangent_dt=tangent_dt,
        )
        for s in range(1, substeps + 1):
            velocity = drive.velocities(s, position, velocity, rest, press)
            velocity[:, 2] = 0.0  # the table holds it; only the plane is in question
            position = position + h * velocity
            if frame >= frames_moving:
                past.append(float((position[0, :2] - goal[0]) @ way))
    return np.array(past)


def _double_root_residual(past: NDArray[np.float64], root: float) -> float:
    """How far a particle's path after its point stopped is from that of a linear
    recurrence whose two roots are both ``root`` (a critically damped sub-step:
    e[k+2] = 2·root·e[k+1] − root²·e[k]), relative to its largest excursion."""
    rest = past[2:] - 2 * root * past[1:-1] + root**2 * past[:-2]
    return float(np.abs(rest).max() / np.abs(past).max())


def test_critical_damping_is_the_law_itself_at_its_own_step() -> None:
    """At h = Δt (the default's four sub-steps at 60 frames a second) the
    experiment's extra damping is zero, and the velocities the same to the bit."""
    assert np.array_equal(_run_on(4, critical=True), _run_on(4, critical=False))
    assert np.abs(_run_on(4, critical=False)).max() < 1e-9  # lands in one sub-step


@pytest.mark.parametrize("substeps", [8, 16])
def test_critical_damping_takes_the_ring_out_of_a_finer_step(substeps: int) -> None:
    """Below Δt the law's continuous form rings (damping ratio 0.5): a particle
    whose point stops dead runs past it and swings back beyond it. With
    ``physics.critical_damping`` it runs on less, never swings back, and its two
    roots a sub-step are both 1 − h/Δt."""
    rings = _run_on(substeps, critical=False)
    damped = _run_on(substeps, critical=True)
    assert rings.max() > 5e-5 and rings.min() < -5e-6  # 87 µm past, 9 µm back at 8
    assert 0.0 < damped.max() < 0.6 * rings.max()
    assert damped.min() > -1e-9
    assert abs(damped[-1]) < 1e-6 and abs(rings[-1]) < 1e-6  # both settle on it
    root = 1.0 - 4.0 / substeps  # h/Δt = (1/60/S) / (1/240)
    assert _double_root_residual(damped, root) < 1e-9
    assert _double_root_residual(rings, root) > 1e-3


@pytest.mark.parametrize(
    ("direction", "root"),
    [((1.0, 0.0), 0.75), ((0.0, 1.0), 0.5)],
    ids=["across the side", "along it"],
)
def test_critical_damping_beside_a_side_uses_each_directions_own_step(
    direction: tuple[float, float], root: float
) -> None:
    """Beside a side (normal +x) with the law's Δt along it half its Δt across
    (``physics.stiff_tangent``'s form) at 16 sub-steps: h/Δt is 1/4 across and 1/2
    along, and the particle's two roots a sub-step are 1 − h/Δt of its direction."""
    damped = _run_on(16, True, direction, normal=(1.0, 0.0), tangent_dt=1 / 480)
    rings = _run_on(16, False, direction, normal=(1.0, 0.0), tangent_dt=1 / 480)
    assert damped.max() > 1e-6 and damped.min() > -1e-9
    assert _double_root_residual(damped, root) < 1e-9
    assert _double_root_residual(rings, root) > 1e-3
