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
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from graspenv.config import SIZE_VALUES, ObjectConfig, SceneConfig, ShapeName
from graspenv.geometry import wrap_angle
from graspenv.surface.controller import ActionMode, ControllerConfig, GripState

__all__ = [
    "DISTURBANCE_DRAWS",
    "EpisodeStart",
    "EpisodeState",
    "RewardConfig",
    "Task",
    "TaskConfig",
    "TaskEpisode",
    "check_range",
    "wrap_angle",
]

#: Random numbers :meth:`Task.initialize_episode` draws per episode: SqueezeHold's
#: disturbance (heading, peak); other tasks draw and discard them.
DISTURBANCE_DRAWS = 2


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
    """What every task's configuration has: the ranges an episode is drawn from,
    success tolerances and timing. A task with settings of its own extends it
    (``graspenv.tasks.library``: ``SqueezeHoldConfig``, ``CatchBallConfig``) and
    names it as :attr:`Task.config_type`; the ``task`` table of an environment file
    holds only fields of its task's type.

    Lengths in metres, angles in radians, masses in kilograms.

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

    def __post_init__(self) -> None:
        expected = SIZE_VALUES[self.shape]
        for key in ("size_min", "size_max"):
            if len(getattr(self, key)) != expected:
                raise ValueError(f"task.{key} for a {self.shape} needs {expected} values")
        for key in ("mass", "friction", "goal_distance", "goal_yaw"):
            check_range(key, getattr(self, key))
        if self.frame_skip < 1:
            raise ValueError(f"task.frame_skip must be >= 1, got {self.frame_skip}")


def check_range(key: str, value: tuple[float, float]) -> None:
    """Raise ``ValueError`` naming ``task.<key>`` unless ``value`` is (min, max)."""
    lo, hi = value
    if not lo <= hi:
        raise ValueError(f"task.{key} must be (min, max) with min <= max, got {(lo, hi)}")


@dataclass
class EpisodeState:
    """What the task sees after a step: the object and the hand, measured.

    Task-owned memory of the episode (a hold's reference pose, a disturbance's
    draw) is not here but in the task's own episode record
    (:meth:`Task.initialize_episode`, :meth:`Task.after_step`).

    Attributes:
        position: object centre, metres, world frame, (3,).
        quaternion: object orientation (x, y, z, w), (4,).
        yaw: object yaw, unwrapped since the episode started, radians.
        linear_velocity: m/s, (3,); angular_velocity: rad/s, (3,).
        tilt: radians; slip: m/s; grip_force: N; force_closure: bool.
        step: environment steps since reset.
        fingers: finger positions, metres, world frame, (n, 2).
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


@dataclass(frozen=True)
class TaskEpisode:
    """A task's own record of one episode, beyond what :class:`EpisodeState`
    measures: empty for most tasks. A task that keeps bookkeeping (SqueezeHold's
    hold) subclasses it; :meth:`Task.initialize_episode` makes it, and
    :meth:`Task.after_step` returns the next one (records are never mutated)."""


@dataclass(frozen=True)
class EpisodeStart:
    """How a task starts an episode once its object is placed.

    Attributes:
        episode: the task's record of the episode (:class:`TaskEpisode`).
        linear_velocity: the object's initial velocity, m/s, world frame, (3,), or
            None to leave it at rest.
        rolling: spin a sphere to roll at that velocity (rather than slide).
    """

    episode: TaskEpisode = field(default_factory=TaskEpisode)
    linear_velocity: NDArray[np.float64] | None = None
    rolling: bool = False


class Task:
    """A grasp task: override the hooks that differ from these defaults.

    The environment calls the hooks in this order and knows no task by name
    (after dm_control's composer, where a task's hooks run at fixed points of the
    episode and of the step):

    - episode initialisation, at ``reset``: :meth:`draw_object` (the object and its
      placement), :meth:`draw_goal`, :meth:`start_grip` (the hand), then, once the
      scene is built, :meth:`initialize_episode` (initial velocities and the task's
      own :class:`TaskEpisode` record);
    - every camera frame of a step: :meth:`disturbance` (a force on the object);
    - after each step: :meth:`after_step` (the next episode record, from the new
      state), then :meth:`is_success` and :meth:`is_done` (termination), pure
      functions of the state, the goal and the record.

    Class attributes:
        name: used in ids and configuration files.
        config_type: the :class:`TaskConfig` type of the ``task`` table.
        default_config / default_controller / default_reward: the built-in tables.
        default_action_mode: the default for this task's environment.
        goal_size: length of the goal vector.
        pose_goal: the goal is a pose (x, y, yaw) the object should reach (drawn
            in the top view), not some other target.
    """

    name = "task"
    config_type: ClassVar[type[TaskConfig]] = TaskConfig
    default_action_mode: ActionMode = "grip"
    default_config: ClassVar[TaskConfig] = TaskConfig()
    default_controller = ControllerConfig()
    default_reward = RewardConfig()
    goal_size = 3
    pose_goal: ClassVar[bool] = True
    object_name = "object"

    def __init__(
        self,
        config: TaskConfig | None = None,
        reward: RewardConfig | None = None,
    ) -> None:
        config = config or self.default_config
        if not isinstance(config, self.config_type):
            raise TypeError(
                f"{self.name} takes a {self.config_type.__name__}, got {type(config).__name__}"
            )
        self.config = config
        self.reward_config = reward or self.default_reward

    # -- episode initialisation ------------------------------------------------------

    def draw_object(self, rng: np.random.Generator) -> ObjectConfig:
        """The episode's object, drawn from the ranges, placed where it starts."""
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

    def initialize_episode(
        self, rng: np.random.Generator, obj: ObjectConfig, goal: NDArray[np.float64]
    ) -> EpisodeStart:
        """The object's initial motion and the task's episode record, once the
        scene is built; by default at rest, with an empty record.

        Every task draws two numbers here, used or not (:data:`DISTURBANCE_DRAWS`),
        so that an episode after an unseeded ``reset`` draws what it drew when the
        environment drew SqueezeHold's disturbance for every task (v0's episodes,
        bit for bit).
        """
        rng.random(DISTURBANCE_DRAWS)
        return EpisodeStart()

    # -- during an episode -----------------------------------------------------------

    def disturbance(self, state: EpisodeState, episode: TaskEpisode) -> NDArray[np.float64] | None:
        """A force (3,) in newtons, world frame, on the object during the next camera
        frame; None for none."""
        return None

    def after_step(self, state: EpisodeState, episode: TaskEpisode) -> TaskEpisode:
        """The episode record after a step that ended in ``state`` (unchanged by
        default)."""
        return episode

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

    def is_success(
        self, state: EpisodeState, goal: NDArray[np.float64], episode: TaskEpisode
    ) -> bool:
        """Whether the task is achieved in ``state``: a pure function of its
        arguments (bookkeeping belongs in :meth:`after_step`)."""
        return bool(self.goal_success(self.achieved_goal(state), goal))

    def is_done(self, state: EpisodeState, success: bool, episode: TaskEpisode) -> bool:
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
