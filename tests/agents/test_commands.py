"""`graspenv eval` and `compare` outputs, and one-line errors for bad arguments."""

from __future__ import annotations

import csv
import json
import re
import subprocess
import sys
from pathlib import Path

import cv2
import pytest

from graspenv.cli import main

TURN = "graspenv/TurnInPlace-v0"
ROOT = Path(__file__).parents[2]


def test_eval_scripted_writes_table_csv_and_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        ["eval", "--agent", "scripted:pinch-and-turn", "--episodes", "3", "--out", str(tmp_path)]
    )
    out = capsys.readouterr().out
    assert code == 0
    assert "| pinch-and-turn | `graspenv/TurnInPlace-v0` |" in out
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["episodes"] == 3 and summary["success_rate"] >= 2 / 3
    assert summary["success_ci_low"] < summary["success_rate"] <= summary["success_ci_high"]
    assert summary["mean_grip_force_n"] > 0.5 and summary["mean_quality"] > 0
    with (tmp_path / "episodes.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [int(r["seed"]) for r in rows] == [1000, 1001, 1002]


def test_eval_random_needs_no_home_but_an_env(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["eval", "--agent", "random", "--episodes", "1"]) == 2
    assert "--env is needed" in capsys.readouterr().err


def test_compare_writes_table_csv_and_chart(tmp_path: Path) -> None:
    code = main(
        [
            "compare",
            "--env",
            TURN,
            "--agent",
            "scripted:pinch-and-turn",
            "--agent",
            "random",
            "--episodes",
            "2",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    table = (tmp_path / "compare.md").read_text().splitlines()
    assert len(table) == 4 and "pinch-and-turn" in table[2] and "random" in table[3]
    with (tmp_path / "compare.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert {r["agent"] for r in rows} == {"pinch-and-turn", "random"}
    chart = cv2.imread(str(tmp_path / "compare.png"))
    assert chart is not None and chart.shape[0] > chart.shape[1] / 2  # two panels


def test_compare_default_plan_runs_each_strategy_on_its_own_task() -> None:
    pytest.importorskip("stable_baselines3")  # the plan loads the shipped policies
    from graspenv_agents.compare import plan
    from graspenv_agents.scripted import STRATEGIES

    pairs = plan(None, None)
    scripted = {(env, spec) for env, spec in pairs if spec.startswith("scripted:")}
    assert scripted == {(env, f"scripted:{name}") for name, (env, *_) in STRATEGIES.items()}
    import graspenv

    for floor in ("random", "still"):
        assert {env for env, spec in pairs if spec == floor} == set(graspenv.ENV_IDS)


BAD_HYPERPARAMS = {
    "malformed": "graspenv/TurnInPlace-v0: [n_steps: 64",
    "not a mapping": "- n_steps",
    "no entry": "graspenv/SqueezeSlide-v0:\n  n_timesteps: 100",
    "entry not a mapping": "graspenv/TurnInPlace-v0: 5",
    "unknown key": "graspenv/TurnInPlace-v0:\n  n_timesteps: 100\n  n_stepz: 64",
    "no n_timesteps": "graspenv/TurnInPlace-v0:\n  n_steps: 64",
    "bad n_timesteps": "graspenv/TurnInPlace-v0:\n  n_timesteps: many",
}


@pytest.mark.parametrize(
    "argv",
    [
        ["train", "--env", "graspenv/Nope-v0", "--algo", "ppo", "--steps", "10"],
        ["train", "--env", TURN, "--algo", "ppo", "--config", "/nonexistent/ppo.yml"],
        ["eval", "--env", "graspenv/Nope-v0", "--agent", "random"],
        ["eval", "--agent", "scripted:juggle"],
        ["eval", "--env", TURN, "--agent", "/nonexistent/model.zip"],
        ["eval", "--agent", "random", "--env", TURN, "--episodes", "0"],
        ["compare", "--env", "graspenv/Nope-v0"],
        ["compare", "--agent", "scripted:juggle"],
    ],
    ids=lambda argv: " ".join(argv[:4]),
)
def test_bad_arguments_end_in_one_line(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"graspenv {argv[0]}: error: ") and "\n" not in err


@pytest.mark.parametrize("case", list(BAD_HYPERPARAMS))
def test_bad_hyperparameter_files_end_in_one_line(
    case: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("stable_baselines3")  # keys are checked against PPO's arguments
    path = tmp_path / "ppo.yml"
    path.write_text(BAD_HYPERPARAMS[case])
    argv = ["train", "--env", TURN, "--algo", "ppo", "--config", str(path), "--out", str(tmp_path)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("graspenv train: error: ") and str(path) in err and "\n" not in err
    assert not (tmp_path / "ppo").exists()


def test_a_model_file_that_is_not_a_model(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("stable_baselines3")  # each algorithm tries to load the file
    path = tmp_path / "model.zip"
    path.write_bytes(b"not a zip")
    assert main(["eval", "--env", TURN, "--agent", str(path), "--episodes", "1"]) == 2
    assert "is not a stable-baselines3" in capsys.readouterr().err


def test_the_command_starts_without_the_training_stack() -> None:
    """Every `graspenv` run builds the parser, which imports the agents' commands: only
    `train`, when it runs, may load stable-baselines3 and torch."""
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "graspenv.cli", "--help"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    commands = set(re.findall(r"^    (\w+) ", done.stdout, re.MULTILINE))
    assert {"train", "eval", "compare", "demo"} <= commands
    imported = {
        line.rsplit("|", 1)[-1].strip()
        for line in done.stderr.splitlines()
        if line.startswith("import time:")
    }
    # The log sees the command's imports (graspenv.cli's own), and the agents' commands
    # import nothing of theirs until one runs.
    assert "graspenv.config" in imported
    assert not {m for m in imported if m.startswith("graspenv_agents.")} - {"graspenv_agents.cli"}
    assert not {m for m in imported if m.split(".")[0] in ("torch", "stable_baselines3")}
