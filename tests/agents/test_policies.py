"""The learned baselines shipped in agents/policies load and play their task."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from graspenv_agents.compare import POLICIES
from graspenv_agents.evaluate import evaluate
from graspenv_agents.loading import load_agent

pytest.importorskip("stable_baselines3")  # the policies are stable-baselines3 models

FOLDERS = sorted(p for p in POLICIES.iterdir() if (p / "run.json").is_file())


def test_the_learned_baselines_are_shipped() -> None:
    homes = {json.loads((p / "run.json").read_text())["env_id"] for p in FOLDERS}
    assert {
        "graspenv/TurnInPlace-v0",
        "graspenv/SqueezeSlide-v0",
        "graspenv/SqueezeHold-v0",
        "graspenv/SidePush-v0",
        "graspenv/TopRub-v0",
        "graspenv/CatchBall-v0",
    } <= homes
    algos = {json.loads((p / "run.json").read_text())["algo"] for p in FOLDERS}
    assert algos == {"sac", "ppo"}  # an on-policy baseline among them


@pytest.mark.parametrize("folder", FOLDERS, ids=lambda p: p.name)
def test_policy_is_small_and_plays_its_task(folder: Path) -> None:
    assert (folder / "policy.pt").stat().st_size < 2_000_000
    agent = load_agent(str(folder))
    run = json.loads((folder / "run.json").read_text())
    assert agent.home == run["env_id"] and agent.kind == run["algo"].upper()
    result = evaluate(run["env_id"], agent, [5000])
    assert len(result.episodes) == 1 and result.episodes[0].length >= 1


def test_compare_runs_the_learned_policies_in_parallel(tmp_path: Path) -> None:
    """Loading a policy imports torch before the worker pool starts: forked workers
    hung here; the pool now spawns them."""
    from graspenv_agents.compare import compare

    result = compare(None, [str(p) for p in FOLDERS], 1, 1000, tmp_path, workers=2)
    algos = {p.name: json.loads((p / "run.json").read_text())["algo"] for p in FOLDERS}
    expected = {f"{algos[p.name].upper()} ({p.name})" for p in FOLDERS}
    assert {s["agent"] for s in result.summaries} == expected
