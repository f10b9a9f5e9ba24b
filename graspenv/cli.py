"""The ``graspenv`` command.

Sub-commands live in a table so later ones (``train``, ``eval``, ``compare``,
``bench``) are one function and one line each. Errors a user can cause end with a
one-line message and exit status 2, not a traceback.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from graspenv import __version__
from graspenv.config import ConfigError

__all__ = ["main"]


def _demo(args: argparse.Namespace) -> int:
    from graspenv.demo import run_demo

    result = run_demo(Path(args.out), config=args.config, frames=args.frames)
    print(result.summary())
    for path in result.files:
        print(f"wrote {path}")
    return 0


def _add_demo(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="run the main job on the built-in default scene")
    p.add_argument("--out", default="runs/demo", help="folder for what it writes")
    p.add_argument("--config", default=None, help="scene file (default: built-in scene)")
    p.add_argument("--frames", type=int, default=None, help="cut the script short")
    p.set_defaults(run=_demo)


_COMMANDS: tuple[Callable[[argparse._SubParsersAction], None], ...] = (_add_demo,)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="graspenv", description="Grasping on an imaging touch table, simulated."
    )
    parser.add_argument("--version", action="version", version=f"graspenv {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in _COMMANDS:
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
    return code


if __name__ == "__main__":
    sys.exit(main())
