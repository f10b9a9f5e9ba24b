"""The live table: touches in, a contact mask a frame, the pipeline, a state out.

:class:`LiveTable` runs its scene in a thread of its own at the camera's rate
(``surface.fps``, 60 Hz by default), whatever rate the touches arrive at: each frame
it draws the union of every source's touches into a contact mask
(:func:`graspenv.surface.render.render_mask`, the synthetic hand's renderer) and
steps the scene with it. When a frame takes longer than the camera's period, the
frames it overran are dropped, not queued, so the table stays in real time (slower
motion is never replayed late) and :attr:`LiveState.dropped` counts them.

Two kinds of scene: a :class:`~graspenv.simulation.Simulation` (``graspenv serve`` and
``--config``), or an environment's task (``--env``), stepped by the mask through
:meth:`graspenv.envs.grasp_env.GraspEnv.step_touch`, which keeps the goal and the
success test.

Everything the scene is touched by runs on the table's thread; the server reads
:meth:`LiveTable.state` and :meth:`LiveTable.view`, copies made under a lock.
"""

from __future__ import annotations

import base64
import json
import math
import threading
import time
from collections import deque
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.config import SceneConfig, to_dict
from graspenv.envs.grasp_env import GraspEnv
from graspenv.geometry import footprint, yaw_of
from graspenv.live.touches import Touch, TouchBoard
from graspenv.replay import RECORDED_SCENE
from graspenv.simulation import FrameReport, Simulation
from graspenv.surface.render import render_mask

__all__ = ["LiveState", "LiveTable"]

#: Frames over which the frame rate and the frame time are averaged.
_WINDOW = 60
#: Seconds the table keeps drawing views after the last request for one.
_VIEW_KEPT = 1.0


@dataclass(frozen=True)
class LiveState:
    """What the table shows after a frame.

    Attributes:
        frame: frames stepped since the start or the last reset.
        objects: per object, ``position`` (metres) and ``quaternion`` (x, y, z, w),
            world frame.
        contacts: tracked contacts in the last frame.
        touches: touches drawn into its mask.
        dropped: frames dropped since the start, because a frame overran.
        fps: frames stepped per second of wall time, over the last second.
        frame_ms: mean wall milliseconds of a frame's work (mask, pipeline), same
            window.
        grip_force: total normal force of the particles on each object, newtons.
        success: the task's success (``--env``), else ``None``.
        touched_at: wall time (``time.time()``) of the newest touch input the frame
            drew, for latency measurements; 0 before any.
    """

    frame: int
    objects: dict[str, dict[str, list[float]]]
    contacts: int
    touches: int
    dropped: int
    fps: float
    frame_ms: float
    grip_force: dict[str, float]
    success: bool | None
    touched_at: float

    def json(self) -> dict[str, Any]:
        """The fields by name, the timings and forces rounded for the page."""
        return {
            **asdict(self),
            "fps": round(self.fps, 2),
            "frame_ms": round(self.frame_ms, 3),
            "grip_force": {k: round(v, 4) for k, v in self.grip_force.items()},
        }


class LiveTable:
    """A scene stepped in real time by the touches on :attr:`board`.

    Args:
        scene: the scene (:class:`SceneConfig`), or an environment to serve its task.
        record: a folder to write each frame's mask into (``000000.png`` …, white =
            touched, and the scene as ``scene.json``), which ``graspenv replay``
            plays back; ``None`` records nothing.
        seed: the environment's episode seed (``env`` only).

    Attributes:
        board: where the sources put their touches.
        surface: the table's geometry.
    """

    def __init__(
        self,
        scene: SceneConfig | GraspEnv,
        record: str | Path | None = None,
        seed: int = 0,
    ) -> None:
        self.board = TouchBoard()
        self._env: GraspEnv | None = None
        if isinstance(scene, GraspEnv):
            self._env = scene
            self._env.reset(seed=seed)
            self._sim = self._env.simulation
        else:
            self._sim = Simulation(scene)
        self.surface = self._sim.surface
        self._record = Path(record) if record is not None else None
        self._recorded = 0
        if self._record is not None:
            self._record.mkdir(parents=True, exist_ok=True)
            (self._record / RECORDED_SCENE).write_text(
                json.dumps(to_dict(self._sim.config), indent=2)
            )
        self._seed = seed
        self._lock = threading.Lock()
        self._reset_wanted = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._dropped = 0
        self._times: deque[tuple[float, float]] = deque(maxlen=_WINDOW)
        self._touched_at = 0.0
        self._mask = np.zeros(self.surface.shape, np.uint8)
        self._report: FrameReport | None = None
        self._success: bool | None = None
        self._state = self._read_state(0, 0)
        self._view: dict[str, Any] = {}
        self._view_asked = -math.inf

    # -- control -----------------------------------------------------------------------

    def start(self) -> None:
        """Compile the pipeline's kernels (:meth:`warm_up`), then run the table's loop
        in its own thread."""
        if self._thread is not None:
            raise RuntimeError("the table is already running")
        self.warm_up()
        self._thread = threading.Thread(target=self._run, name="graspenv-table", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop the loop (and close the scene)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        if self._env is not None:
            self._env.close()
        else:
            self._sim.close()

    def warm_up(self) -> None:
        """A touch in a corner of the table for a few frames, then a reset: the first
        contact compiles (or loads) the pipeline's kernels, which would otherwise
        stall the first live frames for seconds."""
        corner = Touch(0.02, 0.02)
        for touching in (True, True, True, False):
            shapes = [corner.shape(self.surface)] if touching else []
            mask = render_mask(shapes, self.surface)
            if self._env is not None:
                self._env.step_touch(mask)
            else:
                self._sim.step(mask)
        self._restart()
        self._state = self._read_state(0, 0)

    def reset(self) -> None:
        """Put the scene back at its start (at the loop's next frame)."""
        self._reset_wanted.set()

    def touched(self, when: float | None = None) -> None:
        """Note that a touch input arrived (for :attr:`LiveState.touched_at`)."""
        self._touched_at = time.time() if when is None else when

    def state(self) -> LiveState:
        with self._lock:
            return self._state

    def view(self) -> dict[str, Any]:
        """What the page draws: the state, the mask (PNG, base64), the contours and
        particles (pixels), the objects' outlines (pixels) and heights (metres), and
        the goal's outline where the task has a pose goal.

        The table's thread draws it only while someone asks (within
        :data:`_VIEW_KEPT` seconds): with no page open, no frame pays for it. The
        first call returns an empty dict; the next frames fill it.
        """
        self._view_asked = time.monotonic()
        with self._lock:
            return dict(self._view)

    def step_once(self) -> LiveState:
        """One frame, now, on the caller's thread (for tests, with no loop running)."""
        self._frame()
        return self.state()

    # -- the loop ----------------------------------------------------------------------

    def _run(self) -> None:
        period = 1.0 / self.surface.fps
        clock = time.perf_counter
        due = clock()
        while not self._stop.is_set():
            now = clock()
            if now < due:
                time.sleep(due - now)
            self._frame()
            due += period
            late = clock() - due
            if late > period:
                # Frames this one overran are dropped, not caught up.
                missed = int(late // period)
                self._dropped += missed
                due += missed * period

    def _frame(self) -> None:
        start = time.perf_counter()
        if self._reset_wanted.is_set():
            self._reset_wanted.clear()
            self._restart()
        touched_at = self._touched_at
        touches = self.board.touches()
        shapes = [t.shape(self.surface) for t in touches]
        mask = render_mask(shapes, self.surface)
        if self._env is not None:
            report, self._success = self._env.step_touch(mask)
        else:
            report = self._sim.step(mask)
        if self._record is not None:
            cv2.imwrite(str(self._record / f"{self._recorded:06d}.png"), mask * np.uint8(255))
            self._recorded += 1
        self._mask, self._report = mask, report
        end = time.perf_counter()
        self._times.append((end, end - start))
        state = self._read_state(report.n_contacts, len(touches), touched_at)
        wanted = time.monotonic() - self._view_asked < _VIEW_KEPT
        view = self._draw(state) if wanted else self._view
        with self._lock:
            self._state, self._view = state, view

    def _restart(self) -> None:
        if self._env is not None:
            self._env.reset(seed=self._seed)
        else:
            self._sim.reset()
        self._success = None

    # -- what the page sees ------------------------------------------------------------

    def _read_state(self, contacts: int, touches: int, touched_at: float = 0.0) -> LiveState:
        sim = self._sim
        objects, grip = {}, {}
        for name in sim.object_names:
            position, quaternion = sim.object_pose(name)
            objects[name] = {
                "position": [float(v) for v in position],
                "quaternion": [float(v) for v in quaternion],
            }
            report = sim.contact_report(name)
            grip[name] = float(report.normal_force[report.particle >= 0].sum())
        fps, frame_ms = 0.0, 0.0
        if len(self._times) >= 2:
            span = self._times[-1][0] - self._times[0][0]
            fps = (len(self._times) - 1) / span if span > 0 else 0.0
            frame_ms = 1000.0 * sum(t for _, t in self._times) / len(self._times)
        return LiveState(
            frame=sim.frame_index,
            objects=objects,
            contacts=contacts,
            touches=touches,
            dropped=self._dropped,
            fps=fps,
            frame_ms=frame_ms,
            grip_force=grip,
            success=self._success,
            touched_at=touched_at,
        )

    def _pixels(self, xy: NDArray[np.float64]) -> list[list[float]]:
        pixels: list[list[float]] = np.round(self.surface.world_to_pixel(xy), 1).tolist()
        return pixels

    def _draw(self, state: LiveState) -> dict[str, Any]:
        sim, report = self._sim, self._report
        ok, png = cv2.imencode(".png", self._mask * np.uint8(255))
        contours = []
        if report is not None:
            frame = report.contacts
            for i in range(len(frame.contact_ids)):
                lo, hi = frame.contour_bounds[i], frame.contour_bounds[i + 1]
                contours.append(self._pixels(frame.contours[lo:hi]))
        particles = sim.particle_positions()
        shapes = {obj.name: obj for obj in sim.config.objects}
        outlines = {}
        for name, pose in state.objects.items():
            position = np.asarray(pose["position"])
            outline = footprint(shapes[name], position, yaw_of(pose["quaternion"]))
            outlines[name] = {"outline": self._pixels(outline), "height": position[2]}
        goal = None
        if self._env is not None and self._env.task.pose_goal:
            x, y, yaw = self._env.goal
            obj = shapes[self._env.task.object_name]
            goal = {"outline": self._pixels(footprint(obj, np.array([x, y, 0.0]), yaw))}
        return {
            "type": "view",
            **state.json(),
            "resolution": list(self.surface.resolution),
            "table": list(self.surface.size),
            "mask": base64.b64encode(png.tobytes()).decode() if ok else "",
            "contours": contours,
            "particles": self._pixels(particles[:, :2]) if len(particles) else [],
            "outlines": outlines,
            "goal": goal,
            "task": self._env.task.name if self._env is not None else None,
        }
