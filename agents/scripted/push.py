"""Finger strategies: push a box from behind, rub a card from its top.

Both run in ``fingers`` action mode and read only the state vector. One step moves a
finger by at most ``max_speed`` (0.2 m/s) × 1/30 s ≈ 6.7 mm, so a velocity action is a
wanted displacement divided by :data:`STEP`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .base import ScriptedAgent, State

__all__ = ["GoalSpeed", "PushFromBehind", "RubFromTop"]

#: Finger travel per step at action 1, metres (0.2 m/s over two 60 Hz frames).
STEP = 0.2 / 30.0


def _unit(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``v`` scaled to length 1 (the x axis for a zero vector)."""
    norm = float(np.linalg.norm(v))
    return v / norm if norm > 1e-9 else np.array([1.0, 0.0])


def _left(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``v`` turned 90° anticlockwise."""
    return np.array([-v[1], v[0]])


def _toward(
    position: NDArray[np.float64], target: NDArray[np.float64], limit: float
) -> NDArray[np.float64]:
    """Velocity action that reaches ``target`` in one step, at most ``limit``."""
    move = (target - position) / STEP
    norm = float(np.linalg.norm(move))
    return move * (limit / norm) if norm > limit else move


@dataclass(frozen=True)
class GoalSpeed:
    """How fast (action units) a strategy moves its object towards the goal: ``gain``
    times the distance left (metres), within [``min_speed``, ``max_speed``], so it
    slows as the object nears the goal but never stalls."""

    gain: float
    min_speed: float
    max_speed: float

    def at(self, distance: float) -> float:
        return float(np.clip(self.gain * distance, self.min_speed, self.max_speed))


class PushFromBehind(ScriptedAgent):
    """SidePush: strike the box from the far side of the goal and push it there.

    Phases: ``approach`` (fingers lifted, go side by side to a point ``standoff``
    behind the box on the line goal → box), ``push`` (fingers down, advance along the
    box → goal direction, steering sideways to stay on the line through the box
    centre, slowing as the box nears the goal) and ``done`` (lifted, still) once the
    box is within ``stop_distance`` of the goal. If the box slides off the pushing
    line, the fingers lift and approach again.
    """

    name = "push-from-behind"
    standoff = 0.058
    spread = 0.011
    push_speed = GoalSpeed(gain=12.0, min_speed=0.12, max_speed=0.6)
    lateral_gain = 0.5
    stop_distance = 0.006
    realign = 0.02

    def reset(self) -> None:
        self.phase = "approach"

    def act(self, state: State) -> NDArray[np.float64]:
        box = state.object_xy
        goal = state.goal[:2]
        fingers = state.fingers
        to_goal = goal - box
        distance = float(np.linalg.norm(to_goal))
        forward = _unit(to_goal)
        across = _left(forward)
        offsets = self.spread * np.array([1.0, -1.0])
        velocity = np.zeros_like(fingers)
        touch = 0.0

        if self.phase != "done" and distance < self.stop_distance:
            self.phase = "done"
        elif self.phase == "done" and distance > 2.0 * self.stop_distance:
            self.phase = "approach"

        if self.phase == "approach":
            behind = box - self.standoff * forward
            targets = behind + offsets[:, None] * across
            for i, finger in enumerate(fingers):
                velocity[i] = _toward(finger, targets[i], 1.0)
            if np.max(np.linalg.norm(fingers - targets, axis=1)) < 0.003:
                self.phase = "push"
        elif self.phase == "push":
            touch = 1.0
            centre = fingers.mean(axis=0)
            lateral = float(np.dot(centre - box, across))
            if abs(lateral) > self.realign or float(np.dot(box - centre, forward)) < 0.0:
                self.phase = "approach"
            speed = self.push_speed.at(distance)
            for i, finger in enumerate(fingers):
                side = float(np.dot(finger - box, across)) - offsets[i]
                correction = -self.lateral_gain * side / STEP
                velocity[i] = speed * forward + np.clip(correction, -0.3, 0.3) * across
        action = np.zeros((len(fingers), 3))
        action[:, :2] = velocity
        action[:, 2] = touch if touch > 0 else -1.0
        return action.ravel()


class RubFromTop(ScriptedAgent):
    """TopRub: drag a light card by one finger pressed on its top.

    The finger is placed (lifted) at a contact point in the card's frame, pressed
    down and moved towards the goal. Dragged at its centre the card only translates;
    dragged at a point off to the right of the motion, table friction at the centre
    makes the card swing anticlockwise (to the left for clockwise), so while the yaw
    error is large the contact point is offset ``turn_offset`` sideways. When the
    finger is more than ``replace`` from its wanted contact point (it slipped, or the
    wanted point changed) it lifts and is placed again. A card dragged that way
    turns only a few degrees per centimetre (the fingertip's contact patch resists
    the turn), so when it reaches the goal with its yaw still off by more than
    ``detour_band``, the finger drags it on past the goal by ``detour`` and back,
    turning it on both legs.
    """

    name = "rub-from-top"
    turn_offset = 0.03
    detour = 0.04
    detour_band = math.radians(8.0)
    yaw_band = math.radians(4.0)
    speed = GoalSpeed(gain=10.0, min_speed=0.1, max_speed=0.5)
    replace = 0.012
    placed = 0.002

    def reset(self) -> None:
        self.touching = False
        self.heading = np.array([1.0, 0.0])
        self.waypoint: NDArray[np.float64] | None = None

    def act(self, state: State) -> NDArray[np.float64]:
        card = state.object_xy
        goal = state.goal[:2]
        finger = state.fingers[0]
        yaw_error = math.remainder(float(state.goal[2]) - state.object_yaw, 2 * math.pi)
        if self.waypoint is not None and float(np.linalg.norm(self.waypoint - card)) < 0.005:
            self.waypoint = None
        if (
            self.waypoint is None
            and abs(yaw_error) > self.detour_band
            and float(np.linalg.norm(goal - card)) < 0.004
        ):
            self.waypoint = goal + self.detour * self.heading
        if self.waypoint is not None:
            goal = self.waypoint
        to_goal = goal - card
        distance = float(np.linalg.norm(to_goal))
        if distance > 0.004:
            self.heading = _unit(to_goal)
        offset = np.zeros(2)
        if abs(yaw_error) > self.yaw_band:
            # Right of the motion turns anticlockwise, left clockwise.
            offset = -math.copysign(self.turn_offset, yaw_error) * _left(self.heading)
        contact = card + offset
        miss = float(np.linalg.norm(finger - contact))
        if self.touching and miss > self.replace:
            self.touching = False
        if not self.touching:
            velocity = _toward(finger, contact, 1.0)
            if miss < self.placed:
                self.touching = True
            return np.array([*velocity, -1.0])
        speed = self.speed.max_speed if abs(yaw_error) > self.yaw_band else self.speed.at(distance)
        return np.array([*(speed * self.heading), 1.0])
