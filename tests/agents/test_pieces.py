"""Hyperparameter files, the relative-goal wrapper and charts."""

from __future__ import annotations

import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from graspenv.plots import bar_chart, line_chart
from graspenv_agents.hyperparams import default_file, load_hyperparams, write_hyperparams
from graspenv_agents.wrappers import WRAPPERS, GoalFrame, RelativeGoal


def test_an_entry_is_read_as_the_zoo_reads_it(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")  # the file's keys are checked against SAC's
    path = tmp_path / "sac.yml"
    write_hyperparams(
        path,
        {
            "graspenv/SqueezeSlide-v0": {"n_timesteps": 100, "batch_size": 128},
            "graspenv/TurnInPlace-v0": {"n_timesteps": 200, "gamma": 0.9},
        },
        "two entries",
    )
    assert path.read_text().startswith("# two entries\n")
    slide = load_hyperparams("graspenv/SqueezeSlide-v0", "sac", path)
    assert slide == {"n_timesteps": 100, "batch_size": 128}
    assert load_hyperparams("graspenv/TurnInPlace-v0", "sac", path)["gamma"] == 0.9


def test_shipped_files_have_an_entry_for_every_environment() -> None:
    pytest.importorskip("stable_baselines3")  # keys checked against PPO's and SAC's
    import graspenv

    for algo in ("ppo", "sac"):
        assert default_file(algo).is_file()
        for env_id in graspenv.ENV_IDS:
            entry = load_hyperparams(env_id, algo)
            assert entry["env_wrapper"] in WRAPPERS and "policy_kwargs" in entry


def test_scripted_demonstrations_need_a_replay_buffer_and_plain_observations() -> None:
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from graspenv_agents.zoo import ScriptedDemonstrations

    with pytest.raises(ValueError, match="episodes"):
        ScriptedDemonstrations("pinch-and-turn", episodes=0)
    with pytest.raises(ValueError, match="behaviour_cloning"):
        ScriptedDemonstrations("pinch-and-turn", behaviour_cloning=-1)
    with pytest.raises(ValueError, match="critic_warmup"):
        ScriptedDemonstrations("pinch-and-turn", critic_warmup=-1)
    with pytest.raises(ValueError, match="dagger needs behaviour_cloning"):
        ScriptedDemonstrations("pinch-and-turn", dagger=1)
    with pytest.raises(ValueError, match="dagger_episodes"):
        ScriptedDemonstrations("pinch-and-turn", behaviour_cloning=1, dagger=1, dagger_episodes=0)
    with pytest.raises(ValueError, match="unknown scripted strategy"):
        ScriptedDemonstrations("juggle")
    with pytest.raises(ValueError, match="cloning_loss"):
        ScriptedDemonstrations("pinch-and-turn", cloning_loss="huber")
    with pytest.raises(ValueError, match="noise"):
        ScriptedDemonstrations("pinch-and-turn", noise=-0.1)

    def make() -> gym.Env:
        return gym.make("graspenv/TurnInPlace-v0")

    for model, message in (
        (PPO("MlpPolicy", DummyVecEnv([make]), n_steps=64), "off-policy"),
        (SAC("MlpPolicy", VecNormalize(DummyVecEnv([make])), buffer_size=100), "normalize"),
    ):
        with pytest.raises(ValueError, match=message):
            model.learn(1, callback=ScriptedDemonstrations("pinch-and-turn", episodes=1))
        model.get_env().close()


def test_dagger_labels_the_actors_states_without_storing_its_transitions() -> None:
    """A DAgger round plays the actor and labels each state it reached with what the
    strategy does there (its phase kept along the actor's episode); the replay
    buffer keeps the demonstrations alone."""
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import SAC
    from stable_baselines3.common.vec_env import DummyVecEnv

    from graspenv_agents.loading import load_agent
    from graspenv_agents.zoo import ScriptedDemonstrations

    def make() -> gym.Env:
        return RelativeGoal(gym.make("graspenv/TurnInPlace-v0"))

    model = SAC(
        "MlpPolicy", DummyVecEnv([make]), buffer_size=2000, learning_starts=10**6,
        policy_kwargs={"net_arch": [16, 16]}, seed=0,
    )  # fmt: skip
    demos = ScriptedDemonstrations(
        "pinch-and-turn", episodes=1, behaviour_cloning=5, dagger=1, dagger_episodes=1
    )
    try:
        model.learn(1, callback=demos)
        states = np.concatenate(demos._states)
        labels = np.concatenate(demos._labels)
        # The demonstration's transitions, and learn's one step, are all it stores.
        assert model.replay_buffer.size() == demos.transitions + 1
        actor_states = states[demos.transitions :]
        actor_labels = labels[demos.transitions :]
        assert len(actor_states) > 1
        # The same strategy, fed the actor's states in order, says the same.
        env = make()
        try:
            strategy = load_agent("scripted:pinch-and-turn").build(env)
            said = np.stack([strategy.predict(s)[0] for s in actor_states])
        finally:
            env.close()
        np.testing.assert_allclose(model.policy.scale_action(said), actor_labels, atol=1e-6)
        # And that is not what the barely fitted actor did.
        actions, _ = model.predict(actor_states, deterministic=True)
        assert not np.allclose(actions, actor_labels, atol=0.05)
    finally:
        model.get_env().close()


def test_relative_goal_features_match_the_true_errors() -> None:
    env = RelativeGoal(gym.make("graspenv/TurnInPlace-v0"))
    try:
        obs, _ = env.reset(seed=4)
        base: gym.Env = env.unwrapped  # type: ignore[assignment]
        state = base._state  # type: ignore[attr-defined]
        goal = base._goal  # type: ignore[attr-defined]
        n = env.observation_space.shape[0] - env.env.observation_space.shape[0]
        extra = obs[-n:]
        turn = goal[2] - state.yaw
        assert np.allclose(extra[:2], 10 * (goal[:2] - state.position[:2]), atol=1e-5)
        assert np.allclose(extra[2:4], [math.sin(turn), math.cos(turn)], atol=1e-5)
        assert env.observation_space.contains(obs)
    finally:
        env.close()


def test_relative_goal_needs_state_observations() -> None:
    with pytest.raises(ValueError, match="obs_mode='state'"):
        RelativeGoal(gym.make("graspenv/TurnInPlace-v0", obs_mode="mask"))


def test_charts_draw_their_series(tmp_path: Path) -> None:
    line = line_chart({"s": ([0, 1, 2], [0.0, 0.5, 1.0])}, tmp_path / "l.png", "t", "x", "y")
    bars = bar_chart(
        ["a", "b"], {"one": [0.2, 0.9], "two": [np.nan, 0.4]}, tmp_path / "b.png", "t", "y"
    )
    assert (tmp_path / "l.png").is_file() and (tmp_path / "b.png").is_file()
    blue = np.all(bars == (178, 114, 0), axis=-1)  # series "one"
    orange = np.all(bars == (0, 159, 230), axis=-1)  # series "two"
    cols_blue = np.flatnonzero(blue.any(axis=0))
    assert blue.sum() > 500 and orange.sum() > 100
    # The 0.9 bar is taller than the 0.2 bar.
    heights = [blue[:, c].sum() for c in cols_blue]
    assert max(heights) > 3 * min(h for h in heights if h > 20)
    assert np.any(np.all(line == (178, 114, 0), axis=-1))


def test_goal_frame_puts_the_goal_on_its_x_axis_and_turns_actions_back() -> None:
    """The goal lies on the frame's +x axis at the true distance, a finger's frame
    position turns back into its true offset from the object, and an action in the
    table's frame survives the round trip through the frame."""
    env = GoalFrame(gym.make("graspenv/SidePush-v0"))
    try:
        obs, _ = env.reset(seed=7)
        layout = env.layout
        state = env.state
        xy, goal = state[layout["object_position"]][:2], state[layout["goal"]][:2]
        offset = goal - xy
        assert obs[0] == pytest.approx(10 * np.hypot(*offset), abs=1e-5)
        angle = math.atan2(offset[1], offset[0])
        c, s = math.cos(angle), math.sin(angle)
        fingers = obs[10:14].reshape(2, 2) / 10.0  # frame, metres
        back = fingers @ np.array([[c, s], [-s, c]])  # rotate by +angle
        truth = state[layout["finger_positions"]].reshape(2, 2) - xy
        np.testing.assert_allclose(back, truth, atol=1e-6)
        world = np.array([0.3, -0.2, 1.0, -0.5, 0.1, -1.0], np.float32)
        framed = env.policy_action(world)
        assert not np.allclose(framed, world)  # the goal is not along the table's x
        np.testing.assert_allclose(env._rotate(framed, angle), world, atol=1e-6)
        assert env.observation_space.contains(obs)
    finally:
        env.close()


def test_goal_frame_refuses_what_it_cannot_frame() -> None:
    with pytest.raises(ValueError, match="action_mode='fingers'"):
        GoalFrame(gym.make("graspenv/TurnInPlace-v0"))
    with pytest.raises(ValueError, match="obs_mode='state'"):
        GoalFrame(gym.make("graspenv/SidePush-v0", obs_mode="mask"))


def test_demonstrations_in_the_goal_frame_push_the_box_home() -> None:
    """Through GoalFrame the strategy's actions are turned into the frame before they
    are played: played back, they still push every box to its goal. With DART's
    noise the played actions differ from the labels by about the noise."""
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import SAC
    from stable_baselines3.common.vec_env import DummyVecEnv

    from graspenv_agents.zoo import ScriptedDemonstrations

    def make() -> gym.Env:
        return GoalFrame(gym.make("graspenv/SidePush-v0"))

    for noise in (0.0, 0.3):
        model = SAC(
            "MlpPolicy", DummyVecEnv([make]), buffer_size=2000, learning_starts=10**6,
            policy_kwargs={"net_arch": [16, 16]}, seed=0,
        )  # fmt: skip
        demos = ScriptedDemonstrations(
            "push-from-behind", episodes=2, behaviour_cloning=5, cloning_loss="squared",
            noise=noise,
        )  # fmt: skip
        try:
            model.learn(1, callback=demos)
            assert demos.successes == 2
            played = model.replay_buffer.actions[: demos.transitions, 0]
            labels = np.concatenate(demos._labels)
            gap = np.abs(played - labels)
            if noise == 0.0:
                assert np.allclose(gap, 0.0)
            else:
                assert 0.1 < float(gap.mean()) < 0.3  # E|N(0, 0.3)| = 0.24, less where clipped
        finally:
            model.get_env().close()


def test_demonstrations_fit_a_policy_on_the_contact_mask() -> None:
    """obs_mode="mask" observations (the mask and the state vector) are stored as a
    dict and fitted through the policy's CNN."""
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import SAC
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecTransposeImage

    from graspenv_agents.zoo import ScriptedDemonstrations

    env = VecTransposeImage(
        make_vec_env("graspenv/SqueezeHold-v0", n_envs=1, env_kwargs={"obs_mode": "mask"})
    )
    model = SAC(
        "MultiInputPolicy", env, buffer_size=500, learning_starts=10**6, batch_size=8,
        policy_kwargs={"net_arch": [8], "features_extractor_kwargs": {"cnn_output_dim": 8}},
        seed=0,
    )  # fmt: skip
    demos = ScriptedDemonstrations(
        "firm-hold", episodes=1, behaviour_cloning=3, cloning_loss="squared"
    )
    try:
        before = [p.detach().clone() for p in model.actor.features_extractor.parameters()]
        model.learn(1, callback=demos)
        assert set(demos._states[0]) == {"mask", "state"}
        assert demos._states[0]["mask"].shape == (1, 1, 72, 96)  # channel first, one env
        after = list(model.actor.features_extractor.parameters())
        changed = [
            not np.allclose(b.numpy(), a.detach().numpy())
            for b, a in zip(before, after, strict=True)
        ]
        assert any(changed)
    finally:
        env.close()
