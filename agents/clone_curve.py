"""A behaviour clone's learning curve: success against the demonstrations it saw.

A clone (the ``clone`` entries of ``agents/hyperparams/sac.yml``) is fitted before its
first environment step, so it has no curve over training steps; what it learns from
is the task's scripted episodes. This trains the entry's clone with the callback's
``episodes`` set to each of a few counts (everything else as the entry says), plays
each on the evaluation seeds and writes ``clone_curve.csv`` and ``clone_curve.png``::

    python -m graspenv_agents.clone_curve --env graspenv/TurnInPlace-v0 \\
        --out agents/policies/TurnInPlace-bc
"""

from __future__ import annotations

import argparse
import copy
import sys
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from graspenv.plots import line_chart

from .evaluate import evaluate
from .hyperparams import default_file, load_hyperparams, write_hyperparams
from .loading import load_agent
from .train import train

__all__ = ["COUNTS", "clone_curve"]

#: Demonstration counts the curve is drawn at, with the entry's own count added
#: when it is not among them (SidePush's clone saw 100).
COUNTS = (1, 2, 5, 10, 20, 50)

_CALLBACK = "graspenv_agents.zoo.ScriptedDemonstrations"


def _demonstrations(entry: dict[str, Any]) -> dict[str, Any]:
    """The keyword arguments of the entry's ScriptedDemonstrations (a clone's)."""
    for callback in entry.get("callback", []):
        if isinstance(callback, dict) and _CALLBACK in callback:
            if not callback[_CALLBACK].get("behaviour_cloning"):
                break
            arguments: dict[str, Any] = callback[_CALLBACK]
            return arguments
    raise ValueError(f"the entry names no {_CALLBACK} with behaviour_cloning: not a clone")


def _with_episodes(entry: dict[str, Any], episodes: int) -> dict[str, Any]:
    """The entry with its ScriptedDemonstrations playing ``episodes`` episodes."""
    entry = copy.deepcopy(entry)
    _demonstrations(entry)["episodes"] = episodes
    return entry


def clone_curve(
    env_id: str,
    out: str | Path,
    counts: Sequence[int] | None = None,
    seeds: Sequence[int] = range(1000, 1030),
    seed: int = 0,
    config: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[tuple[int, float]]:
    """Train the clone of ``env_id``'s SAC entry on each count of demonstrations and
    evaluate it on ``seeds``; write ``clone_curve.csv`` and ``clone_curve.png`` into
    ``out``.

    Args:
        env_id: a graspenv environment id whose entry is a clone.
        out: folder for the CSV and the chart.
        counts: demonstration counts, each >= 1 (default: :data:`COUNTS` and the
            entry's own).
        seeds: evaluation episodes' seeds.
        seed: the training seed.
        config: the SAC hyperparameter file (default ``agents/hyperparams/sac.yml``).
        progress: receives a line per count (default: stderr).

    Returns:
        (demonstrations, success rate) per count.

    Raises:
        ValueError: the entry is not a clone, or a count is below 1.
    """
    if counts is not None and (not counts or min(counts) < 1):
        raise ValueError(f"counts must be >= 1, got {list(counts)}")
    path = Path(config) if config is not None else default_file("sac")
    entry = load_hyperparams(env_id, "sac", path)
    own = int(_demonstrations(entry).get("episodes", 50))  # or stop: not a clone
    if counts is None:
        counts = sorted({*COUNTS, own})
    say = progress or (lambda line: print(line, file=sys.stderr, flush=True))
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    points = []
    with tempfile.TemporaryDirectory() as scratch:
        for count in counts:
            file = write_hyperparams(
                Path(scratch) / f"sac_{count}.yml",
                {env_id: _with_episodes(entry, count)},
                f"{path}, {env_id}, with {count} demonstrations",
            )
            run = train(
                env_id, "sac", seed, config=file, out=Path(scratch) / "runs",
                progress=lambda _line: None, progress_bar=False, eval_freq=-1, save_freq=-1,
            )  # fmt: skip
            rate = evaluate(env_id, load_agent(str(run.folder)), seeds).success_rate
            points.append((count, rate))
            say(f"{count} demonstrations: {100 * rate:.0f} % of {len(seeds)} episodes")
    lines = ["demonstrations,success_rate"] + [f"{n},{rate:.4f}" for n, rate in points]
    (out / "clone_curve.csv").write_text("\n".join(lines) + "\n")
    line_chart(
        {"success rate": ([float(n) for n, _ in points], [rate for _, rate in points])},
        out / "clone_curve.png",
        f"{env_id.split('/')[-1]}: behaviour clone, seeds {seeds[0]}-{seeds[-1]}",
        "scripted demonstrations",
        "success rate",
        ylim=(0.0, 1.0),
    )
    return points


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m graspenv_agents.clone_curve")
    parser.add_argument("--env", required=True, help="environment id with a clone entry")
    parser.add_argument("--out", required=True, help="folder for clone_curve.csv and .png")
    parser.add_argument("--episodes", type=int, default=30, help="evaluation episodes")
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--config", default=None, help="SAC hyperparameter file")
    args = parser.parse_args(argv)
    clone_curve(
        args.env, args.out, seeds=range(1000, 1000 + args.episodes), seed=args.seed,
        config=args.config,
    )  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
