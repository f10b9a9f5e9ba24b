"""What rl-baselines3-zoo lacks for graspenv, in the form its hyperparameter files load.

The learned baselines are trained by the zoo itself::

    python -m rl_zoo3.train --algo sac --env graspenv/TurnInPlace-v0 \\
        --gym-packages graspenv --conf-file agents/hyperparams/sac.yml --seed 0

and the one thing they need beyond it is here: a head start from the task's
scripted strategy. :class:`ScriptedDemonstrations` is a stable-baselines3 callback,
named in a file's ``callback`` list with its keyword arguments::

    callback:
      - graspenv_agents.zoo.ScriptedDemonstrations:
          strategy: pinch-and-turn
          episodes: 50

Before the first training step it plays that many episodes of the strategy in the
training environments themselves (so with the file's wrapper and arguments), adds
every transition to the replay buffer, and resets the environments to where
training would have started. With ``behaviour_cloning: N`` it then fits the actor's
deterministic action to the strategy's on those transitions for N gradient steps,
so that training starts from a policy that already does roughly what the
strategy does.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from .loading import load_agent

__all__ = ["ScriptedDemonstrations"]


class ScriptedDemonstrations(BaseCallback):
    """Fill an off-policy algorithm's replay buffer with scripted episodes.

    Args:
        strategy: a name from :data:`graspenv_agents.scripted.STRATEGIES`.
        episodes: episodes to play, >= 1.
        seed: seed of the first episode in each environment (environment i: seed +
            i; its later episodes continue its stream); apart from training's seeds
            and the evaluation seeds (1000 onwards).
        verbose: 1 prints one line with what was added.
    """

    def __init__(
        self,
        strategy: str,
        episodes: int = 50,
        seed: int = 20_000,
        behaviour_cloning: int = 0,
        verbose: int = 1,
    ) -> None:
        super().__init__(verbose)
        if episodes < 1:
            raise ValueError(f"ScriptedDemonstrations: episodes must be >= 1, got {episodes}")
        if behaviour_cloning < 0:
            raise ValueError(
                f"ScriptedDemonstrations: behaviour_cloning must be >= 0, got {behaviour_cloning}"
            )
        self.spec = load_agent(f"scripted:{strategy}")
        self.strategy, self.episodes, self.first_seed = strategy, episodes, seed
        self.behaviour_cloning = behaviour_cloning
        self.transitions = self.successes = 0

    def _on_training_start(self) -> None:
        model: Any = self.model
        if getattr(model, "replay_buffer", None) is None:
            raise ValueError(
                "ScriptedDemonstrations needs an off-policy algorithm (a replay buffer), "
                f"not {type(model).__name__}"
            )
        if model.get_vec_normalize_env() is not None:
            raise ValueError("ScriptedDemonstrations does not support normalize: true")
        env = self.training_env
        # The strategies read the state vector through the environment's named
        # slices; a wrapper appending values (RelativeGoal) leaves them in place.
        layout_env = env.get_attr("unwrapped", [0])[0]
        agents = [self.spec.build(layout_env) for _ in range(env.num_envs)]
        # Environment i starts from seed + i; its later episodes continue its stream.
        env.seed(self.first_seed)
        obs: Any = env.reset()  # state observations: an array, one row per environment
        done_episodes = 0
        while done_episodes < self.episodes:
            actions = np.stack([agents[i].predict(obs[i])[0] for i in range(env.num_envs)])
            new_obs: Any
            new_obs, rewards, dones, infos = env.step(actions)
            next_obs = new_obs.copy()
            for i, done in enumerate(dones):
                if done:
                    next_obs[i] = infos[i]["terminal_observation"]
                    agents[i].reset()
                    done_episodes += 1
                    self.successes += bool(infos[i].get("is_success", False))
            model.replay_buffer.add(
                obs, next_obs, model.policy.scale_action(actions), rewards, dones, infos
            )
            self.transitions += env.num_envs
            obs = new_obs
        # Where training would have started: the algorithm's seed, fresh episodes.
        env.seed(model.seed)
        model._last_obs = env.reset()
        model._last_episode_starts = np.ones(env.num_envs, dtype=bool)
        self.logger.record("demonstrations/transitions", self.transitions)
        self.logger.record("demonstrations/successes", self.successes)
        if self.behaviour_cloning:
            self.logger.record("demonstrations/cloning_loss", self._clone(model))
        if self.verbose:
            print(
                f"replay buffer filled with {done_episodes} episodes of {self.strategy} "
                f"({self.transitions} transitions, {self.successes} successes)",
                flush=True,
            )

    def _clone(self, model: Any) -> float:
        """Fit the actor's deterministic action to the demonstrated one (mean
        squared error, the actor's own optimiser); the last batch's loss."""
        import torch

        actor = model.actor
        loss = torch.zeros(())
        actor.set_training_mode(True)
        for _ in range(self.behaviour_cloning):
            batch = model.replay_buffer.sample(model.batch_size)
            loss = torch.nn.functional.mse_loss(
                actor(batch.observations, deterministic=True), batch.actions
            )
            actor.optimizer.zero_grad()
            loss.backward()
            actor.optimizer.step()
        actor.set_training_mode(False)
        return float(loss)

    def _on_step(self) -> bool:
        return True
