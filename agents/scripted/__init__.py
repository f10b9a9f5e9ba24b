"""Scripted grasp strategies, one or more per environment.

``STRATEGIES`` maps a strategy's name to the environment it plays (id and
``gym.make`` arguments) and its class; measure them with ``graspenv eval`` or
``graspenv compare``. SqueezeSlide has two: a grip from the sides
(``squeeze-and-slide``) and, in ``fingers`` action mode, a push from behind
(``push-to-goal``), so the benchmark can compare them.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from .base import ScriptedAgent
from .grip import PinchAndTurn, SqueezeAndSlide
from .hold_catch import CupAndCatch, FirmHold
from .push import PushFromBehind, RubFromTop

__all__ = ["STRATEGIES", "ScriptedAgent", "Strategy"]


class Strategy(NamedTuple):
    env_id: str
    agent: type[ScriptedAgent]
    env_kwargs: dict[str, Any] = {}  # noqa: RUF012  (never mutated)


STRATEGIES: dict[str, Strategy] = {
    "firm-hold": Strategy("graspenv/SqueezeHold-v0", FirmHold),
    "pinch-and-turn": Strategy("graspenv/TurnInPlace-v0", PinchAndTurn),
    "squeeze-and-slide": Strategy("graspenv/SqueezeSlide-v0", SqueezeAndSlide),
    "push-to-goal": Strategy(
        "graspenv/SqueezeSlide-v0", PushFromBehind, {"action_mode": "fingers"}
    ),
    "push-from-behind": Strategy("graspenv/SidePush-v0", PushFromBehind),
    "rub-from-top": Strategy("graspenv/TopRub-v0", RubFromTop),
    "cup-and-catch": Strategy("graspenv/CatchBall-v0", CupAndCatch),
}
