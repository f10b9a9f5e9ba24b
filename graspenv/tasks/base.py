"""What every task shares: its configuration, the episode it draws, its goal, reward
and success.

A task owns the object (drawn per episode from ranges), the goal, the hand's start,
the disturbances it applies, the reward and the success test; the environment only
steps the pipeline and asks the task. A new task is one :class:`Task` subclass plus
one registration line.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from graspenv.config import ObjectConfig, SceneConfig, ShapeName
from graspenv.surface.controller import ActionMode, ControllerConfig, GripState

__all__ = ["EpisodeState", "RewardConfig", "Task", "TaskConfig", "wrap_angle"]


def wrap_angle(angle: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """Angles wrapped into [-π, π)."""
    return np.mod(np.asarray(angle, dtype=float) + math.pi, 2 * math.pi) - math.pi


@dataclass(frozen=True)
class RewardConfig:
    """Reward weights (each term is documented in the environment's docstring).

    Attributes:
        position: per metre of distance between the object and its goal.
        yaw: per radian of yaw error.
        slip: per m/s of slip (object velocity relative to the gripping fingers).
        tilt: per radian of tilt.
        grip: bonus per step for a stable firm grip (force closure and a grip force
            within [grip_min, grip_max]).
        grip_min: smallest grip force counted as firm, newtons.
        grip_max: largest grip force counted as stable (harder crushes), newtons.
        success: bonus on a successful step.
    """

    position: float = 10.0
    yaw: float = 1.0
    slip: float = 0.5
    tilt: float = 1.0
    grip: float = 0.05
    grip_min: float = 0.5
    grip_max: float = 30.0
    success: float = 1.0


@dataclass(frozen=True)
class TaskConfig:
    """Ranges an episode is drawn from, success tolerances and timing.

    Lengths in metres, angles in radians, masses in kilograms, forces in newtons.

    Attributes:
        shape: the object's shape.
        size_min: smallest ``size`` (as in ``ObjectConfig.size``) drawn per component.
        size_max: largest ``size``.
        mass: (min, max) mass.
        friction: (min, max) lateral friction coefficient.
        start: half extents (x, y) of the region around the table centre where the
            object starts.
        goal_distance: (min, max) distance of the goal from the start, in a random
            direction (0, 0 for tasks that keep the object in place).
        goal_yaw: (min, max) magnitude of the goal's turn, random sign.
        position_tolerance: success distance.
        yaw_tolerance: success yaw error (ignored when goal_yaw is (0, 0)).
        frame_skip: camera frames per environment step (the action is held).
        hold_steps: SqueezeHold: steps the grasp must hold against the disturbance.
        settle_steps: SqueezeHold: steps before the disturbance starts.
        force: SqueezeHold: (min, max) peak disturbance force.
        ball_speed: CatchBall: (min, max) initial rolling speed, m/s.
    """

    shape: ShapeName = "box"
    size_min: tuple[float, ...] = (0.05, 0.05, 0.025)
    size_max: tuple[float, ...] = (0.07, 0.07, 0.035)
    mass: tuple[float, float] = (0.1, 0.3)
    friction: tuple[float, float] = (0.4, 0.6)
    start: tuple[float, float] = (0.05, 0.05)
    goal_distance: tuple[float, float] = (0.0, 0.0)
    goal_yaw: tuple[float, float] = (0.0, 0.0)
    position_tolerance: float = 0.01
    yaw_tolerance: float = math.radians(5.0)
    frame_skip: int = 2
    hold_steps: int = 30
    settle_steps: int = 30
    force: tuple[float, float] = (0.5, 2.0)
    ball_speed: tuple[float, float] = (0.15, 0.35)

    def __post_init__(self) -> None:
        expected = {"box": 3, "sphere": 1, "cylinder": 2}[self.shape]
        for key in ("size_min", "size_max"):
            if len(getattr(self, key)) != expected:
                raise ValueError(f"task.{key} for a {self.shape} needs {expected} values")
        for key in ("mass", "friction", "goal_distance", "goal_yaw", "force", "ball_speed"):
            lo, hi = getattr(self, key)
            if not lo <= hi:
                raise ValueError(f"task.{key} must be (min, max) with min <= max, got {(lo, hi)}")
        if self.frame_skip < 1:
            raise ValueError(f"task.frame_skip must be >= 1, got {self.frame_skip}")


@dataclass
class EpisodeState:
    """What the task sees after a step.

    Attributes:
        position: object centre, metres, world frame, (3,).
        quaternion: object orientation (x, y, z, w), (4,).
        yaw: object yaw, unwrapped since the episode started, radians.
        linear_velocity: m/s, (3,); angular_velocity: rad/s, (3,).
        tilt: radians; slip: m/s; grip_force: N; force_closure: bool.
        step: environment steps since reset.
        grip: the grip's state (grip mode) or None.
        extra: task-specific memory (e.g. where the hand holds the object).
    """

    position: NDArray[np.float64]
    quaternion: NDArray[np.float64]
    yaw: float
    linear_velocity: NDArray[np.float64]
    angular_velocity: NDArray[np.float64]
    tilt: float
    slip: float
    grip_force: float
    force_closure: bool
    step: int
    fingers: NDArray[np.float64]
    extra: dict[str, Any] = field(default_factory=dict)


class Task:
    """A grasp task: override the hooks that differ from these defaults.

    Class attributes:
        name: used in ids and configuration files.
        action_mode / n_fingers: the defaults for this task's environment.
        goal_size: length of the goal vector.
    """

    name = "task"
    default_action_mode: ActionMode = "grip"
    default_config = TaskConfig()
    default_controller = ControllerConfig()
    default_reward = RewardConfig()
    goal_size = 3
    object_name = "object"

    def __init__(
        self,
        config: TaskConfig | None = None,
        reward: RewardConfig | None = None,
    ) -> None:
        self.config = config or self.default_config
        self.reward_config = reward or self.default_reward

    # -- drawing an episode ----------------------------------------------------------

    def draw_object(self, rng: np.random.Generator) -> ObjectConfig:
        cfg = self.config
        size = tuple(float(v) for v in rng.uniform(cfg.size_min, cfg.size_max))
        start = rng.uniform(-1.0, 1.0, 2) * np.asarray(cfg.start)
        return ObjectConfig(
            name=self.object_name,
            shape=cfg.shape,
            size=size,
            mass=float(rng.uniform(*cfg.mass)),
            position=(float(start[0]), float(start[1])),
            yaw=float(rng.uniform(-math.pi, math.pi)) if cfg.shape == "box" else 0.0,
            friction=float(rng.uniform(*cfg.friction)),
            rolling_friction=0.001 if cfg.shape == "sphere" else 0.0,
        )

    def scene(self, base: SceneConfig, obj: ObjectConfig) -> SceneConfig:
        """The episode's scene: the base scene with this episode's object."""
        from graspenv.config import to_dict

        return base.replace(objects=[to_dict(obj)])

    def draw_goal(self, rng: np.random.Generator, obj: ObjectConfig) -> NDArray[np.float64]:
        """Goal (x, y, yaw) for this episode, metres and radians, world frame."""
        cfg = self.config
        heading = rng.uniform(-math.pi, math.pi)
        distance = rng.uniform(*cfg.goal_distance)
        turn = rng.uniform(*cfg.goal_yaw) * rng.choice((-1.0, 1.0))
        x, y = obj.position
        return np.array(
            [x + distance * math.cos(heading), y + distance * math.sin(heading), obj.yaw + turn]
        )

    def start_grip(
        self, rng: np.random.Generator, obj: ObjectConfig, goal: NDArray[np.float64]
    ) -> GripState:
        """Where the hand starts: lifted either side of the object across its yaw."""
        width = obj.size[0] if obj.shape == "box" else 2.0 * obj.size[0]
        return GripState(np.array(obj.position), obj.yaw, width + 0.02, False)

    # -- during an episode -----------------------------------------------------------

    def disturbance(self, state: EpisodeState) -> NDArray[np.float64] | None:
        """A force (3,) in newtons to push the object with during the next step."""
        return None

    def achieved_goal(self, state: EpisodeState) -> NDArray[np.float64]:
        return np.array([state.position[0], state.position[1], state.yaw])

    def goal_errors(
        self, achieved: NDArray[np.float64], desired: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Position error (metres) and yaw error (radians) of goal vectors (..., 3)."""
        position = np.linalg.norm(achieved[..., :2] - desired[..., :2], axis=-1)
        yaw = np.abs(wrap_angle(achieved[..., 2] - desired[..., 2]))
        if self.config.goal_yaw == (0.0, 0.0):
            yaw = np.zeros_like(yaw)
        return position, yaw

    def goal_success(
        self, achieved: NDArray[np.float64], desired: NDArray[np.float64]
    ) -> NDArray[np.bool_]:
        position, yaw = self.goal_errors(achieved, desired)
        return (position <= self.config.position_tolerance) & (yaw <= self.config.yaw_tolerance)

    def is_success(self, state: EpisodeState, goal: NDArray[np.float64]) -> bool:
        return bool(self.goal_success(self.achieved_goal(state), goal))

    def is_done(self, state: EpisodeState, success: bool) -> bool:
        """Whether the episode ends (terminated): on success by default."""
        return success

    # -- reward ----------------------------------------------------------------------

    def goal_reward(
        self, achieved: NDArray[np.float64], desired: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Progress and success terms, vectorised over leading axes (for HER)."""
        w = self.reward_config
        position, yaw = self.goal_errors(achieved, desired)
        success = self.goal_success(achieved, desired)
        return -w.position * position - w.yaw * yaw + w.success * success

    def stability_reward(self, info: Mapping[str, Any]) -> float:
        """Grasp-stability term from one step's info: slip and tilt cost, a stable
        firm grip earns. An info without the metrics (stable-baselines3's HER passes
        empty ones unless ``copy_info_dict=True``) contributes 0."""
        if "slip" not in info:
            return 0.0
        w = self.reward_config
        firm = bool(info["force_closure"]) and w.grip_min <= float(info["grip_force"]) <= w.grip_max
        return -w.slip * float(info["slip"]) - w.tilt * float(info["tilt"]) + w.grip * firm
