"""What every scripted strategy shares: the state vector, and SB3's ``predict`` from it.

A strategy is written against the public environment interface only: the action
space and ``env.unwrapped.observation_layout`` (named slices of the state vector).
It reads the state vector from ``"state"`` observations (or the ``state`` entry of
``"mask"`` ones) and keeps its own phase from one call to the next, restarting when
``episode_start`` says so (as vectorised SB3 evaluation passes it) or when
:meth:`reset` is called (:class:`~graspenv_agents.agent.Agent`).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from graspenv.geometry import yaw_of

from ..agent import Agent

__all__ = ["ScriptedAgent", "State", "squeeze_rate", "yaw_from_quaternion"]


#: Rotation about z of a quaternion (x, y, z, w), radians (graspenv's own).
yaw_from_quaternion = yaw_of


def squeeze_rate(
    force: NDArray[np.float64],
    feel: float = 1.0,
    firm: float = 3.0,
    close: float = -1.0,
    nudge: float = -0.1,
    ease: float = 0.05,
) -> float:
    """The grip-opening action that keeps the weaker finger's force in a band.

    Below ``feel`` newtons the grip closes at ``close``; between ``feel`` and
    ``firm`` it closes slowly (``nudge``); above ``firm`` it opens a little
    (``ease``). Closing blindly would drive the contours past the penetration
    margin, where the penetration limit lifts their particles onto the object's top
    and the grip is lost.
    """
    weakest = float(np.min(force))
    if weakest < feel:
        return close
    return nudge if weakest < firm else ease


class State:
    """Named views of one state vector (units as in GraspEnv's docstring)."""

    def __init__(self, vector: NDArray[np.floating[Any]], layout: dict[str, slice]) -> None:
        self.vector = np.asarray(vector, dtype=float)
        self._layout = layout

    def __getitem__(self, name: str) -> NDArray[np.float64]:
        return self.vector[self._layout[name]]

    @property
    def object_xy(self) -> NDArray[np.float64]:
        return self["object_position"][:2]

    @property
    def object_yaw(self) -> float:
        return yaw_from_quaternion(self["object_quaternion"])

    @property
    def fingers(self) -> NDArray[np.float64]:
        """Finger centres, metres, (n, 2)."""
        return self["finger_positions"].reshape(-1, 2)

    @property
    def finger_force(self) -> NDArray[np.float64]:
        """Per-finger normal force on the object, newtons."""
        return 10.0 * self["finger_force"]

    @property
    def goal(self) -> NDArray[np.float64]:
        return self["goal"]


class ScriptedAgent(Agent):
    """Base class: subclasses implement :meth:`act` for one observation.

    Args:
        env: the environment (possibly wrapped) the strategy will act in.
    """

    name = "scripted"

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        unwrapped: Any = env.unwrapped
        self.layout: dict[str, slice] = dict(unwrapped.observation_layout)
        self.action_mode: str = unwrapped.action_mode
        self.action_space = env.action_space
        self.reset()

    def act(self, state: State) -> NDArray[np.float64]:
        """One action for one state."""
        raise NotImplementedError

    def _vector(self, observation: Any) -> NDArray[np.float64]:
        if isinstance(observation, dict):
            observation = observation["state"]
        return np.asarray(observation, dtype=float)

    def _action(self, observation: Any, deterministic: bool) -> NDArray[np.float32]:
        vector = self._vector(observation)
        batched = vector.ndim == 2
        if batched and vector.shape[0] != 1:
            raise ValueError("a scripted strategy keeps one episode's memory: use n_envs=1")
        raw = self.act(State(vector[0] if batched else vector, self.layout))
        action = np.clip(raw, -1.0, 1.0).astype(np.float32)
        return action[None, :] if batched else action
