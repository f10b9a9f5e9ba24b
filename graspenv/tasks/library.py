"""The six grasp tasks of the suite."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from graspenv.config import ObjectConfig
from graspenv.surface.controller import ControllerConfig, GripState
from graspenv.tasks.base import (
    EpisodeStart,
    EpisodeState,
    RewardConfig,
    Task,
    TaskConfig,
    TaskEpisode,
    check_range,
    wrap_angle,
)

__all__ = [
    "TASKS",
    "CatchBall",
    "CatchBallConfig",
    "CatchEpisode",
    "HoldEpisode",
    "SidePush",
    "SqueezeHold",
    "SqueezeHoldConfig",
    "SqueezeSlide",
    "TopRub",
    "TurnInPlace",
]


@dataclass(frozen=True)
class SqueezeHoldConfig(TaskConfig):
    """SqueezeHold's configuration: :class:`TaskConfig` and the disturbance.

    Attributes:
        hold_steps: steps the grasp must hold against the disturbance, >= 1.
        settle_steps: steps before the disturbance starts, >= 0.
        force: (min, max) peak disturbance force, newtons.
        clearance: gap between each fingertip and the box's face at the start,
            metres, >= 0. Above ``position_tolerance``, a box pushed against a hand
            that never closes moves too far before it meets a finger.
    """

    hold_steps: int = 30
    settle_steps: int = 30
    force: tuple[float, float] = (1.5, 3.0)
    clearance: float = 0.015

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range("force", self.force)
        if not (math.isfinite(self.clearance) and self.clearance >= 0):
            raise ValueError(f"task.clearance must be finite and >= 0, got {self.clearance}")
        if self.hold_steps < 1:
            raise ValueError(f"task.hold_steps must be >= 1, got {self.hold_steps}")
        if self.settle_steps < 0:
            raise ValueError(f"task.settle_steps must be >= 0, got {self.settle_steps}")


@dataclass(frozen=True)
class CatchBallConfig(TaskConfig):
    """CatchBall's configuration: :class:`TaskConfig`, the ball's launch and the catch.

    Attributes:
        ball_speed: (min, max) initial rolling speed, m/s.
        hold_steps: consecutive steps the ball must stay caught (still, and held in
            force closure by the fingers), >= 1.
    """

    ball_speed: tuple[float, float] = (0.45, 0.6)
    hold_steps: int = 10

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range("ball_speed", self.ball_speed)
        if self.hold_steps < 1:
            raise ValueError(f"task.hold_steps must be >= 1, got {self.hold_steps}")


@dataclass(frozen=True, eq=False)
class HoldEpisode(TaskEpisode):
    """SqueezeHold's record of an episode.

    Attributes:
        force_direction: unit planar direction (x, y) of the disturbance, world frame.
        force_peak: the disturbance's peak, newtons.
        hold_pose: the pose (x, y, yaw; metres, radians) the box must keep: where it
            was on the last step before the force began.
        held: whether the box has kept within tolerance of it since.
    """

    force_direction: tuple[float, float]
    force_peak: float
    hold_pose: NDArray[np.float64]
    held: bool = True


@dataclass(frozen=True, eq=False)
class CatchEpisode(TaskEpisode):
    """CatchBall's record of an episode.

    Attributes:
        caught_steps: consecutive steps, up to the last, the ball has been caught.
    """

    caught_steps: int = 0


class SqueezeHold(Task):
    """Hold a squeezed box still while a ramped side force pushes it.

    The hand starts down either side of the box, ``clearance`` (1.5 cm) off its
    faces, so it has to close on the box to hold it. After ``settle_steps`` a force
    in a random planar direction ramps from 0 to a peak drawn per episode over
    ``hold_steps``; the peaks (1.5-3 N) beat the table's friction on every box the
    task draws. (Started on the faces under 0.5-2 N pushes, a still hand held 75 %
    of episodes.) Success: through the whole hold the box
    stays within ``position_tolerance`` (5 mm) and ``yaw_tolerance`` (3°) of its pose
    when the force began. The episode ends when the hold period is over.
    """

    name = "SqueezeHold"
    config_type = SqueezeHoldConfig
    config: SqueezeHoldConfig
    default_config = SqueezeHoldConfig(position_tolerance=0.005, yaw_tolerance=math.radians(3.0))

    def start_grip(
        self, rng: np.random.Generator, obj: ObjectConfig, goal: NDArray[np.float64]
    ) -> GripState:
        opening = obj.size[0] + 2.0 * self.config.clearance
        return GripState(np.array(obj.position), obj.yaw, opening, True)

    def draw_goal(self, rng: np.random.Generator, obj: ObjectConfig) -> NDArray[np.float64]:
        return np.array([obj.position[0], obj.position[1], obj.yaw])

    def _phase(self, state: EpisodeState) -> float:
        """Fraction of the hold period done (< 0 before the force starts)."""
        cfg = self.config
        return (state.step - cfg.settle_steps) / cfg.hold_steps

    def initialize_episode(
        self, rng: np.random.Generator, obj: ObjectConfig, goal: NDArray[np.float64]
    ) -> EpisodeStart:
        """Draw the disturbance's direction and peak."""
        heading = rng.uniform(-math.pi, math.pi)
        record = HoldEpisode(
            force_direction=(math.cos(heading), math.sin(heading)),
            force_peak=float(rng.uniform(*self.config.force)),
            hold_pose=goal.copy(),
        )
        return EpisodeStart(episode=record)

    def disturbance(self, state: EpisodeState, episode: TaskEpisode) -> NDArray[np.float64] | None:
        assert isinstance(episode, HoldEpisode)
        ramp = self._phase(state)
        if ramp < 0.0 or ramp > 1.0:
            return None
        return episode.force_peak * ramp * np.array([*episode.force_direction, 0.0])

    def after_step(self, state: EpisodeState, episode: TaskEpisode) -> HoldEpisode:
        """Until the force starts, the pose to hold follows the box; then each step
        outside the tolerances breaks the hold for good."""
        assert isinstance(episode, HoldEpisode)
        cfg = self.config
        pose = self.achieved_goal(state)
        if self._phase(state) <= 0.0:
            return dataclasses.replace(episode, hold_pose=pose, held=True)
        position, yaw = self.goal_errors(pose, episode.hold_pose)
        held = bool(position <= cfg.position_tolerance and yaw <= cfg.yaw_tolerance)
        return dataclasses.replace(episode, held=episode.held and held)

    def is_success(
        self, state: EpisodeState, goal: NDArray[np.float64], episode: TaskEpisode
    ) -> bool:
        assert isinstance(episode, HoldEpisode)
        return self._phase(state) >= 1.0 and episode.held

    def goal_errors(
        self, achieved: NDArray[np.float64], desired: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        position = np.linalg.norm(achieved[..., :2] - desired[..., :2], axis=-1)
        return position, np.abs(wrap_angle(achieved[..., 2] - desired[..., 2]))

    def is_done(self, state: EpisodeState, success: bool, episode: TaskEpisode) -> bool:
        return self._phase(state) >= 1.0


class TurnInPlace(Task):
    """Turn a box in place to a target yaw (30°–120° either way): success within 5°
    with its centre within 1 cm of where it started."""

    name = "TurnInPlace"
    default_config = TaskConfig(goal_yaw=(math.radians(30), math.radians(120)))


class SqueezeSlide(Task):
    """Bring a box 5–12 cm to a target position by gripping its sides: success with
    its centre within 1 cm."""

    name = "SqueezeSlide"
    default_config = TaskConfig(goal_distance=(0.05, 0.12))


class SidePush(Task):
    """Push a box 5–10 cm to a target by striking its sides: success within 1.5 cm.
    The fingers start lifted behind the box, on the far side from the goal."""

    name = "SidePush"
    default_action_mode = "fingers"
    default_config = TaskConfig(goal_distance=(0.05, 0.10), position_tolerance=0.015)

    def start_grip(
        self, rng: np.random.Generator, obj: ObjectConfig, goal: NDArray[np.float64]
    ) -> GripState:
        away = np.asarray(obj.position) - goal[:2]
        away /= max(float(np.linalg.norm(away)), 1e-9)
        reach = 0.5 * math.hypot(obj.size[0], obj.size[1]) + 0.02
        centre = np.asarray(obj.position) + reach * away
        # Fingers side by side across the push direction.
        return GripState(centre, math.atan2(away[1], away[0]) + math.pi / 2, 0.01, False)


class TopRub(Task):
    """Move a light flat object (a card) to a target pose by friction from its top:
    success within 1 cm and 10°."""

    name = "TopRub"
    default_action_mode = "fingers"
    default_controller = ControllerConfig(n_fingers=1)
    default_config = TaskConfig(
        size_min=(0.07, 0.07, 0.008),
        size_max=(0.09, 0.09, 0.012),
        mass=(0.01, 0.03),
        goal_distance=(0.03, 0.06),
        goal_yaw=(0.0, math.radians(30)),
        yaw_tolerance=math.radians(10),
    )

    def start_grip(
        self, rng: np.random.Generator, obj: ObjectConfig, goal: NDArray[np.float64]
    ) -> GripState:
        return GripState(np.array(obj.position), 0.0, 0.0, False)


class CatchBall(Task):
    """Catch a ball rolling across the table: stop it and hold it between the
    fingers. Success once, for ``hold_steps`` consecutive steps (10: a third of a
    second), the ball has been on the table, under 2 cm/s, and held in force
    closure by the fingers' contacts. The episode also ends when the ball leaves
    the table.

    The goal vector is (vx, vy, held): the ball's planar velocity (m/s) and whether
    the fingers hold it in force closure (1 or 0); the goal is (0, 0, 1). So the
    reward's goal terms (and hindsight relabelling) pay for a still ball in the
    hand, not for a ball that merely stops: one that comes to rest against a
    finger, or stops for an instant as it bounces back off one, passes through
    zero speed too, and a test on speed alone let random actions "catch" 59 % of
    the balls.
    """

    name = "CatchBall"
    goal_size = 3
    pose_goal = False
    config_type = CatchBallConfig
    config: CatchBallConfig
    default_config = CatchBallConfig(
        shape="sphere",
        size_min=(0.015,),
        size_max=(0.025,),
        mass=(0.03, 0.1),
        start=(0.0, 0.1),
        position_tolerance=0.02,
        # Slower balls stop by themselves before x = 0.11 m (a still hand "catches"
        # 30 of 30); at these speeds a still hand stops 1 of 20.
        ball_speed=(0.45, 0.6),
        hold_steps=10,
    )
    # A ball's tilt is only how far it has rolled: no cost (it would be noise the
    # hand cannot act on, up to π a step).
    default_reward = RewardConfig(tilt=0.0)
    table_half = (0.305, 0.23)
    #: The goal: still (vx = vy = 0) and held.
    _caught = np.array([0.0, 0.0, 1.0])

    def draw_object(self, rng: np.random.Generator) -> ObjectConfig:
        obj = super().draw_object(rng)
        return dataclasses.replace(obj, position=(-0.2, obj.position[1]))

    def draw_goal(self, rng: np.random.Generator, obj: ObjectConfig) -> NDArray[np.float64]:
        return self._caught.copy()

    def start_grip(
        self, rng: np.random.Generator, obj: ObjectConfig, goal: NDArray[np.float64]
    ) -> GripState:
        centre = np.array([0.05, obj.position[1] + rng.uniform(-0.05, 0.05)])
        return GripState(centre, math.pi / 2, 0.06, False)

    def initialize_episode(
        self, rng: np.random.Generator, obj: ObjectConfig, goal: NDArray[np.float64]
    ) -> EpisodeStart:
        """Launch the ball rolling towards +x, within 0.2 rad of it."""
        speed = rng.uniform(*self.config.ball_speed)
        heading = rng.uniform(-0.2, 0.2)
        velocity = speed * np.array([math.cos(heading), math.sin(heading), 0.0])
        start = super().initialize_episode(rng, obj, goal)
        return dataclasses.replace(
            start, episode=CatchEpisode(), linear_velocity=velocity, rolling=True
        )

    def achieved_goal(self, state: EpisodeState) -> NDArray[np.float64]:
        velocity = state.linear_velocity
        return np.array([velocity[0], velocity[1], float(state.force_closure)])

    def goal_errors(
        self, achieved: NDArray[np.float64], desired: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Speed error (m/s, against ``position_tolerance`` per second) and the hold's
        (0 held, 1 not; against ``yaw_tolerance``)."""
        speed = np.linalg.norm(achieved[..., :2] - desired[..., :2], axis=-1)
        return speed, np.abs(achieved[..., 2] - desired[..., 2])

    def _on_table(self, state: EpisodeState) -> bool:
        return bool(np.all(np.abs(state.position[:2]) <= self.table_half) and state.position[2] > 0)

    def after_step(self, state: EpisodeState, episode: TaskEpisode) -> CatchEpisode:
        """Count the consecutive steps the ball is caught: on the table, still within
        ``position_tolerance`` per second, and held in force closure."""
        assert isinstance(episode, CatchEpisode)
        caught = self._on_table(state) and bool(
            self.goal_success(self.achieved_goal(state), self._caught)
        )
        return CatchEpisode(caught_steps=episode.caught_steps + 1 if caught else 0)

    def is_success(
        self, state: EpisodeState, goal: NDArray[np.float64], episode: TaskEpisode
    ) -> bool:
        assert isinstance(episode, CatchEpisode)
        return episode.caught_steps >= self.config.hold_steps

    def is_done(self, state: EpisodeState, success: bool, episode: TaskEpisode) -> bool:
        return success or not self._on_table(state)


#: Task classes by name, in the order of ``graspenv.ENV_IDS``.
TASKS: dict[str, type[Task]] = {
    task.name: task
    for task in (SqueezeHold, TurnInPlace, SqueezeSlide, SidePush, TopRub, CatchBall)
}
