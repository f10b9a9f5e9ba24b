"""The Ray scale-out, run by ``tests/scaleout/test_ray.py`` inside a network namespace
that has only loopback (Ray binds its servers to the machine's address; there it has
no other). Not collected on its own: the file name is not ``test_*``.

A session-scoped local Ray instance with 2 CPUs, dashboard and usage statistics
off; the two-node cluster comes last, after it.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

os.environ["RAY_USAGE_STATS_ENABLED"] = "0"
ray = pytest.importorskip("ray")

from graspenv import cluster  # noqa: E402
from graspenv.cli import main  # noqa: E402
from graspenv_agents.compare import POLICIES, compare  # noqa: E402

ENVS = ["graspenv/TurnInPlace-v0"]
AGENTS = ["random", "scripted:pinch-and-turn", str(POLICIES / "TurnInPlace-bc")]
EPISODES, BATCH = 6, 2


@pytest.fixture(scope="session")
def local_ray() -> Iterator[None]:
    cluster.connect(num_cpus=2)
    assert ray.cluster_resources()["CPU"] == 2
    yield
    ray.shutdown()


@pytest.fixture(scope="session")
def local_table(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    """The same benchmark in this process, no Ray: what every Ray run must give."""
    out = tmp_path_factory.mktemp("local")
    compare(ENVS, AGENTS, EPISODES, 1000, out, workers=1)
    return (out / "compare.csv").read_bytes()


def test_compare_on_ray_gives_the_local_table(
    local_ray: None, local_table: bytes, tmp_path: Path
) -> None:
    compare(ENVS, AGENTS, EPISODES, 1000, tmp_path, ray=True, batch=BATCH)
    assert (tmp_path / "compare.csv").read_bytes() == local_table


def _kill_one_worker(name: str, deadline: float) -> int | None:
    """SIGKILL the first process running the Ray task ``name`` (its process title is
    ``ray::name``), polling until ``deadline``."""
    while time.monotonic() < deadline:
        for entry in Path("/proc").iterdir():
            if not entry.name.isdigit():
                continue
            try:
                title = (entry / "cmdline").read_bytes().split(b"\0")[0].decode()
            except OSError:
                continue
            if title.startswith(f"ray::{name}"):
                os.kill(int(entry.name), signal.SIGKILL)
                return int(entry.name)
        time.sleep(0.05)
    return None


def test_a_killed_worker_does_not_change_the_table(
    local_ray: None, local_table: bytes, tmp_path: Path
) -> None:
    killed: list[int | None] = []
    killer = threading.Thread(
        target=lambda: killed.append(_kill_one_worker("evaluate_batch", time.monotonic() + 120))
    )
    killer.start()
    compare(ENVS, AGENTS, EPISODES, 1000, tmp_path, ray=True, batch=BATCH)
    killer.join(timeout=130)
    assert killed and killed[0] is not None, "no worker was running a batch to kill"
    assert (tmp_path / "compare.csv").read_bytes() == local_table


def test_eval_on_ray_gives_the_local_summary(
    local_ray: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["eval", "--agent", "scripted:pinch-and-turn", "--episodes", "4"]
    assert main([*argv, "--out", str(tmp_path / "local")]) == 0
    assert main([*argv, "--ray", "--out", str(tmp_path / "ray")]) == 0
    local = (tmp_path / "local" / "episodes.csv").read_bytes()
    assert (tmp_path / "ray" / "episodes.csv").read_bytes() == local
    capsys.readouterr()


def test_tune_runs_a_small_sweep(local_ray: None, tmp_path: Path) -> None:
    from graspenv_agents.hyperparams import load_hyperparams
    from graspenv_agents.tune import tune

    space = tmp_path / "space.toml"
    space.write_text(
        "[fixed]\n"
        "n_timesteps = 200\neval_freq = 100\neval_episodes = 1\n"
        "learning_starts = 50\nbuffer_size = 5000\n"
        'callback = [{ "graspenv_agents.zoo.ScriptedDemonstrations" = '
        '{ strategy = "pinch-and-turn", episodes = 2 } }]\n'
        "[space.learning_rate]\nloguniform = [1e-4, 3e-3]\n"
        "[space.gamma]\nchoice = [0.9, 0.95]\n"
    )
    result = tune("graspenv/TurnInPlace-v0", "sac", space, trials=2, out=tmp_path / "tune")
    assert result.trials == 2 and 0.0 <= result.best_success <= 1.0
    # The best configuration in the format training reads, with the swept values.
    settings = load_hyperparams("graspenv/TurnInPlace-v0", "sac", result.best_file)
    assert settings["n_timesteps"] == 200 and settings["gamma"] in (0.9, 0.95)
    assert 1e-4 <= settings["learning_rate"] <= 3e-3
    assert settings["learning_rate"] == result.best_config["learning_rate"]
    assert settings["env_wrapper"] == "graspenv_agents.wrappers.RelativeGoal"  # the rest kept
    # The trials' reporting callback is not part of the best configuration.
    assert settings["callback"] == [
        {
            "graspenv_agents.zoo.ScriptedDemonstrations": {
                "strategy": "pinch-and-turn",
                "episodes": 2,
            }
        }
    ]
    rows = (tmp_path / "tune" / "sweep.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[0].startswith("learning_rate,gamma,success")


def test_bench_on_ray_gives_the_local_errors_and_names_the_node(local_ray: None) -> None:
    from graspenv.bench.frontier import run_bench

    args = (["default", "substeps=2"], ["turn", "slide"])
    local = run_bench(*args)
    remote = run_bench(*args, ray=True)
    assert [(r.setting, r.scenario) for r in remote] == [(r.setting, r.scenario) for r in local]
    for a, b in zip(local, remote, strict=True):
        assert a.errors == b.errors and a.frames == b.frames
        assert a.reference_drift_mm == b.reference_drift_mm or (
            a.reference_drift_mm != a.reference_drift_mm
        )
        assert a.node == "" and "/" in b.node and b.row()["node"] == b.node


def test_two_nodes_run_the_tasks_and_give_the_same_table(
    local_table: bytes, tmp_path: Path
) -> None:
    """Last: it replaces the local instance by a two-node cluster on this machine."""
    from ray.cluster_utils import Cluster

    ray.shutdown()
    nodes = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    try:
        nodes.add_node(num_cpus=1)
        nodes.wait_for_nodes()
        said: list[str] = []
        # Through the head's address, as a user joins a cluster.
        compare(
            ENVS,
            AGENTS,
            EPISODES,
            1000,
            tmp_path,
            progress=said.append,
            address=nodes.address,
            batch=1,
        )
        assert len([n for n in ray.nodes() if n["Alive"]]) == 2
        assert "on 2 Ray node(s)" in said[-1], said
        assert (tmp_path / "compare.csv").read_bytes() == local_table
    finally:
        ray.shutdown()
        nodes.shutdown()
