"""The ``graspenv`` command.

Sub-commands live in a table, one function and one line each. Commands from other
packages join through the ``graspenv.commands`` entry-point group (an ``add``
function taking the sub-parser table): that is how the repository's agents
(``agents/``, installed as ``graspenv_agents``) add ``train``, ``eval`` and
``compare`` without graspenv importing them (and print through :func:`say` and
:func:`wrote`, as the built-in ones do).
Errors a user can cause end with a one-line message and exit status 2, not a
traceback.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from graspenv import __version__
from graspenv.config import ConfigError

__all__ = ["main", "say", "wrote"]


def say(line: str) -> None:
    """A progress line, on stderr so that stdout keeps only the results."""
    print(line, file=sys.stderr, flush=True)


def wrote(paths: Iterable[str | Path]) -> int:
    """Name each file a command wrote (on stdout, after its results); exit status 0."""
    for path in paths:
        print(f"wrote {path}")
    return 0


def _add_filters(p: argparse.ArgumentParser, **names: str) -> None:
    """Repeatable ``--KEY`` options, each picking one of what ``names[KEY]`` names
    (by default all of them)."""
    for key, what in names.items():
        p.add_argument(f"--{key}", action="append", help=f"one {what} (repeatable); default all")


def _demo(args: argparse.Namespace) -> int:
    from graspenv.demo import run_demo

    result = run_demo(Path(args.out), config=args.config, frames=args.frames)
    print(result.summary())
    return wrote(result.files)


def _add_demo(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="run the main job on the built-in default scene")
    p.add_argument("--out", default="runs/demo", help="folder for what it writes")
    p.add_argument("--config", default=None, help="scene file (default: built-in scene)")
    p.add_argument("--frames", type=int, default=None, help="cut the script short")
    p.set_defaults(run=_demo)


def _interactions(args: argparse.Namespace) -> int:
    from graspenv.bench.interactions import (
        ABLATION_SCENARIOS,
        ABLATIONS,
        METHODS,
        SCENARIOS,
        markdown_table,
        run_all,
    )

    variants = ABLATIONS if args.ablation else METHODS
    scenarios = args.scenario or (ABLATION_SCENARIOS if args.ablation else list(SCENARIOS))
    for name, values, known in (
        ("scenario", args.scenario, SCENARIOS),
        ("method", args.method, variants),
    ):
        for value in values or ():
            if value not in known:
                raise ValueError(f"unknown {name} {value!r}; expected one of {list(known)}")
    total = len(scenarios) * len(args.method or variants)
    done = 0

    def progress(label: str) -> None:
        nonlocal done
        done += 1
        say(f"[{done}/{total}] {label}")

    results = run_all(scenarios, args.method, args.config, progress, variants)
    table = markdown_table(results)
    print(table)
    if args.out:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(table + "\n")
        print(f"wrote {out}", file=sys.stderr)
    return 0


def _add_interactions(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "interactions",
        help="measure the paper's interactions for each proxy method (Markdown table)",
    )
    _add_filters(p, scenario="scenario", method="proxy method")
    p.add_argument("--config", default=None, help="base scene file (default: built-in)")
    p.add_argument("--out", default=None, help="also write the table to this file")
    p.add_argument(
        "--ablation",
        action="store_true",
        help="compare our tracking changes to the paper's plain form (turn and slide)",
    )
    p.set_defaults(run=_interactions)


def _replay(args: argparse.Namespace) -> int:
    from graspenv.replay import DEFAULT_THRESHOLD, replay

    def progress(done: int, total: int | None) -> None:
        say(f"[{done}/{total or '?'}] frames")

    result = replay(
        Path(args.source),
        Path(args.out),
        config=args.config,
        fps=args.fps,
        limit=args.limit,
        progress=progress,
        video=args.video,
        threshold=DEFAULT_THRESHOLD if args.threshold is None else args.threshold,
    )
    print(result.text())
    return wrote(result.files)


def _add_replay(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "replay",
        help="run a folder of mask images or a video through a scene; write an annotated video",
    )
    p.add_argument("source", help="folder of mask images (natural order) or a video file")
    p.add_argument("--out", default="runs/replay", help="folder for what it writes")
    p.add_argument("--config", default=None, help="scene file (default: built-in scene)")
    p.add_argument("--fps", type=float, default=None, help="recording's rate (default: scene's)")
    p.add_argument("--limit", type=int, default=None, help="replay at most this many frames")
    p.add_argument("--video", choices=("mp4", "gif"), default="mp4", help="video format")
    p.add_argument("--threshold", type=int, default=None, help="touched = grey > this (127)")
    p.set_defaults(run=_replay)


def _gallery(args: argparse.Namespace) -> int:
    import graspenv
    from graspenv.envs.gallery import gallery

    return wrote([gallery(graspenv.ENV_IDS, Path(args.out), args.seed)])


def _add_gallery(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("gallery", help="a picture of every environment (PNG)")
    p.add_argument("--out", default="runs/gallery.png", help="PNG file to write")
    p.add_argument("--seed", type=int, default=0, help="episode seed")
    p.set_defaults(run=_gallery)


def _bench(args: argparse.Namespace) -> int:
    from graspenv.bench.frontier import QUICK_SCENARIOS, QUICK_SETTINGS, SETTINGS, run_bench
    from graspenv.bench.results import markdown_table, read_csv, write_outputs
    from graspenv.bench.scenarios import SCENARIOS

    if (args.noise_seeds or args.noise_level) and not (args.noise and args.from_csv is None):
        raise ValueError("--noise-seeds and --noise-level go with --noise (and not --from-csv)")
    if args.sample is not None and not (args.grid and args.from_csv is None and args.sample > 0):
        raise ValueError("--sample N goes with --grid (and not --from-csv), N at least 1")
    if args.speed:
        from graspenv.bench.speed import run_speed

        if args.runs < 1 or args.env_steps < 1:
            raise ValueError(
                f"--runs and --env-steps must be at least 1, got {args.runs} and {args.env_steps}"
            )

        report = run_speed(say, runs=args.runs, env_steps=args.env_steps)
        print(report.markdown())
        return wrote(report.write(Path(args.out)))
    if args.grid or args.noise:
        from graspenv.bench import grid, noise

        module: Any = grid if args.grid else noise
        if args.from_csv is not None:
            results = module.read_csv(Path(args.from_csv))
        else:
            run = grid.run_grid if args.grid else noise.run_noise
            extra: dict[str, Any] = {}
            if args.noise_seeds:
                extra["seeds"] = list(dict.fromkeys(args.noise_seeds))
            if args.noise_level:
                extra["levels"] = list(dict.fromkeys(args.noise_level))
            if args.grid:
                # The maps' seeded places on the table, or the sample's draw.
                extra["seed"] = args.seed
            if args.sample is not None:
                extra["sample"] = args.sample
            results = run(
                config=args.config,
                progress=say,
                workers=args.workers,
                preset=args.preset,
                **extra,
            )
        print(module.summary(results))
        return wrote(module.write_outputs(results, Path(args.out)))
    if args.fuzz is not None:
        from graspenv.bench.fuzz import run_fuzz

        fuzzed = run_fuzz(
            args.fuzz, args.seed, args.workers, say, preset=args.preset, config=args.config
        )
        print(fuzzed.text())
        print(f"wrote {fuzzed.write(Path(args.out) / 'fuzz.csv')}")
        return 1 if fuzzed.failures else 0
    if args.soak is not None:
        from graspenv.bench.soak import soak

        result = soak(args.soak, args.config, say)
        print(result.text())
        print(f"wrote {result.write(Path(args.out) / 'soak.csv')}")
        return 0 if result.flat and result.violations == 0 else 1
    if args.from_csv is not None:
        results = read_csv(Path(args.from_csv))
    else:
        settings = args.setting or (QUICK_SETTINGS if args.quick else list(SETTINGS))
        scenarios = args.scenario or (QUICK_SCENARIOS if args.quick else list(SCENARIOS))
        placements = args.placements or (1 if args.quick else 3)
        replays = args.replays or (2 if args.quick else 3)
        results = run_bench(
            settings,
            scenarios,
            args.config,
            say,
            placements,
            replays,
            ray=args.ray,
            address=args.address,
        )
    print(markdown_table(results))
    if not any(r.scenario == "turn" for r in results):
        print("no pareto.png: its speed axis is the canonical turn's (add --scenario turn)")
    return wrote(write_outputs(results, Path(args.out)))


def _add_bench(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "bench",
        help="speed against error: scenarios × settings, CSV, Markdown table and Pareto plot",
    )
    p.add_argument("--quick", action="store_true", help="a subset that runs in under 2 minutes")
    _add_filters(p, setting="setting", scenario="scenario")
    p.add_argument(
        "--placements",
        type=int,
        default=None,
        help="sub-pixel placements of each scene, errors averaged (default 3; --quick 1)",
    )
    p.add_argument(
        "--replays",
        type=int,
        default=None,
        help="timing runs of each scene; speeds are per-frame minimums (default 3; --quick 2)",
    )
    p.add_argument("--config", default=None, help="base scene file (default: built-in)")
    p.add_argument("--out", default="runs/bench", help="folder for bench.csv, bench.md, pareto.png")
    p.add_argument(
        "--from-csv",
        default=None,
        metavar="CSV",
        help="instead: draw the table and plot again from an earlier run's bench.csv",
    )
    p.add_argument(
        "--soak",
        type=int,
        default=None,
        metavar="FRAMES",
        help="instead: the grasp cycle for FRAMES frames, invariants and memory (soak.csv)",
    )
    p.add_argument(
        "--speed",
        action="store_true",
        help="instead: whole-run speeds, environment steps/s beside panda-gym, resets, "
        "frame cost against contacts and compile times (speed.md, speed.csv, scaling.png)",
    )
    p.add_argument(
        "--grid",
        action="store_true",
        help="instead: accuracy across the grasp space, 91 grasps (grid.csv, grid.md, "
        "grid_*.png heat maps); with --from-csv, draw them again from a grid.csv",
    )
    p.add_argument(
        "--noise",
        action="store_true",
        help="instead: grasps through FTIR- and DI-like sensor noise up to four times the "
        "DI level, with each contact clean-up (noise.csv, noise.md, noise.png); with "
        "--from-csv, draw them again from a noise.csv",
    )
    p.add_argument(
        "--fuzz",
        type=int,
        default=None,
        metavar="N",
        help="instead: N random hard episodes, the stability invariants checked on every "
        "frame (fuzz.csv); exit 1 if any broke",
    )
    p.add_argument(
        "--sample",
        type=int,
        default=None,
        metavar="N",
        help="--grid: instead of the maps, N grasps drawn at random from the whole grasp "
        "space, every parameter at once (grid_sample.png)",
    )
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        help="--fuzz: the first episode's seed; --grid: the cells' places on the table"
        " (with --sample, the draw's)",
    )
    p.add_argument(
        "--noise-seeds",
        type=int,
        nargs="+",
        default=None,
        metavar="SEED",
        help="--noise: the noise seeds, each at a placement of its own (default: 0 1)",
    )
    p.add_argument(
        "--noise-level",
        nargs="+",
        default=None,
        metavar="LEVEL",
        help="--noise: only these levels (clean, ftir, di, 'di x2', 'di x4')",
    )
    p.add_argument(
        "--ray",
        action="store_true",
        help="speed against error: each (setting, scenario) a Ray task; rows name their node",
    )
    p.add_argument(
        "--address", default=None, metavar="HOST:PORT", help="with --ray: an existing cluster"
    )
    p.add_argument(
        "--workers", type=int, default=2, help="--grid, --noise, --fuzz: processes working at once"
    )
    p.add_argument(
        "--preset",
        default="default",
        help="--grid, --noise, --fuzz: the fidelity preset they run at (fast, default, reference)",
    )
    p.add_argument("--runs", type=int, default=3, help="--speed: whole runs of each scene")
    p.add_argument(
        "--env-steps", type=int, default=600, help="--speed: steps per environment measurement"
    )
    p.set_defaults(run=_bench)


def _serve(args: argparse.Namespace) -> int:
    from graspenv.live.cli import run_serve

    return run_serve(args, say)


def _add_serve(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "serve",
        help="a live table in the browser (touch, mouse pinch) and over TUIO",
        description="Serve the table: a page to touch at http://HOST:PORT/, GET /state, "
        "POST /reset, and TUIO 1.1 over UDP with --tuio. Binds to loopback; "
        "--host 0.0.0.0 exposes the table to the network.",
    )
    scene = p.add_mutually_exclusive_group()
    scene.add_argument("--config", default=None, help="scene file (default: the 6 cm box)")
    scene.add_argument("--env", default=None, metavar="ID", help="serve an environment's task")
    p.add_argument("--seed", type=int, default=0, help="--env: the episode's seed")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default: loopback)")
    p.add_argument("--port", type=int, default=8000, help="HTTP port (0: any free one)")
    p.add_argument("--tuio", type=int, default=None, metavar="PORT", help="UDP port for TUIO 1.1")
    p.add_argument("--record", default=None, metavar="DIR", help="write the masks for replay")
    p.set_defaults(run=_serve)


_COMMANDS: tuple[Callable[[argparse._SubParsersAction], None], ...] = (
    _add_demo,
    _add_interactions,
    _add_replay,
    _add_gallery,
    _add_bench,
    _add_serve,
)


def _plugin_commands() -> list[Callable[[argparse._SubParsersAction], None]]:
    """The ``add`` functions registered in the ``graspenv.commands`` group, by name."""
    from importlib.metadata import entry_points

    found = sorted(entry_points(group="graspenv.commands"), key=lambda ep: ep.name)
    adders = []
    for ep in found:
        try:
            adders.append(ep.load())
        except ImportError:  # a registered package that is not importable here
            continue
    return adders


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="graspenv", description="Grasping on an imaging touch table, simulated."
    )
    parser.add_argument("--version", action="version", version=f"graspenv {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in (*_COMMANDS, *_plugin_commands()):
        add(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code: int = args.run(args)
    except (ConfigError, FileNotFoundError, ValueError) as err:
        print(f"graspenv {args.command}: error: {err}", file=sys.stderr)
        return 2
    except ModuleNotFoundError as err:
        extras = {"matplotlib": "plots", "aiohttp": "serve", "pythonosc": "serve", "ray": "ray"}
        hint = (
            f"pip install 'graspenv[{extras[err.name]}]'"
            if err.name in extras
            else "`make train-deps` installs the training extra"
        )
        print(
            f"graspenv {args.command}: error: needs {err.name}, which is not installed ({hint})",
            file=sys.stderr,
        )
        return 2
    return code


if __name__ == "__main__":
    sys.exit(main())
