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
    centre, slowing as the box nears the goal) and ``done`` (lifted, still) while the
    box is within ``stop_distance`` of the goal. If the box slides off the pushing
    line, the fingers lift and approach again.

    The phase is read from the state alone, with the touch flags (what the last
    action asked) as its one bit of memory: fingers down and still on the line are
    pushing, fingers up push once they are within ``arrived`` of their places
    behind the box. A strategy that answers from the state alone can label any
    state a learner reaches (DAgger, in ``graspenv_agents.zoo``); one that kept its
    phase from the frames before labelled the same state differently from one
    episode to the next, and no clone fitted those labels.
    """

    name = "push-from-behind"
    standoff = 0.058
    spread = 0.011
    push_speed = GoalSpeed(gain=12.0, min_speed=0.12, max_speed=0.6)
    lateral_gain = 0.5
    stop_distance = 0.006
    realign = 0.02
    arrived = 0.003
    #: The phase of the last action (for reading; nothing depends on it).
    phase = "approach"

    def _phase(
        self, state: State, forward: NDArray[np.float64], places: NDArray[np.float64]
    ) -> str:
        box, fingers = state.object_xy, state.fingers
        if bool(np.all(state["finger_touching"] > 0.5)):
            centre = fingers.mean(axis=0)
            lateral = float(np.dot(centre - box, _left(forward)))
            on_line = abs(lateral) <= self.realign and float(np.dot(box - centre, forward)) >= 0
            return "push" if on_line else "approach"
        near = float(np.max(np.linalg.norm(fingers - places, axis=1))) < self.arrived
        return "push" if near else "approach"

    def act(self, state: State) -> NDArray[np.float64]:
        box = state.object_xy
        fingers = state.fingers
        to_goal = state.goal[:2] - box
        distance = float(np.linalg.norm(to_goal))
        forward = _unit(to_goal)
        across = _left(forward)
        # Where the fingers start a push: side by side, behind the box.
        offsets = self.spread * np.array([1.0, -1.0])
        places = box - self.standoff * forward + offsets[:, None] * across
        done = distance < self.stop_distance
        self.phase = "done" if done else self._phase(state, forward, places)
        velocity = np.zeros_like(fingers)
        if self.phase == "approach":
            for i, (finger, target) in enumerate(zip(fingers, places, strict=True)):
                velocity[i] = _toward(finger, target, 1.0)
        elif self.phase == "push":
            speed = self.push_speed.at(distance)
            for i, finger in enumerate(fingers):
                side = float(np.dot(finger - box, across)) - offsets[i]
                correction = -self.lateral_gain * side / STEP
                velocity[i] = speed * forward + np.clip(correction, -0.3, 0.3) * across
        action = np.zeros((len(fingers), 3))
        action[:, :2] = velocity
        action[:, 2] = 1.0 if self.phase == "push" else -1.0
        return action.ravel()


class RubFromTop(ScriptedAgent):
    """TopRub: drag a light card by one finger pressed on its top.

    The finger is placed (lifted) at a contact point in the card's frame, pressed
    down and moved towards its target. Dragged at its centre the card only
    translates; dragged at a point off to the right of the motion, table friction at
    the centre makes the card swing anticlockwise (to the left for clockwise), so
    while the yaw error is large the contact point is offset ``turn_offset``
    sideways. When the finger is more than ``replace`` from its wanted contact point
    (it slipped, or the wanted point changed) it lifts and is placed again.

    A card dragged that way turns only a few degrees per centimetre (the fingertip's
    contact patch resists the turn), so while its yaw is off by more than
    ``detour_band`` and it is within ``detour`` of the goal, the target is not the
    goal but a point ``detour`` beyond it, on the line the card is moving along (on
    the card's side of the goal when it is still): the card is dragged through the
    goal and out, back once it is ``detour`` away, turning on every leg, until its
    yaw is within the band and it is stopped at the goal.

    It answers from the state alone (the touch flag says whether the finger is
    down), so it can label any state a learner reaches. The version before kept the
    detour's waypoint and its heading from frame to frame: 95 of 100 on seeds
    1000–1099, where this one has 96.

    ``turn_offset`` was 30 mm until a particle's contacts formed before it touched
    (``physics.contact_breaking_threshold``): the fingertip's particles no longer
    lose their grip on the card for a sub-step now and then, so the patch resists
    the turn as Coulomb says and an off-centre drag turns the card less (the
    interactions' 20 g rub 2.2° → 0.33°); at 30 mm 80 of seeds 0–99 succeeded,
    at 40 mm 91, at 45 mm 99, at 50 mm 83 (the finger then reaches past the
    smaller cards' edge). At 45 mm the finger presses at or just inside the edge of
    the smallest cards (7 cm).
    """

    name = "rub-from-top"
    turn_offset = 0.045
    detour = 0.04
    detour_band = math.radians(8.0)
    yaw_band = math.radians(4.0)
    speed = GoalSpeed(gain=10.0, min_speed=0.1, max_speed=0.5)
    replace = 0.012
    placed = 0.002
    #: Card speed (m/s) above which its motion says which way the detour goes.
    moving = 0.01

    def _target(self, state: State, yaw_error: float) -> NDArray[np.float64]:
        card, goal = state.object_xy, state.goal[:2]
        from_goal = card - goal
        distance = float(np.linalg.norm(from_goal))
        if abs(yaw_error) <= self.detour_band or distance >= self.detour - 0.005:
            return goal
        velocity = state["object_linear_velocity"][:2]
        if float(np.linalg.norm(velocity)) > self.moving:
            way = _unit(velocity)
        elif distance > 0.001:
            way = from_goal / distance
        else:
            way = np.array([1.0, 0.0])
        return goal + self.detour * way

    def act(self, state: State) -> NDArray[np.float64]:
        card = state.object_xy
        finger = state.fingers[0]
        yaw_error = math.remainder(float(state.goal[2]) - state.object_yaw, 2 * math.pi)
        heading = _unit(self._target(state, yaw_error) - card)
        offset = np.zeros(2)
        if abs(yaw_error) > self.yaw_band:
            # Right of the motion turns anticlockwise, left clockwise.
            offset = -math.copysign(self.turn_offset, yaw_error) * _left(heading)
        contact = card + offset
        miss = float(np.linalg.norm(finger - contact))
        touching = bool(state["finger_touching"][0] > 0.5)
        if miss > self.replace or (not touching and miss >= self.placed):
            return np.array([*_toward(finger, contact, 1.0), -1.0])
        distance = float(np.linalg.norm(state.goal[:2] - card))
        speed = self.speed.max_speed if abs(yaw_error) > self.yaw_band else self.speed.at(distance)
        return np.array([*(speed * heading), 1.0])
