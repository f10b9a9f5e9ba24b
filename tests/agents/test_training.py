"""`graspenv train` (rl-baselines3-zoo underneath) → `graspenv eval` on a short run,
and the run folder it leaves."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import cv2
import pytest

from graspenv.cli import main

pytest.importorskip("stable_baselines3")
pytest.importorskip("rl_zoo3")
event_accumulator = pytest.importorskip("tensorboard.backend.event_processing.event_accumulator")
# stable-baselines3 silences its progress bar's warning (tqdm's rich bar is marked
# experimental) when imported; pytest restores the warning filters before each test.
pytestmark = pytest.mark.filterwarnings("ignore:rich is experimental")

# Small enough for a few seconds of training, in the zoo's format; the evaluation
# and checkpoint frequencies (`--eval-freq`, and `save_freq` below) make both happen.
SHORT = """
graspenv/TurnInPlace-v0:
  n_timesteps: 1024
  policy: MlpPolicy
  n_envs: 1
  normalize: {normalize}
  env_wrapper: graspenv_agents.wrappers.RelativeGoal
  policy_kwargs: "dict(net_arch=[32, 32])"
{algo_keys}
"""
ALGO_KEYS = {
    "ppo": "  n_steps: 256\n  batch_size: 64\n  n_epochs: 2\n",
    "sac": "  learning_starts: 200\n  batch_size: 64\n  train_freq: 4\n  gradient_steps: 1\n"
    "  buffer_size: 5000\n  callback:\n"
    "    - graspenv_agents.zoo.ScriptedDemonstrations:\n"
    "        strategy: pinch-and-turn\n        episodes: 1\n        behaviour_cloning: 20\n"
    "        dagger: 1\n        dagger_episodes: 1\n        critic_warmup: 20\n",
}


@pytest.fixture(scope="module", params=["ppo", "sac"])
def run_folder(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Path:
    algo = request.param
    root = tmp_path_factory.mktemp(algo)
    config = root / f"{algo}.yml"
    # SAC's demonstrations refuse normalised observations (tested below).
    normalize = "true" if algo == "ppo" else "false"
    config.write_text(SHORT.format(normalize=normalize, algo_keys=ALGO_KEYS[algo]))
    code = main(
        [
            "train",
            "--env",
            "graspenv/TurnInPlace-v0",
            "--algo",
            algo,
            "--config",
            str(config),
            "--seed",
            "3",
            "--out",
            str(root / "runs"),
            "--eval-freq",
            "512",
            "--eval-episodes",
            "2",
        ]
    )
    assert code == 0
    (folder,) = (root / "runs" / algo).iterdir()
    return folder


def test_run_folder_records_everything(run_folder: Path) -> None:
    run = json.loads((run_folder / "run.json").read_text())
    assert run["env_id"] == "graspenv/TurnInPlace-v0" and run["seed"] == 3
    assert run["steps"] >= 1024 and run["wall_time_s"] > 0
    assert run["hyperparams"]["n_timesteps"] == 1024
    assert run["command"].startswith("python -m rl_zoo3.train --algo ")
    assert "--seed 3" in run["command"] and "--gym-packages graspenv" in run["command"]
    assert {"graspenv", "stable-baselines3", "rl_zoo3", "torch", "pybullet"} <= set(run["versions"])
    name = "graspenv-TurnInPlace-v0"
    for file in (f"{name}.zip", "best_model.zip", "policy.pt", "evaluations.npz"):
        assert (run_folder / file).is_file(), file
    assert (run_folder / name / "config.yml").is_file()
    if run["algo"] == "ppo":
        assert (run_folder / "vecnormalize.pkl").is_file()
    rows = (run_folder / "evaluations.csv").read_text().splitlines()
    assert rows[0] == "steps,mean_return,success_rate" and len(rows) >= 3
    curve = cv2.imread(str(run_folder / "learning_curve.png"))
    assert curve is not None and curve.shape[0] > 100


@pytest.mark.parametrize("run_folder", ["sac"], indirect=True)
def test_demonstrations_fill_the_replay_buffer_first(run_folder: Path) -> None:
    """The SAC run's file names the scripted head start; the zoo ran it before the
    first step (its TensorBoard log records what went in)."""
    log = event_accumulator.EventAccumulator(str(_events(run_folder)))
    log.Reload()
    transitions = log.Scalars("demonstrations/transitions")
    assert transitions and transitions[0].value > 10
    for tag in ("demonstrations/cloning_loss", "demonstrations/critic_loss"):
        (loss,) = log.Scalars(tag)
        assert math.isfinite(loss.value), tag
    # The DAgger round ran and was written (a point at round 1); what its labels
    # are is tested in test_pieces.py.
    (rate,) = log.Scalars("demonstrations/dagger_success_rate")
    (dagger_loss,) = log.Scalars("demonstrations/dagger_cloning_loss")
    assert rate.step == 1 and 0.0 <= rate.value <= 1.0 and math.isfinite(dagger_loss.value)


def _events(run_folder: Path) -> Path:
    """The run's TensorBoard event file (``run.json`` names its folder)."""
    run = json.loads((run_folder / "run.json").read_text())
    (events,) = Path(run["tensorboard"]).glob("events.out.tfevents.*")
    return events


#: Scalars each algorithm's run logs (besides the evaluation's and the clock's).
TRAINING_TAGS = {
    "ppo": {"train/loss", "train/entropy_loss", "train/value_loss", "rollout/ep_rew_mean"},
    "sac": {"train/actor_loss", "train/critic_loss", "train/ent_coef"},
}


def test_tensorboard_log_holds_the_training_scalars(run_folder: Path) -> None:
    log = event_accumulator.EventAccumulator(str(_events(run_folder)))
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


def test_eval_reads_a_plain_zoo_run(run_folder: Path, tmp_path: Path) -> None:
    """What `python -m rl_zoo3.train` alone leaves (the final model <ENV>.zip and the
    zoo's <ENV>/ settings, no run.json) is an agent too, with its wrapper and, for
    PPO, its observation statistics."""
    from graspenv_agents.loading import load_agent

    name = "graspenv-TurnInPlace-v0"
    zoo = tmp_path / "zoo_run"
    zoo.mkdir()
    for model in (f"{name}.zip", "best_model.zip"):  # the final model is the one played
        shutil.copy(run_folder / model, zoo / model)
    shutil.copytree(run_folder / name, zoo / name)
    algo = json.loads((run_folder / "run.json").read_text())["algo"]
    assert (zoo / name / "vecnormalize.pkl").is_file() == (algo == "ppo")
    spec = load_agent(str(zoo))
    assert spec.home == "graspenv/TurnInPlace-v0" and spec.kind == algo.upper()
    assert spec.wrapper == "graspenv_agents.wrappers.RelativeGoal"
    # The same model and statistics from either folder play the same episodes.
    summaries = []
    for folder in (zoo, run_folder):
        out = tmp_path / f"eval_{folder.name}"
        assert main(["eval", "--agent", str(folder), "--episodes", "2", "--out", str(out)]) == 0
        summaries.append(json.loads((out / "summary.json").read_text()))
    assert summaries[0]["success_rate"] == summaries[1]["success_rate"]
    assert summaries[0]["mean_return"] == pytest.approx(summaries[1]["mean_return"])


def test_eval_refuses_a_model_on_another_observation_space(
    run_folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        [
            "eval",
            "--agent",
            str(run_folder / "graspenv-TurnInPlace-v0.zip"),
            "--env",
            "graspenv/TopRub-v0",
            "--episodes",
            "1",
        ]
    )
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "shape" in err


@pytest.mark.parametrize(
    ("space_file", "env_id"),
    [("sac.toml", "graspenv/TurnInPlace-v0"), ("ppo.toml", "graspenv/SidePush-v0")],
)
def test_the_committed_search_spaces_sweep_their_entries(space_file: str, env_id: str) -> None:
    """Each search space under agents/hyperparams/tune loads, and sweeps hyperparameters
    that the algorithm's zoo entry for the environment it was drawn for holds."""
    from graspenv_agents.hyperparams import default_file, load_hyperparams
    from graspenv_agents.tune import load_space

    algo = space_file.removesuffix(".toml")
    fixed, space = load_space(default_file(algo).parent / "tune" / space_file)
    entry = load_hyperparams(env_id, algo)
    assert fixed["n_timesteps"] > 0 and set(space) <= set(entry)
    if algo == "ppo":  # SidePush's entry is the sweep's best trial (docs/baselines.md)
        for name, (kind, bounds) in space.items():
            value = entry[name]
            assert value in bounds if kind == "choice" else bounds[0] <= value <= bounds[1]
