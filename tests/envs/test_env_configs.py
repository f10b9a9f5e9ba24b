"""Environment configuration files: they load, match the built-in defaults, and bad
keys name the key and the file."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest

from graspenv.config import ConfigError, SceneConfig, read_config_file, to_dict
from graspenv.envs.grasp_env import load_env_config
from graspenv.tasks.library import TASKS

CONFIGS = Path(__file__).resolve().parents[2] / "envs_configs"


def _file(task: str) -> Path:
    return CONFIGS / (re.sub(r"(?<!^)(?=[A-Z])", "_", task).lower() + ".toml")


@pytest.mark.parametrize("name", list(TASKS))
def test_each_file_equals_the_built_in_defaults(name: str) -> None:
    task = TASKS[name]
    scene, config, controller, reward = load_env_config(task, _file(name))
    assert scene == SceneConfig()
    for loaded, default in (
        (config, task.default_config),
        (controller, task.default_controller),
        (reward, task.default_reward),
    ):
        for key, value in to_dict(default).items():
            if isinstance(value, str):
                assert to_dict(loaded)[key] == value, key
            else:
                assert to_dict(loaded)[key] == pytest.approx(value, rel=1e-9), key


@pytest.mark.parametrize("name", list(TASKS))
def test_each_file_lists_exactly_its_tasks_settings(name: str) -> None:
    task = TASKS[name]
    keys = set(read_config_file(_file(name))["task"])
    assert keys == {f.name for f in dataclasses.fields(task.config_type)}


@pytest.mark.parametrize(
    ("task", "key", "value"),
    [
        ("TurnInPlace", "hold_steps", "30"),
        ("SqueezeSlide", "ball_speed", "[0.4, 0.5]"),
        ("SqueezeHold", "ball_speed", "[0.4, 0.5]"),
        ("CatchBall", "force", "[0.5, 2.0]"),
    ],
)
def test_another_tasks_key_names_key_and_file(
    tmp_path: Path, task: str, key: str, value: str
) -> None:
    path = tmp_path / "env.toml"
    path.write_text(f"[task]\n{key} = {value}\n")
    with pytest.raises(ConfigError) as err:
        load_env_config(TASKS[task], path)
    assert f"task.{key}" in str(err.value) and str(path) in str(err.value)


def test_unknown_key_names_key_and_file(tmp_path: Path) -> None:
    path = tmp_path / "env.toml"
    path.write_text("[controller]\nn_finger = 3\n")
    with pytest.raises(ConfigError) as err:
        load_env_config(TASKS["TurnInPlace"], path)
    assert "controller.n_finger" in str(err.value) and str(path) in str(err.value)


def test_bad_value_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "env.toml"
    path.write_text("[task]\nmass = [0.3, 0.1]\n")
    with pytest.raises(ConfigError, match=r"task\.mass") as err:
        load_env_config(TASKS["TurnInPlace"], path)
    assert str(path) in str(err.value)


def test_objects_are_drawn_by_the_task() -> None:
    with pytest.raises(ConfigError, match="drawn per episode"):
        load_env_config(TASKS["TurnInPlace"], {"objects": []})


def test_scene_tables_reach_the_scene() -> None:
    scene, *_ = load_env_config(TASKS["TurnInPlace"], {"physics": {"substeps": 6}})
    assert scene.physics.substeps == 6
