"""``graspenv serve``: the arguments to a table and its server."""

from __future__ import annotations

import argparse
from collections.abc import Callable

import gymnasium as gym

from graspenv.config import load_config
from graspenv.envs.grasp_env import GraspEnv
from graspenv.live.server import serve
from graspenv.live.table import LiveTable

__all__ = ["run_serve"]


def _port(value: int | None, name: str) -> None:
    if value is not None and not 0 <= value <= 65535:
        raise ValueError(f"{name} must be a port number in [0, 65535], got {value}")


def run_serve(args: argparse.Namespace, say: Callable[[str], None]) -> int:
    _port(args.port, "--port")
    _port(args.tuio, "--tuio")
    if args.env is not None:
        if args.env not in gym.registry:
            known = [k for k in gym.registry if k.startswith("graspenv/")]
            raise ValueError(f"unknown environment {args.env!r}; expected one of {known}")
        env = gym.make(args.env).unwrapped
        if not isinstance(env, GraspEnv):
            raise ValueError(f"{args.env} is not a graspenv environment")
        table = LiveTable(env, record=args.record, seed=args.seed)
        say(f"serving {args.env} (seed {args.seed})")
    else:
        table = LiveTable(load_config(args.config), record=args.record)
    if args.record is not None:
        say(f"recording the masks into {args.record} (graspenv replay {args.record})")
    serve(table, args.host, args.port, args.tuio, announce=say)
    return 0
