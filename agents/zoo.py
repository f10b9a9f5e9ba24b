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
training would have started. Optional head starts follow, on those transitions
alone:

- ``behaviour_cloning: N``: N gradient steps of maximum likelihood of the
  demonstrated actions under the actor's own (squashed Gaussian) distribution, so
  that training starts from a policy that does what the strategy does, its spread
  included;
- ``dagger: R`` (with ``behaviour_cloning``): then R rounds of DAgger (Ross, Gordon
  and Bagnell, AISTATS 2011): the cloned actor plays ``dagger_episodes`` episodes
  itself, the strategy says what it would have done in every state the actor
  reached (the strategies answer from the state alone), those labels join the
  demonstrations and the actor is fitted again. A clone alone drifts off the
  states the strategy visits and has never seen what to do there. The
  ``imitation`` library has DAgger but pins gymnasium 0.29 and stable-baselines3
  2.2, so the loop is here;
- ``cloning_loss: squared``: the fit moves the actor's deterministic action by
  squared error (its spread by likelihood about it), where likelihood alone let it
  widen its spread instead;
- ``noise: σ``: the strategy demonstrates with Gaussian noise on its actions and
  its clean actions label the states reached (DART), so a clone sees recoveries;
- ``critic_warmup: N``: then N steps of SAC's own critic update with the actor held
  fixed, so that the actor's first updates follow a critic that has seen the
  demonstrations' returns rather than a random one (a cloned actor following a
  random critic unlearns its cloning: on SqueezeHold a least-squares cloning alone
  held 20 of 20 episodes, and 2 000 steps of SAC after it 1 of 10).

With ``learning_starts`` above ``n_timesteps`` SAC itself never updates, and the
shipped policy is the clone (README, "Learned baselines").
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray
from stable_baselines3.common.callbacks import BaseCallback

from .loading import load_agent

__all__ = ["ScriptedDemonstrations"]


class ScriptedDemonstrations(BaseCallback):
    """Fill an off-policy algorithm's replay buffer with scripted episodes.

    Args:
        strategy: a name from :data:`graspenv_agents.scripted.STRATEGIES`.
        episodes: episodes to play, >= 1.
        seed: seed of the first episode in each environment (environment i: seed +
            i; its later episodes continue its stream); DAgger round r starts at
            seed + 1000 r. Keep it apart from training's seeds and the evaluation
            seeds (1000 onwards). It does not follow the algorithm's seed: training
            seeds share the demonstrations and differ in the networks' start and
            the batches drawn.
        behaviour_cloning: gradient steps of the fit to the labelled states, >= 0.
        dagger: DAgger rounds after the fit (each plays, labels and fits again);
            needs ``behaviour_cloning``.
        dagger_episodes: the actor's episodes in each round, >= 1.
        critic_warmup: SAC critic updates with the actor fixed, >= 0.
        cloning_loss: ``"likelihood"``: the fit maximises the demonstrated actions'
            likelihood under the actor's distribution; ``"squared"``: it fits the
            actor's deterministic action (the squashed mean) by squared error and
            the spread by likelihood about it. Under likelihood alone the actor can
            give up on states it finds hard by widening its spread there: the
            SidePush clone stood still 3 mm from where the push starts, its mean
            velocity 0 against the strategy's 0.4 and its spread 2.2.
        noise: standard deviation of Gaussian noise added to the strategy's actions
            while it demonstrates (action units, before clipping to ±1); the
            states it then reaches are labelled with its clean actions (DART:
            Laskey et al., CoRL 2017), so the demonstrations show how the strategy
            recovers from the small errors a clone makes. 0: none.
        verbose: 1 prints what was added and each DAgger round.

    The fit draws its batches from the labelled states with a generator of its own
    (seeded by the algorithm's seed), not from the replay buffer: until DAgger came
    it drew them with ``replay_buffer.sample``, from numpy's global stream, so runs
    made before then (docs/baselines.md's CatchBall run with ``critic_warmup``) do not
    repeat bit for bit.
    """

    def __init__(
        self,
        strategy: str,
        episodes: int = 50,
        seed: int = 20_000,
        behaviour_cloning: int = 0,
        dagger: int = 0,
        dagger_episodes: int = 20,
        critic_warmup: int = 0,
        cloning_loss: str = "likelihood",
        noise: float = 0.0,
        verbose: int = 1,
    ) -> None:
        super().__init__(verbose)
        if episodes < 1:
            raise ValueError(f"ScriptedDemonstrations: episodes must be >= 1, got {episodes}")
        for key, value in (
            ("behaviour_cloning", behaviour_cloning),
            ("dagger", dagger),
            ("critic_warmup", critic_warmup),
        ):
            if value < 0:
                raise ValueError(f"ScriptedDemonstrations: {key} must be >= 0, got {value}")
        if dagger and not behaviour_cloning:
            raise ValueError("ScriptedDemonstrations: dagger needs behaviour_cloning > 0")
        if cloning_loss not in ("likelihood", "squared"):
            raise ValueError(
                "ScriptedDemonstrations: cloning_loss must be 'likelihood' or 'squared', "
                f"got {cloning_loss!r}"
            )
        if dagger_episodes < 1:
            raise ValueError(
                f"ScriptedDemonstrations: dagger_episodes must be >= 1, got {dagger_episodes}"
            )
        self.spec = load_agent(f"scripted:{strategy}")
        self.strategy, self.episodes, self.first_seed = strategy, episodes, seed
        self.behaviour_cloning, self.critic_warmup = behaviour_cloning, critic_warmup
        self.dagger, self.dagger_episodes = dagger, dagger_episodes
        self.cloning_loss = cloning_loss
        if not (np.isfinite(noise) and noise >= 0):
            raise ValueError(f"ScriptedDemonstrations: noise must be >= 0, got {noise}")
        self.noise = float(noise)
        self._noise_rng = np.random.default_rng(seed)
        self.transitions = self.successes = 0
        # What the actor is fitted to: states and the strategy's (scaled) actions.
        self._states: list[NDArray[np.float32]] = []
        self._labels: list[NDArray[np.float32]] = []

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
        # Whether the wrapper gives the policy a frame of its own (GoalFrame): asked
        # once, not every step.
        self._framed = bool(env.has_attr("policy_action"))
        # The strategies read the state vector through the environment's named
        # slices; a wrapper appending values (RelativeGoal) leaves them in place.
        # Built on an environment of the same spec (its layout and action mode),
        # which works for subprocess environments too.
        spec = env.get_attr("spec", [0])[0]
        layout_env = gym.make(spec.id, **spec.kwargs)
        try:
            agents = [self.spec.build(layout_env) for _ in range(env.num_envs)]
        finally:
            layout_env.close()
        import torch

        self._generator = torch.Generator().manual_seed(model.seed or 0)
        # Environment i starts from seed + i; its later episodes continue its stream.
        env.seed(self.first_seed)
        done_episodes, self.successes = self._play(model, agents, self.episodes, demonstrate=True)
        self.logger.record("demonstrations/transitions", self.transitions)
        self.logger.record("demonstrations/successes", self.successes)
        if self.verbose:
            print(
                f"replay buffer filled with {done_episodes} episodes of {self.strategy} "
                f"({self.transitions} transitions, {self.successes} successes)",
                flush=True,
            )
        if self.behaviour_cloning:
            self.logger.record("demonstrations/cloning_loss", self._clone(model))
        for round_ in range(self.dagger):
            # The actor's own episodes, from seeds apart from the demonstrations'.
            env.seed(self.first_seed + 1_000 * (round_ + 1))
            played, successes = self._play(model, agents, self.dagger_episodes, demonstrate=False)
            loss = self._clone(model)
            # One point a round (x: the round), written now: a clone's run may end
            # before stable-baselines3 writes its own log.
            self.logger.record("demonstrations/dagger_success_rate", successes / played)
            self.logger.record("demonstrations/dagger_cloning_loss", loss)
            self.logger.dump(step=round_ + 1)
            if self.verbose:
                print(
                    f"DAgger round {round_ + 1}: the actor succeeded in {successes} of "
                    f"{played} episodes; {sum(map(len, self._labels))} labelled states; "
                    f"loss {loss:.3f}",
                    flush=True,
                )
        # Where training would have started: the algorithm's seed, fresh episodes.
        env.seed(model.seed)
        model._last_obs = env.reset()
        model._last_episode_starts = np.ones(env.num_envs, dtype=bool)
        if self.critic_warmup:
            self.logger.record("demonstrations/critic_loss", self._warm_critic(model))
        self.logger.dump(step=0)

    def _play(
        self, model: Any, agents: list[Any], episodes: int, demonstrate: bool
    ) -> tuple[int, int]:
        """Play ``episodes`` episodes in the training environments: the strategy's
        (``demonstrate``, every transition into the replay buffer) or the actor's
        (deterministic), every state labelled with the strategy's action either way.
        Returns the episodes played and how many succeeded."""
        env = self.training_env
        for agent in agents:
            agent.reset()
        obs: Any = env.reset()  # one row per environment (an array, or a dict of them)
        done_episodes = successes = 0
        while done_episodes < episodes:
            labels = self._labels_for(agents, obs)
            scaled = model.policy.scale_action(labels)
            if self.behaviour_cloning:  # kept only for the fits
                self._states.append(_copy(obs))
                self._labels.append(scaled)
            if demonstrate:
                actions = labels
                if self.noise:  # DART: play a perturbed action, keep the clean label
                    actions = np.clip(
                        labels + self._noise_rng.normal(0.0, self.noise, labels.shape), -1, 1
                    ).astype(np.float32)
            else:
                actions = model.predict(obs, deterministic=True)[0]
            new_obs: Any
            new_obs, rewards, dones, infos = env.step(actions)
            next_obs = _copy(new_obs)
            for i, done in enumerate(dones):
                if done:
                    _set_row(next_obs, i, infos[i]["terminal_observation"])
                    agents[i].reset()
                    done_episodes += 1
                    successes += bool(infos[i].get("is_success", False))
            if demonstrate:  # the actions played (the labels, unless perturbed)
                played = scaled if not self.noise else model.policy.scale_action(actions)
                model.replay_buffer.add(obs, next_obs, played, rewards, dones, infos)
                self.transitions += env.num_envs
            obs = new_obs
        return done_episodes, successes

    def _labels_for(self, agents: list[Any], obs: NDArray[np.float32]) -> NDArray[np.float32]:
        """The strategy's action in each environment's state, in the policy's terms.

        A wrapper that replaces the state vector and the action's frame
        (:class:`~graspenv_agents.wrappers.GoalFrame`) keeps the state in ``state``
        and turns the strategy's action into its own with ``policy_action``; any
        other observation holds the state vector at its start.
        """
        env = self.training_env
        if not self._framed:
            return np.stack([agents[i].predict(_row(obs, i))[0] for i in range(env.num_envs)])
        states = env.get_attr("state")
        return np.stack(
            [
                env.env_method("policy_action", agents[i].predict(states[i])[0], indices=[i])[0]
                for i in range(env.num_envs)
            ]
        )

    def _clone(self, model: Any) -> float:
        """Maximise the log-likelihood of the strategy's actions, in every state
        labelled so far, under the actor (its own optimiser); the last batch's
        negative log-likelihood."""
        import torch

        actor = model.actor
        states = _stack(self._states)
        count = len(next(iter(states.values()))) if isinstance(states, dict) else len(states)
        # Saturated actions (the strategies clip to ±1) would put atanh at infinity:
        # keep them just inside.
        labels = torch.as_tensor(np.concatenate(self._labels), dtype=torch.float32)
        labels = labels.clamp(-0.999, 0.999)
        loss = torch.zeros(())
        actor.set_training_mode(True)
        for _ in range(self.behaviour_cloning):
            rows = torch.randint(count, (model.batch_size,), generator=self._generator)
            mean, log_std, _ = actor.get_action_dist_params(_take(states, rows))
            if self.cloning_loss == "likelihood":
                distribution = actor.action_dist.proba_distribution(mean, log_std)
                loss = -distribution.log_prob(labels[rows]).mean()
            else:
                # The squashed mean fitted by squared error, the spread by likelihood
                # about that mean: the mean cannot buy its misses with a wider spread.
                squared = ((torch.tanh(mean) - labels[rows]) ** 2).sum(dim=1).mean()
                distribution = actor.action_dist.proba_distribution(mean.detach(), log_std)
                loss = squared - distribution.log_prob(labels[rows]).mean()
            actor.optimizer.zero_grad()
            loss.backward()
            actor.optimizer.step()
        actor.set_training_mode(False)
        return float(loss.detach())

    def _warm_critic(self, model: Any) -> float:
        """SAC's critic update (as ``SAC.train``) with the actor and the entropy
        coefficient fixed; the last batch's loss."""
        import torch
        from stable_baselines3.common.utils import polyak_update

        critic, target_critic = model.critic, model.critic_target
        if model.log_ent_coef is not None:
            ent_coef = torch.exp(model.log_ent_coef.detach())
        else:
            ent_coef = model.ent_coef_tensor
        loss = torch.zeros(())
        critic.set_training_mode(True)
        for _ in range(self.critic_warmup):
            batch = model.replay_buffer.sample(model.batch_size)
            with torch.no_grad():
                next_actions, next_log_prob = model.actor.action_log_prob(batch.next_observations)
                next_q = torch.cat(target_critic(batch.next_observations, next_actions), dim=1)
                next_q = torch.min(next_q, dim=1, keepdim=True)[0]
                next_q = next_q - ent_coef * next_log_prob.reshape(-1, 1)
                target = batch.rewards + (1 - batch.dones) * model.gamma * next_q
            current = critic(batch.observations, batch.actions)
            loss = (
                0.5 * torch.stack([torch.nn.functional.mse_loss(q, target) for q in current]).sum()
            )
            critic.optimizer.zero_grad()
            loss.backward()
            critic.optimizer.step()
            polyak_update(critic.parameters(), target_critic.parameters(), model.tau)
            polyak_update(model.batch_norm_stats, model.batch_norm_stats_target, 1.0)
        critic.set_training_mode(False)
        return float(loss.detach())

    def _on_step(self) -> bool:
        return True


# Observations are an array with a row per environment or, for ``obs_mode="mask"``,
# a dict of such arrays (the mask, channel first after SB3's transpose, and the
# state vector).


def _copy(obs: Any) -> Any:
    return {k: v.copy() for k, v in obs.items()} if isinstance(obs, dict) else obs.copy()


def _row(obs: Any, i: int) -> Any:
    return {k: v[i] for k, v in obs.items()} if isinstance(obs, dict) else obs[i]


def _set_row(obs: Any, i: int, row: Any) -> None:
    if isinstance(obs, dict):
        for k in obs:
            obs[k][i] = row[k]
    else:
        obs[i] = row


def _stack(observations: list[Any]) -> Any:
    """The stored observations as one tensor (or a dict of tensors); masks stay
    uint8 until the policy's own preprocessing scales them."""
    import torch

    if isinstance(observations[0], dict):
        return {
            k: torch.as_tensor(np.concatenate([o[k] for o in observations]))
            for k in observations[0]
        }
    return torch.as_tensor(np.concatenate(observations), dtype=torch.float32)


def _take(states: Any, rows: Any) -> Any:
    return {k: v[rows] for k, v in states.items()} if isinstance(states, dict) else states[rows]
