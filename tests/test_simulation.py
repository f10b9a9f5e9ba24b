"""The public contract of make_simulation / Simulation (docs/design.md, section 5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import graspenv
from graspenv.bench.interactions import BOX, CLEARANCE, FINGER_RADIUS
from graspenv.config import FIDELITY_PRESETS, PRESET_DRIFT_MM, SceneConfig, load_config
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


# -- per-episode scenes, disturbances, 3-D views and contact bookkeeping ---------------

# Another episode's objects: a taller, heavier, grippier box and a ball beside it.
OTHER_OBJECTS = [
    {"name": "box", "shape": "box", "size": [0.06, 0.05, 0.04], "mass": 0.3, "friction": 0.7},
    {"name": "ball", "shape": "sphere", "size": [0.015], "position": [0.12, 0.1]},
]


def _run(sim: Simulation, masks: list[np.ndarray]) -> np.ndarray:
    for mask in masks:
        sim.step(mask)
    poses = [np.concatenate(sim.object_pose(name)) for name in sim.object_names]
    return np.concatenate([*poses, sim.particle_positions().ravel()])


def test_reset_to_another_scene_matches_a_new_simulation() -> None:
    scene = graspenv.load_config(None, objects=OTHER_OBJECTS, proxy={"stack_layers": 2})
    with Simulation(scene) as fresh:
        masks = _pinch_masks(fresh)
        expected = _run(fresh, masks)
    # The episode before used another proxy method and other objects.
    with graspenv.make_simulation(proxy={"method": "rigid"}) as sim:
        surface = sim.surface
        _run(sim, masks[:30])
        sim.reset(scene)
        assert sim.config == scene and sim.frame_index == 0
        assert sim.object_names == ("box", "ball")
        assert sim.surface is surface  # same surface section: kept
        assert _run(sim, masks).tobytes() == expected.tobytes()
        # The plain reset now restores the new scene. It is the cheap reset, not
        # guaranteed bit-identical once particles turn a box (PhysicsWorld.reset):
        # bit-identical through the squeeze, within 1 mm (0.68 mm) at the end.
        sim.reset()
        assert sim.object_names == ("box", "ball")
        assert _run(sim, masks[:30]).tobytes() == _run_fresh(scene, masks[:30]).tobytes()
        sim.reset()
        np.testing.assert_allclose(_run(sim, masks), expected, rtol=0.0, atol=1e-3)


def _run_fresh(scene: SceneConfig, masks: list[np.ndarray]) -> np.ndarray:
    with Simulation(scene) as sim:
        return _run(sim, masks)


def test_reset_to_the_same_scene_rebuilds_it_bit_for_bit() -> None:
    # A turned box squeezed by particles: the case in which the cheap reset (no
    # scene) is not bit-identical to a fresh start.
    objects = [{"name": "box", "shape": "box", "size": [0.06, 0.05, 0.03], "yaw": 0.6}]
    scene = graspenv.load_config(None, objects=objects)
    with Simulation(scene) as fresh:
        masks = _pinch_masks(fresh, 30)
        expected = _run(fresh, masks)
    with Simulation(scene) as sim:
        _run(sim, masks)
        sim.reset(sim.config)
        assert _run(sim, masks).tobytes() == expected.tobytes()


def test_reset_with_another_surface_replaces_the_surface() -> None:
    with graspenv.make_simulation() as sim:
        scene = graspenv.load_config(None, surface={"resolution": [320, 240], "fps": 30.0})
        sim.reset(scene)
        assert sim.surface.resolution == (320, 240) and sim.surface.fps == 30.0
        assert sim.world.frame_dt == pytest.approx(1 / 30)
        assert sim.step(np.zeros((240, 320), np.uint8)).n_particles == 0
        with pytest.raises(ValueError, match=r"\(240, 320\)"):
            sim.step(np.zeros((480, 640), np.uint8))


def test_set_object_state_and_apply_force_pass_through() -> None:
    ball = {"name": "ball", "shape": "sphere", "size": [0.02], "mass": 0.1}
    with graspenv.make_simulation(objects=[ball]) as sim:
        empty = np.zeros(sim.surface.shape, np.uint8)
        sim.set_object_state(
            "ball", position=[-0.1, 0.0], linear_velocity=[0.2, 0, 0], rolling=True
        )
        sim.step(empty)
        linear, angular = sim.object_velocity("ball")
        assert linear[0] == pytest.approx(0.2, rel=1e-3)  # rolls on without slowing
        assert angular[1] == pytest.approx(0.2 / 0.02, rel=1e-3)
        sim.apply_force("ball", [0.0, 0.6, 0.0])  # for the next frame only
        sim.step(empty)
        pushed, _ = sim.object_velocity("ball")
        # A free push would give F·Δt/m = 0.1 m/s; the table's friction spins the ball
        # up and takes 2/7 of it (a solid sphere that starts rolling).
        assert 0.05 < pushed[1] < 0.1
        sim.step(empty)
        coasting, _ = sim.object_velocity("ball")
        assert coasting[1] == pytest.approx(pushed[1], rel=0.3)
        assert sim.object_pose("ball")[0][0] > -0.1 + 0.2 * 2 / 60 * 0.9


def test_render_view_shows_the_box_on_the_table() -> None:
    with graspenv.make_simulation() as sim:
        image = sim.render_view()
        assert image.shape == (240, 320, 3) and image.dtype == np.uint8
        # The default camera looks at the table centre, where the box is.
        box = image[118:123, 158:163].reshape(-1, 3).mean(axis=0)
        table = image[150:155, 58:63].reshape(-1, 3).mean(axis=0)
        assert np.abs(box - table).sum() > 60
        small = sim.render_view(64, 48, target=(0.0, 0.0, 0.015), distance=0.3, pitch_deg=-30)
        assert small.shape == (48, 64, 3)


@pytest.mark.parametrize("method", ["persistent", "instant", "rigid"])
def test_particles_by_contact_and_particle_velocities(method: str) -> None:
    with graspenv.make_simulation(proxy={"method": method, "stack_layers": 2}) as sim:
        assert sim.particles_by_contact() == {}
        for mask in _pinch_masks(sim, 30):
            report = sim.step(mask)
        groups = sim.particles_by_contact()
        positions, velocities = sim.particle_positions(), sim.particle_velocities()
        assert velocities.shape == positions.shape
        assert np.all(np.isfinite(velocities))
        contacts = sim.contact_report("box")
        if method == "instant":
            assert groups == {}
            return
        assert set(groups) == set(report.contacts.ids) and len(groups) == 2
        if method == "rigid":
            assert all(ids.size == 0 and ids.dtype == np.int64 for ids in groups.values())
            return
        every = np.concatenate(list(groups.values()))
        np.testing.assert_array_equal(np.sort(every), sim.world.pool.active_ids)
        # Per-finger forces: both fingers squeeze the box.
        touching = contacts.particle >= 0
        assert np.all(np.isin(contacts.particle[touching], every))
        per_finger = [
            contacts.normal_force[np.isin(contacts.particle, ids)].sum() for ids in groups.values()
        ]
        assert min(per_finger) > 0.1


def test_make_simulation_takes_the_environments_presets() -> None:
    """fidelity= merges a preset over the scene; explicit overrides win over it."""
    with graspenv.make_simulation(fidelity="fast") as sim:
        # fast is the default's model without CCD (README, "Speed against error").
        assert sim.config == load_config(None, physics={"ccd": False})
    assert load_config(None).physics.ccd
    with graspenv.make_simulation(fidelity="reference", physics={"substeps": 3}) as sim:
        assert sim.config.physics.substeps == 3
        assert sim.config.physics.solver_iterations == 300
    # A scene file's coarser sub-stepping does not carry into its reference.
    coarse = {"physics": {"max_substeps": 8, "substep_travel": 0.002}}
    with graspenv.make_simulation(coarse, fidelity="reference") as sim:
        assert (sim.config.physics.max_substeps, sim.config.physics.substep_travel) == (32, 2.5e-4)
    with graspenv.make_simulation() as sim:
        assert sim.config == load_config(None)
    # auto picks the cheapest preset within the budget (PRESET_DRIFT_MM).
    budget = PRESET_DRIFT_MM["fast"] + 1.0
    with graspenv.make_simulation(fidelity="auto", error_budget=budget) as sim:
        assert sim.config.physics.ccd is FIDELITY_PRESETS["fast"]["physics"]["ccd"] is False
    with pytest.raises(ValueError, match="fidelity must be one of"):
        graspenv.make_simulation(fidelity="best")
    with pytest.raises(ValueError, match="needs error_budget"):
        graspenv.make_simulation(fidelity="auto")
