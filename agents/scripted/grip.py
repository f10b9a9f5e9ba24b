"""Grip strategies: squeeze a box from two sides by feel, then turn or carry it.

Both close the grip until each fingertip feels the box (its observed normal force),
then keep the squeeze in a band by nudging the opening: closing blindly drives the
contours more than the penetration margin into the box, where the penetration limit
lifts their particles onto its top and the grip is lost.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .base import ScriptedAgent, State, squeeze_rate

__all__ = ["PinchAndTurn", "SqueezeAndSlide"]

# The force (newtons, weaker finger) past which the box counts as held.
FEEL = 1.0


class PinchAndTurn(ScriptedAgent):
    """TurnInPlace: pinch the box, then turn the grip at a rate proportional to the
    remaining yaw error (goal yaw − box yaw), touching throughout."""

    name = "pinch-and-turn"
    gain = 2.0
    max_rate = 0.5

    def act(self, state: State) -> NDArray[np.float64]:
        force = state.finger_force
        turn = 0.0
        if force.min() > FEEL:
            error = math.remainder(float(state.goal[2]) - state.object_yaw, 2 * math.pi)
            turn = float(np.clip(self.gain * error, -1.0, 1.0)) * self.max_rate
        return np.array([0.0, 0.0, turn, squeeze_rate(force), 1.0])


class SqueezeAndSlide(ScriptedAgent):
    """SqueezeSlide: pinch the box, then move the grip centre towards the goal at a
    speed proportional to the remaining distance."""

    name = "squeeze-and-slide"
    gain = 8.0

    def act(self, state: State) -> NDArray[np.float64]:
        force = state.finger_force
        velocity = np.zeros(2)
        if force.min() > FEEL:
            velocity = np.clip(self.gain * (state.goal[:2] - state.object_xy), -1.0, 1.0)
        return np.array([velocity[0], velocity[1], 0.0, squeeze_rate(force), 1.0])
