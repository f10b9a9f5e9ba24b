"""The invariant checker itself: each invariant trips on a state that breaks it and
stays quiet on one that does not (states are set by hand, not simulated)."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

import graspenv
from graspenv.bench.invariants import (
    REBOUND_DEPTH,
    InvariantChecker,
    InvariantsBroken,
    first_difference,
    hand_speed,
    inscribed_radius,
    object_penetration,
    speed_bound,
)
from graspenv.config import ObjectConfig, load_config
from graspenv.simulation import Simulation
from graspenv.surface import Fingertip, Hand

BOX = ObjectConfig(name="box", shape="box", size=(0.06, 0.04, 0.03))
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


@pytest.fixture
def sim() -> Iterator[Simulation]:
    """The default scene: a 6 × 6 × 3 cm box at rest at the table centre."""
    with graspenv.make_simulation() as simulation:
        yield simulation


def _place_particle(sim: Simulation, xyz: tuple[float, float, float]) -> None:
    ids = sim.world.pool.acquire(1)
    sim.world.pool.place(ids, [xyz])


def test_a_resting_scene_keeps_every_invariant(sim: Simulation) -> None:
    checker = InvariantChecker(sim, finger_speed=0.0)
    _place_particle(sim, (0.05, 0.0, sim.config.proxy.particle_radius))
    checker.check()
    checker.assert_ok()
    assert checker.frames == 1
    assert checker.worst.height_margin == pytest.approx(0.0, abs=1e-4)


def test_speed_above_the_bound_is_reported(sim: Simulation) -> None:
    bound = speed_bound(sim.config, 0.1)
    sim.set_object_state("box", linear_velocity=(bound * 1.01, 0.0, 0.0))
    checker = InvariantChecker(sim, finger_speed=0.1)
    checker.check()
    assert checker.broken() == {"speed"}
    assert checker.worst.speed_ratio == pytest.approx(1.01)
    with pytest.raises(InvariantsBroken, match="speed broken by box"):
        checker.assert_ok()
    faster_fingers = InvariantChecker(sim, finger_speed=0.2)
    faster_fingers.check()
    faster_fingers.assert_ok()


def test_spin_above_the_bound_is_reported(sim: Simulation) -> None:
    # The default box's smallest half extent is 15 mm: 150 rad/s is 2.25 m/s there,
    # over the squeeze rebound's 1.68 m/s (7 mm in 1/240 s).
    sim.set_object_state("box", angular_velocity=(0.0, 0.0, 150.0))
    checker = InvariantChecker(sim, finger_speed=0.0)
    checker.check()
    assert checker.broken() == {"spin"}


def test_a_dropped_object_is_allowed_its_free_fall_speed(sim: Simulation) -> None:
    # 0.5 m below its start (off the table): up to sqrt(2 g 0.5) = 3.1 m/s more.
    checker = InvariantChecker(sim, finger_speed=0.0)
    sim.set_object_state("box", position=(0.5, 0.0, -0.485), linear_velocity=(0.0, 0.0, -3.0))
    checker.check()
    checker.assert_ok()
    # Started down there, it has not fallen: no allowance.
    started_low = InvariantChecker(sim, finger_speed=0.0)
    started_low.check()
    assert started_low.broken() == {"speed"}


def test_an_object_sunk_into_the_table_is_reported(sim: Simulation) -> None:
    checker = InvariantChecker(sim, finger_speed=0.0)
    sim.set_object_state("box", position=(0.0, 0.0, 0.015 - 0.003))
    checker.check()
    assert checker.broken() == {"tunnelling"}
    assert checker.worst.height_margin == pytest.approx(-0.003)


def test_an_object_at_or_past_the_edge_is_not_judged_for_sinking(sim: Simulation) -> None:
    checker = InvariantChecker(sim, finger_speed=0.0)
    edge = sim.surface.size[0] / 2
    sim.set_object_state("box", position=(edge - 0.01, 0.0, 0.0))
    checker.check()
    sim.set_object_state("box", position=(edge + 0.2, 0.0, -0.7))
    checker.check()
    assert "tunnelling" not in checker.broken()
    assert checker.worst.height_margin == math.inf


def test_a_particle_inside_an_object_is_reported(sim: Simulation) -> None:
    checker = InvariantChecker(sim, finger_speed=0.0)
    # 1.5 mm into the box's +x face at half height: the sphere overlaps 3.5 mm.
    _place_particle(sim, (0.0285, 0.0, 0.015))
    checker.check()
    assert checker.broken() == {"inside_object"}
    assert checker.worst.deepest_in_object == pytest.approx(0.0035)


def test_a_particle_touching_an_object_is_not_inside_it(sim: Simulation) -> None:
    checker = InvariantChecker(sim, finger_speed=0.0)
    _place_particle(sim, (0.0315, 0.0, 0.015))  # 0.5 mm overlap: a squeeze
    checker.check()
    checker.assert_ok()
    assert checker.worst.deepest_in_object == pytest.approx(0.0005)


def test_a_particle_below_the_table_is_reported_off_the_table_it_is_not(sim: Simulation) -> None:
    checker = InvariantChecker(sim, finger_speed=0.0)
    _place_particle(sim, (0.2, 0.1, 0.0))  # 2 mm below where it would rest
    _place_particle(sim, (0.4, 0.0, -0.3))  # past the edge, falling
    checker.check()
    assert checker.broken() == {"below_table"}
    assert checker.worst.lowest_particle == pytest.approx(-0.002)
    assert "particle" in checker.violations[0].subject


def test_a_non_finite_state_is_reported_and_nothing_else_judged(
    sim: Simulation, monkeypatch: pytest.MonkeyPatch
) -> None:
    checker = InvariantChecker(sim, finger_speed=0.0)
    nan = np.full(3, np.nan)
    monkeypatch.setattr(sim, "object_velocity", lambda name: (nan, np.zeros(3)))
    checker.check()
    assert checker.broken() == {"finite"}
    assert checker.worst.non_finite == 1
    assert checker.worst.max_speed == 0.0


def test_first_difference_finds_the_first_differing_frame() -> None:
    poses = np.zeros((5, 2, 7))
    assert first_difference(poses, poses.copy()) is None
    other = poses.copy()
    other[3, 1, 2] = 1e-12
    assert "frame 3" in str(first_difference(poses, other))
    assert first_difference(poses, poses[:4]) is not None
    # Bit for bit: the same NaN matches, a zero of the other sign does not.
    with_nan = poses.copy()
    with_nan[2, 0, 0] = np.nan
    assert first_difference(with_nan, with_nan.copy()) is None
    signed = poses.copy()
    signed[1, 0, 0] = -0.0
    assert "frame 1" in str(first_difference(poses, signed))


def test_penetration_of_box_sphere_and_cylinder() -> None:
    centres = np.array([[0.031, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.025, 0.0]])
    depth = object_penetration(BOX, np.zeros(3), IDENTITY, centres, 0.002)
    # 1 mm outside the x face, 15 mm inside (the nearest face is z), 5 mm outside y.
    np.testing.assert_allclose(depth, [0.001, 0.017, -0.003], atol=1e-12)
    # Turned 90° about z the 6 cm side lies along y.
    quarter = np.array([0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)])
    turned = object_penetration(BOX, np.zeros(3), quarter, centres[2:], 0.002)
    np.testing.assert_allclose(turned, [0.007], atol=1e-12)
    ball = ObjectConfig(name="ball", shape="sphere", size=(0.02,))
    np.testing.assert_allclose(
        object_penetration(ball, np.zeros(3), IDENTITY, np.array([[0.0, 0.0, 0.021]]), 0.002),
        [0.001],
    )
    can = ObjectConfig(name="can", shape="cylinder", size=(0.01, 0.04))
    points = np.array([[0.012, 0.0, 0.0], [0.0, 0.0, 0.019], [0.013, 0.0, 0.024]])
    np.testing.assert_allclose(
        object_penetration(can, np.zeros(3), IDENTITY, points, 0.002),
        [0.0, 0.003, 0.002 - 0.005],
        atol=1e-12,
    )


def test_inscribed_radius_is_the_lowest_resting_height() -> None:
    assert inscribed_radius(BOX) == pytest.approx(0.015)
    assert inscribed_radius(ObjectConfig(name="b", shape="sphere", size=(0.02,))) == 0.02
    assert inscribed_radius(ObjectConfig(name="c", shape="cylinder", size=(0.01, 0.04))) == 0.01
    assert inscribed_radius(ObjectConfig(name="d", shape="cylinder", size=(0.03, 0.02))) == 0.01


def test_hand_speed_is_the_fastest_point_of_a_touching_shape() -> None:
    hand = Hand()
    tip = Fingertip((0.0, 0.0), radii=(0.01, 0.01), linear_velocity=(0.3, 0.4))
    tip.set_twist((0.3, 0.4), 2.0)
    hand.add("index", tip)
    hand.add("lifted", Fingertip(linear_velocity=(5.0, 0.0)), touching=False)
    assert hand_speed([hand]) == pytest.approx(0.5 + 2.0 * 0.01)
    assert hand_speed([]) == 0.0


def test_speed_bound_adds_the_squeeze_rebound_of_the_control_law() -> None:
    scene = load_config()
    assert speed_bound(scene, 0.1) == pytest.approx(0.1 + REBOUND_DEPTH * 240)
    soft = scene.replace(physics={"control_time": 1 / 30})
    assert speed_bound(soft, 0.1) == pytest.approx(0.1 + REBOUND_DEPTH * 30)
    # Δt is never shorter than the sub-step (1/60 s with one sub-step a frame).
    coarse = scene.replace(physics={"substeps": 1})
    assert speed_bound(coarse, 0.0) == pytest.approx(REBOUND_DEPTH * 60)
    # A looser penetration margin does not loosen the bound.
    loose = scene.replace(proxy={"penetration_margin": 0.05})
    assert speed_bound(loose, 0.1) == speed_bound(scene, 0.1)
