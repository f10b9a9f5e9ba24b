"""What every agent here offers: stable-baselines3's ``predict``, and ``reset``.

An agent keeps its own memory of the episode (a scripted strategy's phase; random
actions and the learned MLP policies keep none), so :meth:`Agent.predict` hands SB3's
recurrent ``state`` back unchanged, as SB3 itself does for non-recurrent policies,
and forgets the episode when ``episode_start`` says one begins (as vectorised SB3
evaluation passes it) or when :meth:`Agent.reset` is called. A subclass says only
how an observation becomes an action (:meth:`Agent._action`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["Agent"]


class Agent:
    """Base class: subclasses implement :meth:`_action`, and :meth:`reset` if they
    keep a memory of the episode."""

    name = "agent"

    def reset(self) -> None:
        """Forget the episode (nothing to forget unless a subclass keeps a memory)."""

    def seed(self, seed: int) -> None:
        """Seed what the agent draws at random for the episode that starts (nothing
        unless a subclass draws): every episode's actions then follow from its own
        seed, whichever episodes ran before it in the same process."""

    def _action(self, observation: Any, deterministic: bool) -> NDArray[np.float32]:
        """The action for ``observation``: one, or a batch of one from a VecEnv."""
        raise NotImplementedError

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.float32], Any]:
        """SB3's interface: the action for ``observation``, and ``state`` unchanged."""
        if episode_start is not None and bool(np.asarray(episode_start).ravel()[0]):
            self.reset()
        return self._action(observation, deterministic), state
