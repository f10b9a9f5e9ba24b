"""Scripted grasp strategies, one or more per environment.

``STRATEGIES`` maps a strategy's name to its environment id and class; run them all
with ``python -m agents.scripted.evaluate``.
"""

from __future__ import annotations

from agents.scripted.base import ScriptedAgent
from agents.scripted.grip import PinchAndTurn, SqueezeAndSlide
from agents.scripted.hold_catch import CupAndCatch, FirmHold
from agents.scripted.push import PushFromBehind, RubFromTop

__all__ = ["STRATEGIES", "ScriptedAgent"]

STRATEGIES: dict[str, tuple[str, type[ScriptedAgent]]] = {
    "firm-hold": ("graspenv/SqueezeHold-v0", FirmHold),
    "pinch-and-turn": ("graspenv/TurnInPlace-v0", PinchAndTurn),
    "squeeze-and-slide": ("graspenv/SqueezeSlide-v0", SqueezeAndSlide),
    "push-from-behind": ("graspenv/SidePush-v0", PushFromBehind),
    "rub-from-top": ("graspenv/TopRub-v0", RubFromTop),
    "cup-and-catch": ("graspenv/CatchBall-v0", CupAndCatch),
}
