"""The tasks' hooks on hand-built states (no physics): per-task configuration types,
episode initialisation, the disturbance, the episode record and pure success."""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np
import pytest

from graspenv.config import PhysicsConfig
from graspenv.tasks.base import DISTURBANCE_DRAWS, EpisodeState, Task, TaskConfig, TaskEpisode
from graspenv.tasks.library import (
    TASKS,
    CatchBall,
    CatchBallConfig,
    HoldEpisode,
    SqueezeHold,
    SqueezeHoldConfig,
    TurnInPlace,
)


def state_at(step: int, x: float = 0.0, yaw: float = 0.0, vx: float = 0.0) -> EpisodeState:
    """An object resting (or rolling at ``vx`` m/s) on the table at (x, 0), yaw."""
    return EpisodeState(
        position=np.array([x, 0.0, 0.015]),
        quaternion=np.array([0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]),
        yaw=yaw,
        linear_velocity=np.array([vx, 0.0, 0.0]),
        angular_velocity=np.zeros(3),
        tilt=0.0,
        slip=0.0,
        grip_force=0.0,
        force_closure=False,
        step=step,
        fingers=np.zeros((2, 2)),
    )


def start_hold(seed: int = 0) -> tuple[SqueezeHold, HoldEpisode, np.ndarray]:
    task = SqueezeHold()
    rng = np.random.default_rng(seed)
    obj = task.draw_object(rng)
    goal = task.draw_goal(rng, obj)
    start = task.initialize_episode(rng, obj, goal)
    assert isinstance(start.episode, HoldEpisode)
    return task, start.episode, goal


def test_each_task_has_only_its_own_settings() -> None:
    assert type(SqueezeHold.default_config) is SqueezeHoldConfig
    assert type(CatchBall.default_config) is CatchBallConfig
    shared = {f.name for f in dataclasses.fields(TaskConfig)}
    for name, task in TASKS.items():
        assert isinstance(task.default_config, task.config_type), name
        own = {f.name for f in dataclasses.fields(task.config_type)} - shared
        assert own == {
            "SqueezeHold": {"hold_steps", "settle_steps", "force", "clearance"},
            "CatchBall": {"ball_speed", "hold_steps"},
        }.get(name, set()), name


def test_a_task_refuses_another_tasks_configuration() -> None:
    with pytest.raises(TypeError, match="SqueezeHoldConfig"):
        SqueezeHold(TaskConfig())


@pytest.mark.parametrize(
    ("config", "message"),
    [
        (dict(force=(2.0, 1.0)), r"task\.force"),
        (dict(hold_steps=0), r"task\.hold_steps"),
        (dict(settle_steps=-1), r"task\.settle_steps"),
        (dict(clearance=-0.001), r"task\.clearance"),
        (dict(clearance=math.nan), r"task\.clearance"),
    ],
)
def test_bad_hold_settings_name_the_key(config: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SqueezeHoldConfig(**config)  # type: ignore[arg-type]


def test_bad_ball_settings_name_the_key() -> None:
    with pytest.raises(ValueError, match=r"task\.ball_speed"):
        CatchBallConfig(ball_speed=(0.6, 0.4))
    with pytest.raises(ValueError, match=r"task\.hold_steps"):
        CatchBallConfig(hold_steps=0)


@pytest.mark.parametrize("name", list(TASKS))
def test_initialisation_draws_the_same_stream_for_every_task(name: str) -> None:
    # Every task draws the disturbance's two numbers (SqueezeHold uses them), so an
    # unseeded reset continues one stream whichever the task; CatchBall draws its
    # launch (two numbers) first.
    task = TASKS[name]()
    rng = np.random.default_rng(11)
    obj = task.draw_object(rng)
    goal = task.draw_goal(rng, obj)
    before = copy.deepcopy(rng.bit_generator.state)
    task.initialize_episode(rng, obj, goal)
    expected = np.random.default_rng(0)
    expected.bit_generator.state = before
    expected.random(DISTURBANCE_DRAWS + (2 if name == "CatchBall" else 0))
    assert rng.bit_generator.state == expected.bit_generator.state


def test_only_catch_ball_starts_the_object_moving() -> None:
    for name, cls in TASKS.items():
        task = cls()
        rng = np.random.default_rng(3)
        obj = task.draw_object(rng)
        start = task.initialize_episode(rng, obj, task.draw_goal(rng, obj))
        if name == "CatchBall":
            assert start.linear_velocity is not None and start.rolling
            low, high = task.config.ball_speed  # type: ignore[attr-defined]
            assert low <= np.linalg.norm(start.linear_velocity) <= high
            assert start.linear_velocity[0] > 0.0
        else:
            assert start.linear_velocity is None, name


def test_the_hold_starts_open_and_pushes_harder_than_the_table_holds() -> None:
    # A still hand must not hold the box: the fingertips start clear of its faces,
    # and every push peaks above the table's friction on the heaviest, grippiest box
    # the task draws (combined friction is the product of the two coefficients).
    task = SqueezeHold()
    cfg = task.config
    rng = np.random.default_rng(3)
    obj = task.draw_object(rng)
    grip = task.start_grip(rng, obj, task.draw_goal(rng, obj))
    assert grip.opening == pytest.approx(obj.size[0] + 2 * cfg.clearance)
    assert cfg.clearance > cfg.position_tolerance
    physics = PhysicsConfig()
    heaviest = max(cfg.friction) * physics.table_friction * max(cfg.mass) * physics.gravity
    assert min(cfg.force) > heaviest


def test_the_hold_disturbance_ramps_between_settle_and_hold() -> None:
    task, episode, _ = start_hold()
    cfg = task.config
    assert task.disturbance(state_at(cfg.settle_steps - 1), episode) is None
    half = task.disturbance(state_at(cfg.settle_steps + cfg.hold_steps // 2), episode)
    full = task.disturbance(state_at(cfg.settle_steps + cfg.hold_steps), episode)
    assert half is not None and full is not None
    assert np.linalg.norm(full) == pytest.approx(episode.force_peak)
    assert np.allclose(half, 0.5 * full)
    assert full[2] == 0.0
    assert task.disturbance(state_at(cfg.settle_steps + cfg.hold_steps + 1), episode) is None
    assert TurnInPlace().disturbance(state_at(40), TaskEpisode()) is None


def test_the_hold_record_follows_the_box_then_breaks_for_good() -> None:
    task, episode, _ = start_hold()
    cfg = task.config
    # Before the force: the pose to hold follows the box.
    episode = task.after_step(state_at(cfg.settle_steps, x=0.002), episode)
    assert episode.held and episode.hold_pose[0] == pytest.approx(0.002)
    # Inside the tolerance: still held; beyond it once: broken, even back inside.
    episode = task.after_step(state_at(cfg.settle_steps + 1, x=0.004), episode)
    assert episode.held
    broken = task.after_step(state_at(cfg.settle_steps + 2, x=0.01), episode)
    assert not broken.held
    back = task.after_step(state_at(cfg.settle_steps + 3, x=0.002), broken)
    assert not back.held
    end = state_at(cfg.settle_steps + cfg.hold_steps, x=0.002)
    assert task.is_success(end, np.zeros(3), episode)
    assert not task.is_success(end, np.zeros(3), back)
    assert task.is_done(end, False, back)


def test_success_is_a_pure_function_of_its_arguments() -> None:
    task, episode, goal = start_hold()
    end = state_at(task.config.settle_steps + task.config.hold_steps)
    pose = episode.hold_pose.copy()
    answers = {task.is_success(end, goal, episode) for _ in range(3)}
    assert len(answers) == 1
    assert episode.held and np.array_equal(episode.hold_pose, pose)
    # Before the hold is over there is no success, whatever the record says.
    assert not task.is_success(state_at(task.config.settle_steps), goal, episode)


def caught(x: float = 0.1, vx: float = 0.0, held: bool = True) -> EpisodeState:
    state = state_at(5, x=x, vx=vx)
    state.force_closure = held
    return state


def test_catch_ball_succeeds_only_held_still_on_the_table_long_enough() -> None:
    task = CatchBall()
    goal = task.draw_goal(np.random.default_rng(0), task.draw_object(np.random.default_rng(0)))
    record = task.initialize_episode(
        np.random.default_rng(0), task.draw_object(np.random.default_rng(0)), goal
    ).episode
    hold = task.config.hold_steps
    # Held still: success on the hold_steps-th step in a row, not before.
    for _ in range(hold):
        assert not task.is_success(caught(), goal, record)
        record = task.after_step(caught(), record)
    assert task.is_success(caught(), goal, record)
    # A ball that stops without being held, that is held but rolling, or that has
    # left the table, resets the count.
    for state in (caught(held=False), caught(vx=0.1), caught(x=0.4)):
        assert task.after_step(state, record).caught_steps == 0  # type: ignore[attr-defined]
    assert task.is_done(state_at(5, x=0.4, vx=0.3), False, record)
    assert not CatchBall.pose_goal and TurnInPlace.pose_goal


def test_catch_ball_goal_terms_pay_for_a_held_still_ball() -> None:
    task = CatchBall()
    goal = np.array([0.0, 0.0, 1.0])
    achieved = np.array([task.achieved_goal(s) for s in (caught(), caught(held=False))])
    assert achieved[:, 2].tolist() == [1.0, 0.0]
    assert task.goal_success(achieved, goal).tolist() == [True, False]
    reward = task.goal_reward(achieved, goal)
    assert reward[0] > reward[1]


def test_the_default_hooks_keep_the_record() -> None:
    record = TaskEpisode()
    assert Task().after_step(state_at(1), record) is record
