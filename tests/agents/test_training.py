"""`graspenv train` → `graspenv eval` on a short run, and the run folder it leaves."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import pytest

from graspenv.cli import main

pytest.importorskip("stable_baselines3")
event_accumulator = pytest.importorskip("tensorboard.backend.event_processing.event_accumulator")
# stable-baselines3 silences its progress bar's warning (tqdm's rich bar is marked
# experimental) when imported; pytest restores the warning filters before each test.
pytestmark = pytest.mark.filterwarnings("ignore:rich is experimental")

# Small enough for a few seconds of training; the evaluation and checkpoint
# frequencies make both happen within the run.
SHORT = """
[defaults]
n_envs = 1
normalize = true
env_wrapper = "relative_goal"
eval_freq = 512
eval_episodes = 2
checkpoint_freq = 512
{algo_keys}
"""
ALGO_KEYS = {
    "ppo": "n_steps = 256\nbatch_size = 64\nn_epochs = 2\npolicy_kwargs = { net_arch = [32, 32] }",
    "sac": "learning_starts = 200\nbatch_size = 64\ntrain_freq = 4\ngradient_steps = 1\n"
    "buffer_size = 5000\npolicy_kwargs = { net_arch = [32, 32] }\n"
    'demonstrations = "scripted:pinch-and-turn"\ndemo_episodes = 1',
}


@pytest.fixture(scope="module", params=["ppo", "sac"])
def run_folder(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Path:
    algo = request.param
    root = tmp_path_factory.mktemp(algo)
    config = root / f"{algo}.toml"
    config.write_text(SHORT.format(algo_keys=ALGO_KEYS[algo]))
    code = main(
        [
            "train",
            "--env",
            "graspenv/TurnInPlace-v0",
            "--algo",
            algo,
            "--config",
            str(config),
            "--steps",
            "1024",
            "--seed",
            "3",
            "--out",
            str(root / "runs"),
        ]
    )
    assert code == 0
    (folder,) = (root / "runs").iterdir()
    return folder


def test_run_folder_records_everything(run_folder: Path) -> None:
    run = json.loads((run_folder / "run.json").read_text())
    assert run["env_id"] == "graspenv/TurnInPlace-v0" and run["seed"] == 3
    assert run["steps"] >= 1024 and run["wall_time_s"] > 0
    assert run["hyperparams"]["n_timesteps"] == 1024
    assert run["hyperparams"]["eval_episodes"] == 2
    if run["algo"] == "sac":  # one scripted episode went into the replay buffer first
        assert run["demonstrations"]["episodes"] == 1
        assert run["demonstrations"]["transitions"] > 10
    assert {"graspenv", "stable-baselines3", "torch", "pybullet"} <= set(run["versions"])
    for name in ("model.zip", "best_model.zip", "vecnormalize.pkl", "progress.csv"):
        assert (run_folder / name).is_file(), name
    assert list((run_folder / "checkpoints").glob("model_*_steps.zip"))
    rows = (run_folder / "evaluations.csv").read_text().splitlines()
    assert rows[0] == "steps,mean_return,success_rate" and len(rows) >= 3
    curve = cv2.imread(str(run_folder / "learning_curve.png"))
    assert curve is not None and curve.shape[0] > 100


#: Scalars each algorithm's run logs (besides the evaluation's and the clock's).
TRAINING_TAGS = {
    "ppo": {"train/loss", "train/entropy_loss", "train/value_loss", "rollout/ep_rew_mean"},
    "sac": {"train/actor_loss", "train/critic_loss", "train/ent_coef"},
}


def test_tensorboard_log_holds_the_training_scalars(run_folder: Path) -> None:
    (events,) = (run_folder / "tb").glob("events.out.tfevents.*")
    log = event_accumulator.EventAccumulator(str(events))
    log.Reload()
    tags = set(log.Tags()["scalars"])
    algo = json.loads((run_folder / "run.json").read_text())["algo"]
    expected = {"eval/mean_reward", "eval/success_rate", "time/fps"} | TRAINING_TAGS[algo]
    assert expected <= tags, sorted(expected - tags)
    steps = [event.step for event in log.Scalars("eval/mean_reward")]
    assert steps == sorted(steps) and steps[-1] >= 512


def test_eval_accepts_the_trained_model(run_folder: Path, tmp_path: Path) -> None:
    out = tmp_path / "eval"
    code = main(["eval", "--agent", str(run_folder), "--episodes", "2", "--out", str(out)])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["env_id"] == "graspenv/TurnInPlace-v0" and summary["episodes"] == 2
    assert len((out / "episodes.csv").read_text().splitlines()) == 3


def test_eval_refuses_a_model_on_another_observation_space(
    run_folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        [
            "eval",
            "--agent",
            str(run_folder / "model.zip"),
            "--env",
            "graspenv/TopRub-v0",
            "--episodes",
            "1",
        ]
    )
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "shape" in err
