"""GraspEnv: one Gymnasium environment class for every grasp task.

The environment is orchestration only. One step, in order: the finger controller
turns the action into the hand's motion; for each camera frame of the step the task
may push the object (a disturbance), the hand is rendered into a contact mask, the
mask goes through the whole pipeline (:class:`graspenv.simulation.Simulation`), and
the hand advances; then grasp metrics are measured, the task updates its episode
record and gives the reward, success and termination. The environment calls the
task's hooks (:class:`graspenv.tasks.base.Task`) and knows no task by name.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

import cv2
import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from graspenv.config import (
    ConfigError,
    SceneConfig,
    SurfaceConfig,
    at_fidelity,
    build_section,
    read_config,
    resolve_fidelity,
    scene_from,
)
from graspenv.geometry import footprint, yaw_of, yaw_step
from graspenv.simulation import FrameReport, Simulation
from graspenv.surface.controller import ActionMode, ControllerConfig, FingerController
from graspenv.surface.render import render_mask
from graspenv.tasks.base import EpisodeState, RewardConfig, Task, TaskConfig, TaskEpisode
from graspenv.tasks.metrics import GraspMetrics, grasp_metrics
from graspenv.viz import draw_mask, draw_points, draw_polyline, id_colour

__all__ = ["GoalGraspEnv", "GraspEnv", "load_env_config", "make_grasp_env"]

ObsMode = Literal["state", "mask", "goal"]
MASK_SHAPE = (72, 96)  # rows, columns: the table's 4:3 aspect, every 6.7 camera pixels
# Scales that bring the observation's forces near unit size.
FORCE_SCALE = 10.0
# Every vector entry is clipped to ±BOUND (SI units; nothing physical comes near it,
# but finite bounds keep the space well defined for the checkers and for agents).
BOUND = 100.0


def load_env_config(
    task: type[Task], config: str | Path | Mapping[str, Any] | None
) -> tuple[SceneConfig, TaskConfig, ControllerConfig, RewardConfig]:
    """Split an environment configuration into its scene and task parts.

    The file (TOML or JSON, e.g. ``envs_configs/turn_in_place.toml``) or dict holds
    the scene tables (``surface``, ``contacts``, ``proxy``, ``physics``; the object
    is drawn per episode by the task) and ``task``, ``controller`` and ``reward``
    tables; each missing table or key takes the task's built-in default. The
    ``task`` table holds the fields of the task's own configuration type
    (``task.config_type``): a key another task has is unknown here.

    Raises:
        ConfigError: unknown keys or bad values, naming the key and the file.
        FileNotFoundError: the file does not exist.
    """
    data, source = read_config(config)
    if "objects" in data:
        raise ConfigError(
            f"{source}: 'objects' is drawn per episode by the task; set the ranges in "
            "the 'task' table instead"
        )
    return (
        scene_from({k: v for k, v in data.items() if k not in _TASK_TABLES}, source),
        build_section(task.config_type, data.get("task"), "task", source, task.default_config),
        build_section(
            ControllerConfig, data.get("controller"), "controller", source, task.default_controller
        ),
        build_section(RewardConfig, data.get("reward"), "reward", source, task.default_reward),
    )


_TASK_TABLES = ("task", "controller", "reward")


class GraspEnv(gym.Env[Any, NDArray[np.float32]]):
    """A grasp task on an imaging touch table, through the whole particle pipeline.

    ## Action Space

    ``action_mode="grip"``: ``Box(-1, 1, (5,))``: grip centre velocity (x, y) in units
    of ``controller.max_speed``, turn rate (``max_turn_rate``), opening rate
    (``max_open_rate``) and touch (fingers down when > 0). ``action_mode="fingers"``:
    ``Box(-1, 1, (3·n,))``: per finger a planar velocity and a touch flag. Actions are
    held for ``task.frame_skip`` camera frames. Out-of-range values are clipped; NaN
    or infinite ones raise ``ValueError``. Actions only move the synthetic hand; they
    reach the physics through the rendered contact mask.

    ## Observation Space

    ``obs_mode="state"``: a float32 vector: object position (3, m), quaternion (4,
    x y z w), linear (3, m/s) and angular (3, rad/s) velocity, finger positions (2·n,
    m), touch flags (n), the goal (3: x, y in m and yaw in rad; CatchBall: the
    ball's planar velocity, m/s, and whether it is held, desired (0, 0, 1)),
    per-finger normal force on the object (n, in units of 10 N), per-finger particle
    contact count (n, in units of 10) and slip (1, m/s).
    ``"mask"``: a Dict with ``mask``, the contact mask downsampled to 72 × 96 × 1
    uint8, and ``state``, the vector above. ``"goal"``: Gymnasium-Robotics' Dict
    (``observation`` without the goal, ``achieved_goal``, ``desired_goal``) with a
    vectorised :meth:`compute_reward` for hindsight relabelling.

    ## Rewards

    Per step, with weights from the ``reward`` table: ``−position·‖Δxy‖ −
    yaw·|Δyaw| + success·[success]`` (task progress; yaw only for tasks with a yaw
    goal) plus the grasp-stability term ``−slip·slip − tilt·tilt + grip·[firm]``,
    where firm means force closure with a grip force in ``[grip_min, grip_max]``.
    ``goal_reward(achieved, desired, info)`` gives the same value for batches (and
    is ``compute_reward`` in goal mode).

    ## Starting State

    The object (shape, size, mass, friction within the ``task`` ranges), its start
    and the goal are drawn from the seed; the hand starts as the task places it
    (lifted either side of the object for the grip tasks).

    ## Episode End

    Terminated on success (SqueezeHold: when the hold period ends; CatchBall: also
    when the ball leaves the table) or when the object falls off the table.
    Truncated by ``max_episode_steps`` from the registration.

    ## Arguments

    ``task`` (name or Task), ``proxy`` (``persistent``, ``instant`` or ``rigid``),
    ``obs_mode``, ``action_mode`` (default: the task's), ``render_mode``
    (``rgb_array``: top-down picture; ``rgb_array_3d``: PyBullet's software camera),
    ``config`` (an environment file or dict), ``fidelity`` (``fast``, ``default``,
    ``reference``, or ``auto``: the cheapest preset whose measured drift against the
    reference is within ``error_budget`` millimetres; see ``PRESET_DRIFT_MM``).

    ## Version History

    - v0: first release. 2026-12-03: CatchBall succeeds on a catch (the ball held
      still in force closure for `hold_steps`), not on the ball stopping; its goal
      vector gained the hold. 2026-12-04: SqueezeHold's hand starts 15 mm off the
      box's faces (``task.clearance``) and the push peaks at 1.5-3 N, above what
      the table's friction alone holds, so a still hand no longer holds the box.
    """

    metadata: dict[str, Any] = {  # noqa: RUF012  (Gymnasium's own convention)
        "render_modes": ["rgb_array", "rgb_array_3d"],
        # One picture per step at the default timing; each instance gives its own
        # (``1 / dt``) in its copy.
        "render_fps": SurfaceConfig().fps / TaskConfig().frame_skip,
    }

    def __init__(
        self,
        task: str | Task = "TurnInPlace",
        proxy: str | None = None,
        obs_mode: ObsMode = "state",
        action_mode: ActionMode | None = None,
        render_mode: str | None = None,
        config: str | Path | Mapping[str, Any] | None = None,
        fidelity: str = "default",
        error_budget: float | None = None,
    ) -> None:
        from graspenv.tasks.library import TASKS

        if isinstance(task, str):
            if task not in TASKS:
                raise ValueError(f"unknown task {task!r}; expected one of {list(TASKS)}")
            task_cls: type[Task] = TASKS[task]
        else:
            task_cls = type(task)
        if obs_mode not in ("state", "mask", "goal"):
            raise ValueError(f"obs_mode must be 'state', 'mask' or 'goal', got {obs_mode!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        fidelity = resolve_fidelity(fidelity, error_budget)
        self.fidelity = fidelity
        scene, task_config, controller_config, reward_config = load_env_config(task_cls, config)
        scene = at_fidelity(scene, fidelity)
        self._base_scene = scene if proxy is None else scene.replace(proxy={"method": proxy})
        self.task: Task = task if isinstance(task, Task) else task_cls(task_config, reward_config)
        self.obs_mode: ObsMode = obs_mode
        self.render_mode = render_mode
        mode = action_mode or self.task.default_action_mode
        if mode not in ("fingers", "grip"):
            raise ValueError(f"action_mode must be 'fingers' or 'grip', got {mode!r}")
        self.action_mode: ActionMode = mode

        # One picture per step: 1 / dt, frame_skip camera frames.
        self.metadata = {
            **self.metadata,
            "render_fps": self._base_scene.surface.fps / self.task.config.frame_skip,
        }

        self._sim = Simulation(self._base_scene)
        self.controller = FingerController(controller_config, self._sim.surface, self.action_mode)
        n = controller_config.n_fingers
        self.action_space = spaces.Box(-1.0, 1.0, (self.controller.action_size,), np.float32)
        sizes = {
            "object_position": 3,
            "object_quaternion": 4,
            "object_linear_velocity": 3,
            "object_angular_velocity": 3,
            "finger_positions": 2 * n,
            "finger_touching": n,
            "goal": self.task.goal_size,
            "finger_force": n,
            "finger_contacts": n,
            "slip": 1,
        }
        ends = np.cumsum(list(sizes.values()))
        self.observation_layout: dict[str, slice] = {
            name: slice(int(end - size), int(end))
            for (name, size), end in zip(sizes.items(), ends, strict=True)
        }
        """Where each quantity sits in the state vector (``obs_mode="state"``, and the
        ``state`` entry of ``"mask"``); units as in the class docstring (forces in
        10 N, contact counts in tens)."""
        state_size = int(ends[-1])
        vector = spaces.Box(-BOUND, BOUND, (state_size,), np.float32)
        if obs_mode == "state":
            self.observation_space = vector
        elif obs_mode == "mask":
            self.observation_space = spaces.Dict(
                {"mask": spaces.Box(0, 255, (*MASK_SHAPE, 1), np.uint8), "state": vector}
            )
        else:
            goal = spaces.Box(-BOUND, BOUND, (self.task.goal_size,), np.float32)
            self.observation_space = spaces.Dict(
                {
                    "observation": spaces.Box(
                        -BOUND, BOUND, (state_size - self.task.goal_size,), np.float32
                    ),
                    "achieved_goal": goal,
                    "desired_goal": goal,
                }
            )
        self._goal = np.zeros(self.task.goal_size)
        self._state: EpisodeState | None = None
        self._episode = TaskEpisode()
        self._metrics = GraspMetrics.empty()
        self._finger_force = np.zeros(n)
        self._finger_contacts = np.zeros(n)
        self._mask = np.zeros(self._sim.surface.shape, np.uint8)
        self._yaw_unwrapped = 0.0
        self._yaw_last = 0.0
        self._touch_frames, self._touch_success = 0, False
        self._closed = False

    @property
    def dt(self) -> float:
        """Simulated seconds per environment step (``frame_skip`` camera frames)."""
        return self.task.config.frame_skip / self._base_scene.surface.fps

    @property
    def simulation(self) -> Simulation:
        """The pipeline this environment steps (:meth:`reset` rebuilds its scene)."""
        return self._sim

    @property
    def goal(self) -> NDArray[np.float64]:
        """This episode's goal vector (a copy)."""
        return self._goal.copy()

    def step_touch(self, mask: NDArray[np.generic]) -> tuple[FrameReport, bool]:
        """One camera frame driven by a contact mask from outside the finger
        controller: a person's hand at the live table (``graspenv serve --env``).

        The task's disturbance pushes as in :meth:`step`; after every ``frame_skip``
        frames the episode's state, its record and the success test advance as one
        step's do. Returns the frame's report and the task's success as of the last
        completed step.
        """
        if self._state is None:
            raise RuntimeError("call reset() before step_touch()")
        task = self.task
        force = task.disturbance(self._state, self._episode)
        if force is not None:
            self._sim.apply_force(task.object_name, force)
        report = self._sim.step(mask)
        self._mask = np.asarray(mask, np.uint8)
        self._touch_frames += 1
        if self._touch_frames % task.config.frame_skip == 0:
            self._state = self._read_state(self._state.step + 1)
            self._episode = task.after_step(self._state, self._episode)
            self._touch_success = task.is_success(self._state, self._goal, self._episode)
        return report, self._touch_success

    # -- gymnasium API -----------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        super().reset(seed=seed)
        rng = self.np_random
        task = self.task
        obj = task.draw_object(rng)
        self._goal = task.draw_goal(rng, obj)
        grip = task.start_grip(rng, obj, self._goal)
        self._sim.reset(task.scene(self._base_scene, obj))
        start = task.initialize_episode(rng, obj, self._goal)
        if start.linear_velocity is not None:
            self._sim.set_object_state(
                task.object_name, linear_velocity=start.linear_velocity, rolling=start.rolling
            )
        self._episode = start.episode
        self.controller.place_grip(grip)
        self._mask = np.zeros(self._sim.surface.shape, np.uint8)
        _, q = self._sim.object_pose(task.object_name)
        self._yaw_unwrapped = self._yaw_last = yaw_of(q)
        self._state = self._read_state(step=0)
        self._touch_frames, self._touch_success = 0, False
        info = self._info(success=False, n_particles=0)
        return self._observation(), info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._state is None:
            raise RuntimeError("call reset() before step()")
        task, sim = self.task, self._sim
        action = np.asarray(action, dtype=np.float64)
        n_particles = 0
        for _ in range(task.config.frame_skip):
            self.controller.apply(action)
            force = task.disturbance(self._state, self._episode)
            if force is not None:
                sim.apply_force(task.object_name, force)
            self._mask = render_mask(self.controller.hand, sim.surface)
            n_particles = sim.step(self._mask).n_particles
            self.controller.advance()
        self._state = self._read_state(self._state.step + 1)
        self._episode = task.after_step(self._state, self._episode)
        success = task.is_success(self._state, self._goal, self._episode)
        fell = bool(self._state.position[2] < -0.02)
        terminated = task.is_done(self._state, success, self._episode) or fell
        info = self._info(success, n_particles)
        # From the goals as the observation carries them (float32), so that
        # compute_reward on observed goals gives back exactly this reward.
        reward = float(
            self.goal_reward(
                info["achieved_goal"].astype(np.float32), self._goal.astype(np.float32), info
            )
        )
        return self._observation(), reward, terminated, False, info

    def goal_reward(
        self, achieved_goal: NDArray[Any], desired_goal: NDArray[Any], info: Any
    ) -> NDArray[np.float64] | float:
        """Reward for (batches of) goals: the step reward, recomputed from goals.

        Args:
            achieved_goal: shape (goal_size,) or (B, goal_size).
            desired_goal: same shape.
            info: the step's info dict, or a sequence (or object array) of B of them.
        """
        goal_term = self.task.goal_reward(
            np.asarray(achieved_goal, dtype=float), np.asarray(desired_goal, dtype=float)
        )
        if isinstance(info, Mapping):
            return goal_term + self.task.stability_reward(info)
        stability = np.array([self.task.stability_reward(i) for i in np.asarray(info).ravel()])
        return goal_term + stability.reshape(np.shape(goal_term))

    def render(self) -> NDArray[np.uint8] | None:
        if self.render_mode == "rgb_array":
            return self._top_view()
        if self.render_mode == "rgb_array_3d":
            return self._sim.render_view()
        return None

    def close(self) -> None:
        if not self._closed:
            self._sim.close()
            self._closed = True
        super().close()

    # -- internals ---------------------------------------------------------------------

    def _read_state(self, step: int) -> EpisodeState:
        sim, name = self._sim, self.task.object_name
        pose, velocity = sim.object_pose(name), sim.object_velocity(name)
        (position, quaternion), (linear, angular) = pose, velocity
        now = yaw_of(quaternion)
        self._yaw_unwrapped += yaw_step(now, self._yaw_last)
        self._yaw_last = now
        self._measure(pose, velocity)
        m = self._metrics
        return EpisodeState(
            position=position,
            quaternion=quaternion,
            yaw=self._yaw_unwrapped,
            linear_velocity=linear,
            angular_velocity=angular,
            tilt=m.tilt,
            slip=m.slip,
            grip_force=m.grip_force,
            force_closure=m.force_closure,
            step=step,
            fingers=self.controller.finger_positions(),
        )

    def _measure(
        self,
        pose: tuple[NDArray[np.float64], NDArray[np.float64]],
        velocity: tuple[NDArray[np.float64], NDArray[np.float64]],
    ) -> None:
        """Grasp metrics and per-finger forces from the last physics sub-step, of the
        object at ``pose`` (position, quaternion) moving at ``velocity`` (linear,
        angular), as the simulation reports them."""
        sim, name = self._sim, self.task.object_name
        report = sim.contact_report(name)
        particles = report.particle >= 0
        velocities = sim.world.pool.velocities(report.particle[particles])
        obj = sim.config.objects[0]
        self._metrics = grasp_metrics(
            report,
            *pose,
            *velocity,
            velocities,
            mu=obj.friction * sim.config.proxy.particle_friction,
        )
        fingers = self.controller.finger_positions()
        touching = self.controller.touching()
        force = np.zeros(len(fingers))
        count = np.zeros(len(fingers))
        if np.any(particles) and np.any(touching):
            where = report.position[particles, :2]
            distance = np.linalg.norm(where[:, None, :] - fingers[None, :, :], axis=2)
            distance[:, ~touching] = np.inf
            nearest = np.argmin(distance, axis=1)
            np.add.at(force, nearest, report.normal_force[particles])
            np.add.at(count, nearest, 1.0)
        self._finger_force, self._finger_contacts = force, count

    def _vector(self) -> NDArray[np.float32]:
        state = self._state
        assert state is not None
        vector = np.concatenate(
            [
                state.position,
                state.quaternion,
                state.linear_velocity,
                state.angular_velocity,
                state.fingers.ravel(),
                self.controller.touching().astype(float),
                self._goal,
                self._finger_force / FORCE_SCALE,
                self._finger_contacts / 10.0,
                [state.slip],
            ]
        )
        return np.clip(vector, -BOUND, BOUND).astype(np.float32)

    def _observation(self) -> Any:
        vector = self._vector()
        if self.obs_mode == "state":
            return vector
        if self.obs_mode == "mask":
            small = cv2.resize(self._mask, MASK_SHAPE[::-1], interpolation=cv2.INTER_AREA)
            return {"mask": small.reshape(*MASK_SHAPE, 1).astype(np.uint8), "state": vector}
        assert self._state is not None
        goal = self.observation_layout["goal"]
        observation = np.concatenate([vector[: goal.start], vector[goal.stop :]])
        return {
            "observation": observation,
            "achieved_goal": np.clip(self.task.achieved_goal(self._state), -BOUND, BOUND).astype(
                np.float32
            ),
            "desired_goal": np.clip(self._goal, -BOUND, BOUND).astype(np.float32),
        }

    def _info(self, success: bool, n_particles: int) -> dict[str, Any]:
        assert self._state is not None
        m, state = self._metrics, self._state
        return {
            "is_success": bool(success),
            "object_pose": np.concatenate([state.position, state.quaternion]),
            "slip": m.slip,
            "grip_force": m.grip_force,
            "n_particles": int(n_particles),
            "force_closure": bool(m.force_closure),
            "epsilon": m.epsilon,
            "tilt": m.tilt,
            "penetration": m.penetration,
            "n_contacts": m.n_contacts,
            "achieved_goal": self.task.achieved_goal(self._state),
            "desired_goal": self._goal.copy(),
        }

    def _top_view(self) -> NDArray[np.uint8]:
        """Top-down picture: mask, contours, particles, object and goal (RGB)."""
        sim = self._sim
        surface = sim.surface
        canvas = draw_mask(self._mask)
        obj = sim.config.objects[0]
        if self.task.pose_goal:
            goal_pose = np.array([self._goal[0], self._goal[1], 0.0])
            draw_polyline(
                canvas, surface, footprint(obj, goal_pose, float(self._goal[2])), (90, 200, 90)
            )
        position, quaternion = sim.object_pose(self.task.object_name)
        outline = footprint(obj, position, yaw_of(quaternion))
        draw_polyline(canvas, surface, outline, (255, 200, 80), thickness=2)
        particles = sim.particle_positions()
        if len(particles):
            draw_points(canvas, surface, particles[:, :2], (80, 80, 255), radius=1.5)
        for i, finger in enumerate(self.controller.finger_positions()):
            colour = id_colour(i)
            centre = surface.world_to_pixel(finger)
            cv2.circle(canvas, (int(centre[0]), int(centre[1])), 3, colour, 1, cv2.LINE_AA)
        return np.ascontiguousarray(canvas[:, :, ::-1])


class GoalGraspEnv(GraspEnv):
    """GraspEnv with ``obs_mode="goal"``: adds Gymnasium-Robotics' ``compute_reward``
    (only here, since checkers take any env that has one for a goal environment)."""

    def compute_reward(
        self, achieved_goal: NDArray[Any], desired_goal: NDArray[Any], info: Any
    ) -> NDArray[np.float64] | float:
        """Vectorised reward for hindsight relabelling; see :meth:`goal_reward`."""
        return self.goal_reward(achieved_goal, desired_goal, info)


def make_grasp_env(obs_mode: ObsMode = "state", **kwargs: Any) -> GraspEnv:
    """The registrations' entry point: a :class:`GoalGraspEnv` for ``obs_mode="goal"``,
    a :class:`GraspEnv` otherwise."""
    if obs_mode == "goal":
        return GoalGraspEnv(obs_mode=obs_mode, **kwargs)
    return GraspEnv(obs_mode=obs_mode, **kwargs)
