from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path

import pytest

from graspenv.config import (
    ConfigError,
    ObjectConfig,
    PhysicsConfig,
    SceneConfig,
    at_fidelity,
    load_config,
    to_dict,
)

CONFIGS = Path(__file__).resolve().parents[1] / "envs_configs"


def test_default_file_matches_built_in_default() -> None:
    assert load_config(CONFIGS / "default.toml") == load_config(None) == SceneConfig()


def test_coarse_file_is_the_benchs_coarse_setting() -> None:
    """envs_configs/coarse.toml (the fast preset until 2026-12-06) and the bench's
    ``coarse`` setting are one setting."""
    from graspenv.bench.frontier import COARSE, SETTINGS

    coarse = load_config(CONFIGS / "coarse.toml")
    assert coarse == load_config(None).replace(**COARSE) == load_config(None, **SETTINGS["coarse"])
    assert coarse != load_config(None)


def test_the_default_scene_file_loads() -> None:
    assert isinstance(load_config(CONFIGS / "default.toml"), SceneConfig)


def test_dict_round_trip() -> None:
    config = load_config(None, proxy={"method": "rigid"})
    assert config.proxy.method == "rigid"
    assert load_config(to_dict(config)) == config


def test_overrides_merge_into_sections() -> None:
    config = load_config(None, proxy={"window": 6}, surface={"fps": 120})
    assert config.proxy.window == 6
    assert config.proxy.method == "persistent"
    assert config.surface.fps == 120.0
    assert config.surface.resolution == (640, 480)


def test_replace_keeps_other_fields() -> None:
    config = SceneConfig().replace(physics={"substeps": 8})
    assert config.physics.substeps == 8
    assert config.proxy == SceneConfig().proxy


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"surfce": {}}, "unknown key 'surfce'"),
        ({"proxy": {"methd": "rigid"}}, "unknown key 'proxy.methd'"),
        ({"proxy": {"method": "magic"}}, "'proxy.method' must be one of"),
        ({"surface": {"size": [0.6]}}, "'surface.size' must have 2 values"),
        ({"surface": {"fps": "fast"}}, "'surface.fps' must be a number"),
        ({"surface": {"fps": -1}}, "surface.fps must be finite and > 0"),
        ({"proxy": {"window": 2.5}}, "'proxy.window' must be an integer"),
        ({"proxy": {"penetration_limit": 1}}, "must be true or false"),
        (
            {"objects": [{"name": "b", "shape": "box", "size": [0.1, 0.1]}]},
            "needs 3 value(s)",
        ),
        (
            {"objects": [{"name": "b", "shape": "cone", "size": [0.1]}]},
            "'objects[0].shape' must be one of",
        ),
        ({"objects": [{"shape": "sphere", "size": [0.1]}]}, "name"),
        (
            {
                "objects": [
                    {"name": "a", "shape": "sphere", "size": [0.02]},
                    {"name": "a", "shape": "sphere", "size": [0.02]},
                ]
            },
            "names must be unique",
        ),
    ],
)
def test_bad_values_name_the_key(data: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=None) as err:
        load_config(data)
    assert message in str(err.value)
    assert "<dict>" in str(err.value)


def test_errors_name_the_file(tmp_path: Path) -> None:
    path = tmp_path / "scene.toml"
    path.write_text('[proxy]\nmethod = "magic"\n')
    with pytest.raises(ConfigError) as err:
        load_config(path)
    assert str(path) in str(err.value)
    assert "proxy.method" in str(err.value)


def test_unparsable_file_is_a_config_error(tmp_path: Path) -> None:
    path = tmp_path / "scene.toml"
    path.write_text("[proxy\n")
    with pytest.raises(ConfigError, match="cannot parse"):
        load_config(path)


def test_missing_file() -> None:
    with pytest.raises(FileNotFoundError, match=r"not-there\.toml"):
        load_config("not-there.toml")


def test_object_height() -> None:
    config = load_config(
        {
            "objects": [
                {"name": "b", "shape": "box", "size": [0.1, 0.1, 0.03]},
                {"name": "s", "shape": "sphere", "size": [0.02]},
                {"name": "c", "shape": "cylinder", "size": [0.02, 0.05]},
            ]
        }
    )
    assert [o.height for o in config.objects] == pytest.approx([0.03, 0.04, 0.05])


def test_stacks_only_where_the_scene_has_round_objects() -> None:
    ball = {"name": "ball", "shape": "sphere", "size": [0.02], "mass": 0.05}
    upright = {"name": "can", "shape": "cylinder", "size": [0.02, 0.05], "mass": 0.1}
    assert load_config(None).proxy.stack_layers == "auto"
    assert load_config(None).stack_layers == 1  # a box: vertical sides
    assert load_config(None, objects=[upright]).stack_layers == 1
    assert load_config(None, objects=[upright, ball]).stack_layers == 3
    assert load_config(None, objects=[ball], proxy={"round_stack_layers": 2}).stack_layers == 2
    assert load_config(None, objects=[ball], proxy={"stack_layers": 1}).stack_layers == 1
    assert load_config(None, proxy={"stack_layers": 2}).stack_layers == 2


@pytest.mark.parametrize("value", [0, "tall", 1.5])
def test_stack_layers_must_be_a_positive_integer_or_auto(value: object) -> None:
    with pytest.raises(ConfigError, match="stack_layers"):
        load_config(None, proxy={"stack_layers": value})


def test_contour_spacing_follows_the_particle_radius() -> None:
    scene = load_config(None)
    assert scene.contacts.spacing == "auto"
    assert scene.contact_settings.spacing == 2 * scene.proxy.particle_radius == 0.004
    bigger = scene.replace(proxy={"particle_radius": 0.003})
    assert bigger.contact_settings.spacing == pytest.approx(0.006)
    fixed = load_config(None, contacts={"spacing": 0.005}, proxy={"particle_radius": 0.003})
    assert fixed.contact_settings.spacing == 0.005
    with pytest.raises(ConfigError, match="spacing"):
        load_config(None, contacts={"spacing": "wide"})


def test_particles_weigh_a_share_of_the_lightest_object() -> None:
    def scene(*masses: float, **proxy: object) -> SceneConfig:
        objects = [
            {"name": f"box{i}", "shape": "box", "size": [0.05, 0.05, 0.03], "mass": m}
            for i, m in enumerate(masses)
        ]
        return load_config(None, objects=objects, proxy=proxy)

    # The 0.2 kg box: 20 g particles, as they were (0.1 · 0.2 / 0.02 is not exactly
    # 1 in binary; the scale is).
    default = load_config(None)
    assert default.particle_scale == 1.0
    assert default.particle_settings == (default.proxy, default.physics)
    light = scene(0.005)
    assert light.particle_scale == pytest.approx(0.025)
    proxy, physics = light.particle_settings
    assert proxy.particle_mass == pytest.approx(0.0005)
    assert proxy.down_force == pytest.approx(0.05 * 0.025)
    assert physics.max_particle_force == pytest.approx(PhysicsConfig().max_particle_force * 0.025)
    assert scene(2.0).particle_scale == pytest.approx(10.0)  # heavier objects too
    proxy, physics = scene(2.0).particle_settings
    assert proxy.particle_mass == pytest.approx(0.2)
    assert physics.max_particle_force == pytest.approx(PhysicsConfig().max_particle_force * 10)
    assert proxy.down_force == pytest.approx(0.05 * 10)
    assert scene(2.0, 0.05).particle_scale == pytest.approx(0.25)  # the lightest
    assert scene(2.0, 5.0).particle_scale == pytest.approx(10.0)  # both heavy
    assert scene(0.005, mass_ratio=0.0).particle_scale == 1.0
    with pytest.raises(ConfigError, match="mass_ratio"):
        load_config(None, proxy={"mass_ratio": -0.1})
    with pytest.raises(ConfigError, match="mass_ratio"):
        load_config(None, proxy={"mass_ratio": float("inf")})


def test_a_tall_object_gets_shorter_sub_steps() -> None:
    """``proxy.effective_mass_ratio``: where a particle outweighs 0.15 of the mass a
    level push at its centre feels, m / (1 + m h² / I), a frame's sub-steps shrink
    by the excess; the particles weigh what ``mass_ratio`` gives. The canonical box
    (20 g particles against the 138 g it feels) and flatter objects keep four."""
    can = ObjectConfig("can", "cylinder", (0.0155, 0.0438), mass=0.015)
    below = 0.0438 / 2 - 0.002
    inertia = 0.015 * (3 * 0.0155**2 + 0.0438**2) / 12
    felt = 1 / (1 / 0.015 + below**2 / inertia)
    assert can.level_push_mass(0.002) == pytest.approx(felt)
    assert felt == pytest.approx(0.0053, abs=1e-4)
    tall = load_config(None, objects=[asdict(can)])
    assert tall.particle_scale == pytest.approx(0.1 * 0.015 / 0.02)
    # 1.5 g particles against 0.15 · 5.3 g: a step of 0.53 of the law's Δt (1/240 s).
    share = 0.15 * felt / 0.0015
    assert tall.sub_steps == math.ceil(4 / share) == 8
    assert tall.replace(proxy={"effective_mass_ratio": 0.0}).sub_steps == 4
    assert tall.replace(physics={"max_substeps": 6}).sub_steps == 6
    assert at_fidelity(tall, "reference").sub_steps == 8
    default = load_config(None)
    box = default.objects[0]
    assert 0.1 * box.mass < 0.15 * box.level_push_mass(0.002) < 0.11 * box.mass
    assert default.sub_steps == 4
    flat = ObjectConfig("flat", "box", (0.06, 0.06, 0.008), mass=0.2)
    assert flat.level_push_mass(0.002) == pytest.approx(0.2, rel=0.05)
    ball = ObjectConfig("ball", "sphere", (0.02,), mass=0.05)
    assert ball.level_push_mass(0.002) == 0.05
    with pytest.raises(ConfigError, match="effective_mass_ratio"):
        load_config(None, proxy={"effective_mass_ratio": -1.0})


@pytest.mark.parametrize(
    "sections",
    [
        {},
        {"objects": [asdict(ObjectConfig("can", "cylinder", (0.02, 0.05), mass=0.05))]},
        {"proxy": {"particle_radius": 0.003}},
        {"contacts": {"spacing": 0.001}},
        {"proxy": {"mass_ratio": 0.0}},
        {"proxy": {"particle_mass": 0.04}},
    ],
    ids=["default", "light-can", "radius-3mm", "spacing-1mm", "no-mass-ratio", "heavy"],
)
def test_the_reference_halves_the_scenes_contour_at_the_same_stiffness_per_length(
    sections: dict,
) -> None:
    """The reference refines the scene in space (``refined_contour``): its own contour
    spacing halved, each particle half as heavy (its mass and the table's press), so
    the particles per metre double and the grip's stiffness per metre of contour
    stays; the outline is smoothed, which the finer contour needs."""
    scene = load_config(None, **sections)
    ref = at_fidelity(scene, "reference")
    assert ref.contacts.contour_spacing(ref.proxy.particle_radius) == pytest.approx(
        scene.contacts.contour_spacing(scene.proxy.particle_radius) / 2
    )
    masses = [c.proxy.particle_mass * c.particle_scale for c in (scene, ref)]
    presses = [c.proxy.down_force * c.particle_scale for c in (scene, ref)]
    assert masses[1] == pytest.approx(masses[0] / 2)
    assert presses[1] == pytest.approx(presses[0] / 2)
    assert (scene.contacts.outline_smoothing, ref.contacts.outline_smoothing) == (0, 6)
    assert ref.physics.substeps == 8 and ref.proxy.particle_radius == scene.proxy.particle_radius


@pytest.mark.parametrize("key", ["close_px", "fill_px", "outline_smoothing"])
@pytest.mark.parametrize("value", [-1, 2.5, True, "wide"])
def test_mask_clean_ups_take_whole_pixels(key: str, value: object) -> None:
    with pytest.raises(ConfigError, match=key):
        load_config(None, contacts={key: value})


def test_the_closing_needs_an_odd_kernel() -> None:
    assert load_config(None, contacts={"close_px": 5}).contacts.close_px == 5
    with pytest.raises(ConfigError, match="odd"):
        load_config(None, contacts={"close_px": 4})


@pytest.mark.parametrize("value", [0, 2, 17, 3.0, True, "three"])
def test_the_vote_takes_an_odd_count_of_frames(value: object) -> None:
    with pytest.raises(ConfigError, match="vote_frames"):
        load_config(None, contacts={"vote_frames": value})
    assert load_config(None, contacts={"vote_frames": 5}).contacts.vote_frames == 5


def test_the_di_table_file_is_the_default_scene_with_the_di_clean_ups() -> None:
    scene = load_config(CONFIGS / "di_table.toml")
    contacts = scene.contacts
    assert (contacts.vote_frames, contacts.close_px, contacts.fill_px) == (3, 5, 2)
    assert scene.replace(contacts={"vote_frames": 1, "close_px": 0, "fill_px": 0}) == (
        SceneConfig()
    )


@pytest.mark.parametrize("value", [0.0, -0.25, 1.5])
def test_the_ccd_sphere_is_a_share_of_the_particle(value: float) -> None:
    with pytest.raises(ConfigError, match=r"physics.ccd_sphere must be in \(0, 1\]"):
        load_config(None, physics={"ccd_sphere": value})
    assert load_config(None, physics={"ccd_sphere": 1.0}).physics.ccd_sphere == 1.0
