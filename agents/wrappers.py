"""Observation wrappers a hyperparameter file may name (the zoo's ``env_wrapper``).

The state vector gives the object's pose and the goal in the table's frame: the
goal's yaw is an absolute angle and the object's orientation a quaternion, so the
quantity a grip policy needs (how far, and which way, still to turn) is a wrapped
difference of angles that a small network learns slowly. :class:`RelativeGoal`
appends that and the other object-relative quantities, computed from the state
vector alone (no privileged simulator state).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from graspenv.geometry import yaw_of

__all__ = ["WRAPPERS", "GoalFrame", "RelativeGoal"]


def _state_layout(env: gym.Env[Any, Any], wrapper: str) -> tuple[dict[str, slice], int]:
    """The state vector's named slices and the hand's finger count, for a wrapper
    that needs ``obs_mode="state"``."""
    unwrapped: Any = env.unwrapped
    if getattr(unwrapped, "obs_mode", None) != "state":
        raise ValueError(f"{wrapper} needs obs_mode='state'")
    layout: dict[str, slice] = dict(unwrapped.observation_layout)
    fingers = layout["finger_positions"]
    return layout, (fingers.stop - fingers.start) // 2


class RelativeGoal(gym.ObservationWrapper[NDArray[np.float32], Any, NDArray[np.float32]]):
    """Appends to a ``"state"`` observation: the goal relative to the object (x, y in
    decimetres; sine and cosine of the remaining turn) and each finger's position
    relative to the object (decimetres)."""

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        super().__init__(env)
        self.layout, self.n_fingers = _state_layout(env, "RelativeGoal")
        unwrapped: Any = env.unwrapped
        # CatchBall's goal is a velocity and a hold, not a pose: nothing to add.
        self.goal_is_pose = bool(getattr(unwrapped.task, "pose_goal", True))
        base = env.observation_space
        assert isinstance(base, spaces.Box)
        extra = 4 + 2 * self.n_fingers
        self.observation_space = spaces.Box(
            np.concatenate([base.low, np.full(extra, -100.0, np.float32)]),
            np.concatenate([base.high, np.full(extra, 100.0, np.float32)]),
            dtype=np.float32,
        )

    def observation(self, observation: NDArray[np.float32]) -> NDArray[np.float32]:
        v = np.asarray(observation, dtype=np.float64)
        xy = v[self.layout["object_position"]][:2]
        goal = v[self.layout["goal"]]
        if self.goal_is_pose:
            offset = goal[:2] - xy
            turn = goal[2] - yaw_of(v[self.layout["object_quaternion"]])
        else:
            offset, turn = np.zeros(2), 0.0
        fingers = v[self.layout["finger_positions"]].reshape(-1, 2) - xy
        extra = np.concatenate(
            [10.0 * offset, [math.sin(turn), math.cos(turn)], 10.0 * fingers.ravel()]
        )
        return np.concatenate([observation, extra.astype(np.float32)]).astype(np.float32)


class GoalFrame(gym.Wrapper[NDArray[np.float32], NDArray[np.float32], Any, Any]):
    """Observations and finger velocities in the frame of the object's way to its
    goal (``action_mode="fingers"`` tasks with a pose goal: SidePush, TopRub).

    The frame's origin is the object's centre and its x axis points at the goal. A
    push or a rub is the same motion wherever on the table it starts and whichever
    way the goal lies, so in this frame a policy sees one task instead of one per
    heading: the strategies' targets (behind the box on the line to the goal, beside
    the card's centre) sit at fixed coordinates, where in the table's frame they are
    a rotation of the goal's direction that a network fitted to 50 demonstrations
    did not learn (the SidePush clone drove past its targets in every episode).

    Observation (float32): distance to the goal (dm); sine and cosine of the yaw still
    to turn and of the object's yaw in the frame; the object's planar velocity in the
    frame (dm/s) and its turn rate (rad/s); its height (dm) and how upright it stands
    (the z component of its own z axis); each finger's position
    in the frame (dm); then the state vector's touch flags, finger forces, contact
    counts and slip. Action: as the environment's, each finger's planar velocity
    given in the frame. Nothing absolute is left, so nothing a policy learns is tied
    to where on the table the demonstrations happened.

    :attr:`state` is the environment's own state vector at the last reset or step
    (what a scripted strategy reads), and :meth:`policy_action` turns an action in
    the table's frame into this wrapper's, so that a strategy can label the states
    a policy reaches.
    """

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        super().__init__(env)
        self.layout, self.n_fingers = _state_layout(env, "GoalFrame")
        unwrapped: Any = env.unwrapped
        if getattr(unwrapped, "action_mode", None) != "fingers":
            raise ValueError("GoalFrame needs action_mode='fingers'")
        if not bool(getattr(unwrapped.task, "pose_goal", True)):
            raise ValueError("GoalFrame needs a task whose goal is a pose")
        self._kept = ("finger_touching", "finger_force", "finger_contacts", "slip")
        size = (
            10
            + 2 * self.n_fingers
            + sum(self.layout[name].stop - self.layout[name].start for name in self._kept)
        )
        self.observation_space = spaces.Box(-100.0, 100.0, (size,), np.float32)
        self.state = np.zeros(self.layout["slip"].stop, np.float32)
        self._angle = 0.0

    def reset(self, **kwargs: Any) -> tuple[NDArray[np.float32], dict[str, Any]]:
        observation, info = self.env.reset(**kwargs)
        return self._features(observation), info

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], Any, bool, bool, dict[str, Any]]:
        observation, reward, terminated, truncated, info = self.env.step(
            self._rotate(action, self._angle)
        )
        return self._features(observation), reward, terminated, truncated, info

    def policy_action(self, action: NDArray[np.floating[Any]]) -> NDArray[np.float32]:
        """An action in the table's frame, in this wrapper's frame (at :attr:`state`)."""
        return self._rotate(action, -self._angle)

    def _rotate(self, action: NDArray[np.floating[Any]], angle: float) -> NDArray[np.float32]:
        per_finger = np.array(action, dtype=np.float64).reshape(self.n_fingers, 3)
        c, s = math.cos(angle), math.sin(angle)
        vx, vy = per_finger[:, 0], per_finger[:, 1]
        per_finger[:, 0], per_finger[:, 1] = c * vx - s * vy, s * vx + c * vy  # both sides first
        return per_finger.ravel().astype(np.float32)

    def _features(self, observation: NDArray[np.float32]) -> NDArray[np.float32]:
        self.state = np.asarray(observation, dtype=np.float32)
        v = np.asarray(observation, dtype=np.float64)
        xy = v[self.layout["object_position"]][:2]
        goal = v[self.layout["goal"]]
        yaw = yaw_of(v[self.layout["object_quaternion"]])
        offset = goal[:2] - xy
        distance = float(np.hypot(*offset))
        # At the goal the direction is undefined: keep the last one.
        if distance > 1e-4:
            self._angle = math.atan2(offset[1], offset[0])
        c, s = math.cos(self._angle), math.sin(self._angle)
        to_frame = np.array([[c, s], [-s, c]])
        velocity = to_frame @ v[self.layout["object_linear_velocity"]][:2]
        fingers = (v[self.layout["finger_positions"]].reshape(-1, 2) - xy) @ to_frame.T
        turn, heading = goal[2] - yaw, yaw - self._angle
        qx, qy = v[self.layout["object_quaternion"]][:2]
        upright = 1.0 - 2.0 * (qx * qx + qy * qy)  # the object's z axis, up the table's
        parts = [
            [10.0 * distance, math.sin(turn), math.cos(turn), math.sin(heading)],
            [math.cos(heading), *(10.0 * velocity), v[self.layout["object_angular_velocity"]][2]],
            [10.0 * v[self.layout["object_position"]][2], upright],
            10.0 * fingers.ravel(),
            *(v[self.layout[name]] for name in self._kept),
        ]
        return np.concatenate([np.asarray(p, dtype=np.float64) for p in parts]).astype(np.float32)


#: Names a run's ``env_wrapper`` may use: the import path a zoo hyperparameter file
#: gives, and the short name of the runs trained before the zoo.
WRAPPERS: dict[str, type[gym.Wrapper[Any, Any, Any, Any]]] = {
    "graspenv_agents.wrappers.RelativeGoal": RelativeGoal,
    "graspenv_agents.wrappers.GoalFrame": GoalFrame,
    "relative_goal": RelativeGoal,
}
