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

__all__ = ["WRAPPERS", "RelativeGoal"]


class RelativeGoal(gym.ObservationWrapper[NDArray[np.float32], Any, NDArray[np.float32]]):
    """Appends to a ``"state"`` observation: the goal relative to the object (x, y in
    decimetres; sine and cosine of the remaining turn) and each finger's position
    relative to the object (decimetres)."""

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        super().__init__(env)
        unwrapped: Any = env.unwrapped
        if getattr(unwrapped, "obs_mode", None) != "state":
            raise ValueError("RelativeGoal needs obs_mode='state'")
        self.layout: dict[str, slice] = dict(unwrapped.observation_layout)
        self.n_fingers = (
            self.layout["finger_positions"].stop - self.layout["finger_positions"].start
        ) // 2
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


#: Names a run's ``env_wrapper`` may use: the import path a zoo hyperparameter file
#: gives, and the short name of the runs trained before the zoo.
WRAPPERS: dict[str, type[gym.Wrapper[Any, Any, Any, Any]]] = {
    "graspenv_agents.wrappers.RelativeGoal": RelativeGoal,
    "relative_goal": RelativeGoal,
}
