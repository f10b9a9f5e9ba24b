"""The behaviour clone's learning curve: a clone per demonstration count, evaluated."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3")
pytest.importorskip("rl_zoo3")
pytestmark = pytest.mark.filterwarnings("ignore:rich is experimental")

ENTRY = """
graspenv/SqueezeSlide-v0:
  n_timesteps: 8
  policy: MlpPolicy
  env_wrapper: graspenv_agents.wrappers.RelativeGoal
  learning_starts: 1000000
  buffer_size: 2000
  batch_size: 32
  policy_kwargs: "dict(net_arch=[16, 16])"
  callback:
    - graspenv_agents.zoo.ScriptedDemonstrations:
        strategy: squeeze-and-slide
        episodes: 50
        behaviour_cloning: {cloning}
"""


def test_a_point_per_count_in_the_csv_and_the_chart(tmp_path: Path) -> None:
    from graspenv_agents.clone_curve import clone_curve

    config = tmp_path / "sac.yml"
    config.write_text(ENTRY.format(cloning=20))
    points = clone_curve(
        "graspenv/SqueezeSlide-v0", tmp_path / "out", counts=(1, 2), seeds=[1000],
        config=config, progress=lambda _line: None,
    )  # fmt: skip
    assert [n for n, _ in points] == [1, 2]
    assert all(rate in (0.0, 1.0) for _, rate in points)  # one episode each
    with (tmp_path / "out" / "clone_curve.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [int(r["demonstrations"]) for r in rows] == [1, 2]
    assert [float(r["success_rate"]) for r in rows] == [rate for _, rate in points]
    assert (tmp_path / "out" / "clone_curve.png").stat().st_size > 1000


def test_an_entry_that_is_not_a_clone_is_refused(tmp_path: Path) -> None:
    from graspenv_agents.clone_curve import clone_curve

    config = tmp_path / "sac.yml"
    config.write_text(ENTRY.format(cloning=0))
    with pytest.raises(ValueError, match="not a clone"):
        clone_curve("graspenv/SqueezeSlide-v0", tmp_path / "out", config=config)
    with pytest.raises(ValueError, match="counts"):
        clone_curve("graspenv/SqueezeSlide-v0", tmp_path / "out", counts=(0,), config=config)
