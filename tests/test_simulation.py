"""The public contract of make_simulation / Simulation (DESIGN.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import graspenv
from graspenv.bench.interactions import BOX, CLEARANCE, FINGER_RADIUS
from graspenv.simulation import STAGES, Simulation
from graspenv.surface.render import render_mask
from graspenv.surface.scripts import two_finger_pinch


def _pinch_masks(sim: Simulation, frames: int = 55) -> list[np.ndarray]:
    script = two_finger_pinch(
        BOX.position,
        gap=BOX.size[0] + 2 * CLEARANCE,
        finger_radius=FINGER_RADIUS,
        approach=CLEARANCE + 0.003,
        turn=math.pi / 4,
        turn_frames=30,
        slide_frames=0,
    )
    masks = [render_mask(hand, sim.surface) for _, hand in script.frames(sim.surface)]
    return masks[:frames]


def test_default_scene_and_surface() -> None:
    with graspenv.make_simulation() as sim:
        assert sim.object_names == ("box",)
        assert sim.surface.resolution == (640, 480)
        assert sim.surface.size == (0.61, 0.46)
        assert sim.surface.fps == 60.0
        position, quaternion = sim.object_pose("box")
        assert position.shape == (3,) and quaternion.shape == (4,)
        assert position[2] == pytest.approx(0.015, abs=1e-3)  # resting on the table
        linear, angular = sim.object_velocity("box")
        assert linear.shape == (3,) and angular.shape == (3,)


def test_step_reports_contacts_particles_and_stage_times() -> None:
    with graspenv.make_simulation() as sim:
        masks = _pinch_masks(sim, 10)
        reports = [sim.step(mask) for mask in masks]
        last = reports[-1]
        assert last.index == 9
        assert last.n_contacts == 2
        assert last.n_particles == last.command.n_particles > 0
        assert set(last.timings) == set(STAGES)
        assert all(t >= 0.0 for t in last.timings.values())
        assert reports[5].n_new == 0 and reports[5].n_removed == 0


def test_bool_masks_are_accepted() -> None:
    with graspenv.make_simulation() as sim:
        mask = _pinch_masks(sim, 6)[-1]
        assert sim.step(mask != 0).n_contacts == 2


@pytest.mark.parametrize(
    ("mask", "message"),
    [
        (np.zeros((480, 641), np.uint8), r"\(480, 640\).*got shape \(480, 641\)"),
        (np.zeros((480, 640, 3), np.uint8), "got 3-D array"),
        (np.zeros((480, 640), np.float32), "bool or uint8; got dtype float32"),
        ([[0, 1], [1, 0]], "ndarray"),
    ],
)
def test_bad_masks_raise_value_error(mask: object, message: str) -> None:
    with graspenv.make_simulation() as sim, pytest.raises(ValueError, match=message):
        sim.step(mask)  # type: ignore[arg-type]


def test_unknown_object_name() -> None:
    with graspenv.make_simulation() as sim, pytest.raises(KeyError, match="ball"):
        sim.object_pose("ball")


def test_reset_replays_bit_for_bit() -> None:
    with graspenv.make_simulation() as sim:
        masks = _pinch_masks(sim)

        def run() -> np.ndarray:
            for mask in masks:
                sim.step(mask)
            position, quaternion = sim.object_pose("box")
            return np.concatenate([position, quaternion, sim.particle_positions().ravel()])

        first = run()
        sim.reset()
        assert sim.frame_index == 0
        second = run()
    assert np.array_equal(first, second)


def test_two_simulations_agree_bit_for_bit() -> None:
    results = []
    for _ in range(2):
        with graspenv.make_simulation() as sim:
            for mask in _pinch_masks(sim, 40):
                sim.step(mask)
            results.append(np.concatenate(sim.object_pose("box")))
    assert np.array_equal(results[0], results[1])


def test_close_twice_and_closed_use() -> None:
    sim = graspenv.make_simulation()
    sim.close()
    sim.close()
    with pytest.raises(RuntimeError, match="closed"):
        sim.object_pose("box")


@pytest.mark.parametrize("method", ["persistent", "instant", "rigid"])
def test_every_method_turns_the_box_some_way(method: str) -> None:
    with graspenv.make_simulation(proxy={"method": method}) as sim:
        masks = _pinch_masks(sim)
        for mask in masks:
            report = sim.step(mask)
        assert report.n_particles > 0
        position, _ = sim.object_pose("box")
        assert np.all(np.isfinite(position))
        assert abs(position[2] - 0.015) < 0.015  # not thrown off (rigid tilts it)


@pytest.mark.parametrize("matcher", ["exhaustive", "fast"])
def test_both_matchers_hold_the_turn(matcher: str) -> None:
    from graspenv.bench.interactions import turn_in_place

    scene = graspenv.load_config(None, proxy={"matcher": matcher})
    assert abs(turn_in_place(scene)["yaw_error_deg"]) <= 1.0


def test_config_overrides_reach_the_simulation(tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "scene.toml"
    path.write_text(
        '[surface]\nresolution = [320, 240]\n\n[[objects]]\nname = "ball"\n'
        'shape = "sphere"\nsize = [0.02]\n'
    )
    with graspenv.make_simulation(path, proxy={"stack_layers": 3}) as sim:
        assert sim.object_names == ("ball",)
        assert sim.surface.resolution == (320, 240)
        assert sim.config.proxy.stack_layers == 3
        assert sim.step(np.zeros((240, 320), np.uint8)).n_particles == 0
