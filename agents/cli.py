"""The ``graspenv train``, ``eval`` and ``compare`` commands.

graspenv never imports agents: these commands reach the ``graspenv`` command through
the ``graspenv.commands`` entry-point group (``pyproject.toml``), each an ``add``
function taking argparse's sub-parser table. The ``graspenv`` command imports this
module whatever it is asked to do, so it imports no command's modules itself (not
stable-baselines3 or torch above all): each command imports what it needs when it
runs. User errors raise ``ValueError`` or
``FileNotFoundError``, which the ``graspenv`` command prints as one line.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import TypedDict

from graspenv.cli import say, wrote

__all__ = ["add_compare", "add_eval", "add_train", "add_tune"]


def _add_ray(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--ray",
        action="store_true",
        help="run batches of episodes as Ray tasks (a local instance on this machine's cores)",
    )
    p.add_argument(
        "--address",
        default=None,
        metavar="HOST:PORT",
        help="with Ray: an existing cluster (`ray start --head` prints it; implies --ray)",
    )


def _add_episodes(p: argparse.ArgumentParser, first_seed: int | None, seed_help: str) -> None:
    """What eval and compare measure over: ``--episodes`` seeded episodes, the first
    with seed ``--seed`` (:func:`_check_episodes` checks the count)."""
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--seed", type=int, default=first_seed, help=seed_help)


def _check_episodes(episodes: int) -> None:
    if episodes < 1:
        raise ValueError(f"--episodes must be at least 1, got {episodes}")


def _add_baseline(p: argparse.ArgumentParser, seed_help: str) -> None:
    """What naming a baseline takes: train and tune share it."""
    p.add_argument("--env", required=True, help="environment id, e.g. graspenv/TurnInPlace-v0")
    p.add_argument("--algo", required=True, choices=("ppo", "sac"))
    p.add_argument(
        "--config", default=None, help="hyperparameter file (default: agents/hyperparams/ALGO.yml)"
    )
    p.add_argument("--seed", type=int, default=0, help=seed_help)


class Baseline(TypedDict):
    """The baseline :func:`_add_baseline`'s options name, as train's and tune's
    keyword arguments."""

    env_id: str
    algo: str
    seed: int
    config: str | None


def _baseline(args: argparse.Namespace) -> Baseline:
    return Baseline(env_id=args.env, algo=args.algo, seed=args.seed, config=args.config)


def _train(args: argparse.Namespace) -> int:
    # Here, not at the top: train imports stable-baselines3 and torch (seconds), which
    # every other `graspenv` command would pay for on start; rich is in the training
    # extra only.
    import rich

    from .train import train

    # stable-baselines3's progress bar draws on rich's shared console: on stderr, like
    # every progress line of `graspenv`, so that stdout keeps only the result.
    rich.reconfigure(stderr=True)

    result = train(
        **_baseline(args),
        out=args.out,
        steps=args.steps,
        progress=say,
        eval_freq=args.eval_freq,
        eval_episodes=args.eval_episodes,
    )
    print(result.text())
    return 0


def add_train(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "train",
        help="train a PPO or SAC baseline with rl-baselines3-zoo (prints the zoo command)",
    )
    _add_baseline(p, "seeds the zoo's run")
    p.add_argument("--out", default="runs/train", help="the zoo's log folder")
    p.add_argument("--steps", type=int, default=None, help="override n_timesteps")
    p.add_argument(
        "--eval-freq", type=int, default=5_000, help="steps between evaluations (-1: none)"
    )
    p.add_argument("--eval-episodes", type=int, default=10, help="episodes per evaluation")
    p.set_defaults(run=_train)


def _progress(label: str) -> Callable[[int, int], None]:
    def report(done: int, total: int) -> None:
        if done == total or done % max(total // 10, 1) == 0:
            say(f"[{done}/{total}] {label}")

    return report


def _eval(args: argparse.Namespace) -> int:
    # The commands import their modules when they run, not here: this module is
    # imported by every `graspenv` command, and evaluate and compare bring the
    # environments and the compiled kernels (they made `graspenv --help` take 2.5
    # times as long).
    from .evaluate import FIRST_SEED, evaluate, summary_table
    from .loading import load_agent

    _check_episodes(args.episodes)
    first = FIRST_SEED if args.seed is None else args.seed
    agent = load_agent(args.agent, first)
    env_id = args.env or agent.home
    if env_id is None:
        raise ValueError(f"--env is needed for agent {args.agent!r}")
    seeds = range(first, first + args.episodes)
    report = _progress(f"{agent.label} on {env_id}")
    if args.ray or args.address:
        if args.video:
            raise ValueError("--video records locally: run it without --ray")
        from .distributed import evaluations

        found, _ = evaluations([(env_id, args.agent)], seeds, args.config, args.address)
        result = found[env_id, args.agent]
    else:
        result = evaluate(env_id, agent, seeds, args.config, report, args.video)
    print(summary_table([result.summary()]))
    out = Path(args.out or f"runs/eval/{env_id.split('/')[-1]}-{agent.label.split(' ')[0]}")
    return wrote([*result.write(out), *([Path(args.video)] if args.video else [])])


def add_eval(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "eval",
        help="measure an agent over seeded episodes (success with 95 %% CI, stability; CSV/JSON)",
    )
    p.add_argument("--env", default=None, help="environment id (default: the agent's own)")
    p.add_argument(
        "--agent",
        required=True,
        help="scripted:NAME, random, still, a model, or a run folder "
        "(graspenv train's or a plain zoo run's)",
    )
    _add_episodes(p, None, "first episode seed (default 1000)")
    p.add_argument("--config", default=None, help="environment file (default: built-in)")
    p.add_argument("--out", default=None, help="folder for episodes.csv and summary.json")
    p.add_argument("--video", default=None, help="record the first episode (.mp4 or .gif)")
    _add_ray(p)
    p.set_defaults(run=_eval)


def _compare(args: argparse.Namespace) -> int:
    from .compare import compare  # as in _eval

    _check_episodes(args.episodes)
    result = compare(
        args.env,
        args.agent,
        args.episodes,
        args.seed,
        Path(args.out),
        progress=say,
        workers=args.workers,
        ray=args.ray,
        address=args.address,
    )
    print(result.table)
    return wrote(result.files)


def add_compare(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "compare",
        help="the strategy benchmark: agents × environments, Markdown table and bar chart",
    )
    p.add_argument("--env", action="append", help="environment id (repeatable; default all)")
    p.add_argument(
        "--agent",
        action="append",
        help="agent spec (repeatable; default every scripted strategy, the shipped "
        "learned policies and random)",
    )
    _add_episodes(p, 1000, "first episode seed")
    p.add_argument("--out", default="runs/compare", help="folder for the table, CSV and chart")
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        help="processes at once (default: one per core; with --ray, the local instance's CPUs)",
    )
    _add_ray(p)
    p.set_defaults(run=_compare)


def _tune(args: argparse.Namespace) -> int:
    from .tune import tune  # as in _eval: Ray, stable-baselines3 and torch load here

    result = tune(
        **_baseline(args),
        space_file=args.space,
        trials=args.trials,
        out=args.out,
        address=args.address,
        say=say,
    )
    print(f"best of {result.trials} trials: success {result.best_success:.2f}")
    return wrote(result.files)


def add_tune(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "tune",
        help="a hyperparameter sweep of a baseline with Ray Tune (ASHA; best.yml for train)",
    )
    _add_baseline(p, "every trial's training seed")
    p.add_argument(
        "--space",
        required=True,
        help="search space file (e.g. agents/hyperparams/tune/sac.toml)",
    )
    p.add_argument("--trials", type=int, default=8, help="configurations to draw")
    p.add_argument("--out", default="runs/tune", help="folder for trials, sweep.csv, best.yml")
    p.add_argument("--address", default=None, metavar="HOST:PORT", help="an existing Ray cluster")
    p.set_defaults(run=_tune)
