"""``graspenv replay``: recorded contact masks through a scene, annotated.

A folder of mask images or a video file (from a real table, another simulator or an
earlier run) is read frame by frame, turned into binary contact masks at the scene's
camera resolution and stepped through a :class:`~graspenv.simulation.Simulation`.
Every frame is drawn in full (mask in grey, tracked contours coloured by contact id,
particles in red, object outlines in blue) into ``replay.mp4`` (or ``replay.gif``),
and what happened is written to ``summary.json`` (machine-readable, with a per-frame
trace) and ``summary.txt`` (a few lines for people).

**Masks from images.** Each frame is read as grey (colour is converted, alpha is
ignored) and a pixel is touched where its grey value is strictly greater than
``threshold`` (default 127: robust to the faint noise lossy video codecs add to
black; pass 0 for "non-zero = touched"). A frame whose size is not the surface
resolution (W, H) is resized to it by nearest neighbour, aspect ratio not kept, and a
warning is given once per source.

**Timing.** One mask is one camera frame of the scene: simulated time advances by
``1 / surface.fps`` per mask. A recording made at another rate should be replayed
with ``fps`` set to it, or objects move at the wrong speed.
"""

from __future__ import annotations

import itertools
import json
import math
import re
import time
import warnings
from collections.abc import Callable, Generator, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.config import ObjectConfig, SceneConfig, load_config, to_dict
from graspenv.contacts.tracking import ContactFrame
from graspenv.geometry import footprint, yaw_of, yaw_step
from graspenv.simulation import STAGES, FrameReport, Simulation, make_simulation
from graspenv.viz import (
    draw_mask,
    draw_points,
    draw_polyline,
    id_colour,
    put_label,
    write_animation,
)

__all__ = [
    "DEFAULT_THRESHOLD",
    "IMAGE_SUFFIXES",
    "RECORDED_SCENE",
    "ObjectTrack",
    "ReplayResult",
    "draw_table",
    "read_masks",
    "replay",
]

IMAGE_SUFFIXES = frozenset(
    {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm", ".pbm", ".webp"}
)
DEFAULT_THRESHOLD = 127
#: The scene a recording was made in, beside its masks (``graspenv serve --record``).
RECORDED_SCENE = "scene.json"

Mask = NDArray[np.uint8]
VideoFormat = Literal["mp4", "gif"]
Progress = Callable[[int, int | None], None]

_OBJECT_COLOUR = (255, 200, 80)
_PARTICLE_COLOUR = (80, 80, 255)
# Browsers show GIF frame delays under 20 ms as 100 ms, so a GIF keeps one frame in
# every few, at about this rate.
_GIF_FPS = 20.0


# -- reading masks -------------------------------------------------------------------


def _natural_key(path: Path) -> tuple[tuple[str | int, ...], str]:
    # re.split with a capturing group alternates text and digits, text first, so the
    # tuples compare str with str and int with int: frame_2 < frame_10.
    parts = re.split(r"(\d+)", path.name.casefold())
    return tuple(int(p) if i % 2 else p for i, p in enumerate(parts)), path.name


@dataclass
class _Source:
    """An opened source of grey frames (a sorted list of images or a video)."""

    path: Path
    images: list[Path] | None = None
    capture: Any = None  # cv2.VideoCapture, already read up to its first frame
    first: NDArray[np.uint8] | None = None
    count: int | None = None  # frames, if known (a video's count is only a hint)
    fps: float | None = None  # a video's own frame rate, if it reports one

    def grey_frames(self) -> Iterator[tuple[str, NDArray[np.uint8]]]:
        """(where the frame came from, grey (H, W) uint8 image), in order."""
        if self.images is not None:
            for image in self.images:
                grey = cv2.imread(str(image), cv2.IMREAD_GRAYSCALE)
                if grey is None:
                    raise ValueError(
                        f"cannot read {image} as an image; expected a mask image "
                        f"({', '.join(sorted(IMAGE_SUFFIXES))})"
                    )
                yield str(image), np.asarray(grey, np.uint8)
            return
        try:
            frame = self.first
            index = 0
            while frame is not None:
                yield f"{self.path} frame {index}", frame
                ok, bgr = self.capture.read()
                frame = _grey(bgr) if ok else None
                index += 1
        finally:
            self.capture.release()


def _grey(image: NDArray[Any]) -> NDArray[np.uint8]:
    if image.ndim == 3:
        return np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), np.uint8)
    return np.asarray(image, np.uint8)


def _open(source: Path) -> _Source:
    """Check a source and open it; raises at once for the errors a user can cause."""
    if not source.exists():
        raise FileNotFoundError(f"replay source not found: {source}")
    if source.is_dir():
        images = sorted(
            (
                p
                for p in source.iterdir()
                if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES and not p.name.startswith(".")
            ),
            key=_natural_key,
        )
        if not images:
            raise ValueError(
                f"no mask images in folder {source}; expected files ending in "
                f"{', '.join(sorted(IMAGE_SUFFIXES))}"
            )
        return _Source(source, images=images, count=len(images))
    if source.suffix.lower() in IMAGE_SUFFIXES:
        return _Source(source, images=[source], count=1)
    capture = cv2.VideoCapture(str(source))
    if not capture.isOpened():
        capture.release()
        raise ValueError(
            f"cannot read {source} as a video (OpenCV cannot decode it, or it has no "
            f"frames); expected a video file (e.g. .mp4, .avi) or a folder of mask images"
        )
    ok, bgr = capture.read()
    if not ok:
        capture.release()
        raise ValueError(f"video {source} yields no frames; expected at least one")
    count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
    fps = float(capture.get(cv2.CAP_PROP_FPS))
    return _Source(
        source,
        capture=capture,
        first=_grey(bgr),
        count=count if count > 0 else None,
        fps=fps if fps > 0 and math.isfinite(fps) else None,
    )


def _check_threshold(threshold: int) -> int:
    if isinstance(threshold, bool) or not isinstance(threshold, int | np.integer):
        raise ValueError(f"threshold must be an integer grey level, got {threshold!r}")
    if not 0 <= threshold <= 254:
        raise ValueError(f"threshold must be in [0, 254] (touched = grey > it), got {threshold}")
    return int(threshold)


def _masks(
    source: _Source, resolution: tuple[int, int], threshold: int
) -> Generator[Mask, None, None]:
    width, height = resolution
    warned = False
    for where, grey in source.grey_frames():
        if grey.shape != (height, width):
            if not warned:
                warnings.warn(
                    f"{where} is {grey.shape[1]}×{grey.shape[0]} pixels, the surface "
                    f"{width}×{height}: frames of {source.path} are resized to it "
                    f"(nearest neighbour, aspect ratio not kept)",
                    UserWarning,
                    stacklevel=2,
                )
                warned = True
            grey = np.asarray(
                cv2.resize(grey, (width, height), interpolation=cv2.INTER_NEAREST), np.uint8
            )
        _, mask = cv2.threshold(grey, threshold, 255, cv2.THRESH_BINARY)
        yield np.asarray(mask, np.uint8)


def read_masks(
    source: str | Path, resolution: tuple[int, int], threshold: int = DEFAULT_THRESHOLD
) -> Iterator[Mask]:
    """Contact masks from a folder of images, one image or a video file.

    A folder is read in natural order of file names (``frame_2`` before
    ``frame_10``); files with other suffixes and hidden files are skipped. Anything
    else that is not an image is opened as a video with OpenCV.

    Args:
        source: a folder of mask images (:data:`IMAGE_SUFFIXES`), one image, or a
            video file.
        resolution: the surface's camera resolution (W columns, H rows), pixels;
            frames of another size are resized to it (nearest neighbour) with one
            warning.
        threshold: a pixel is touched where its grey value is > ``threshold``
            (0..254); 0 means non-zero = touched.

    Returns:
        An iterator of (H, W) uint8 masks, 255 = touched, 0 elsewhere, row 0 at the
        top (the camera's view). The source is checked and opened at once; an image
        that turns out unreadable raises when the iterator reaches it.

    Raises:
        FileNotFoundError: ``source`` does not exist.
        ValueError: an empty folder, a file that is neither an image nor a video,
            a video with no frames, an unreadable image, or a bad ``threshold``.
    """
    threshold = _check_threshold(threshold)
    width, height = (int(v) for v in resolution)
    if width <= 0 or height <= 0:
        raise ValueError(f"resolution must be positive (W, H) pixels, got {resolution}")
    return _masks(_open(Path(source)), (width, height), threshold)


# -- the result ----------------------------------------------------------------------


@dataclass
class ObjectTrack:
    """One object's path through a replay.

    Attributes:
        name: the object's name in the scene.
        start_position: centre before the first frame, metres, world frame, (3,).
        start_yaw: rotation about z before the first frame, radians.
        position: centre after each frame, metres, world frame, (T, 3).
        yaw: rotation about z after each frame, unwrapped (continuous across ±π),
            radians, (T,).
    """

    name: str
    start_position: NDArray[np.float64]
    start_yaw: float
    position: NDArray[np.float64]
    yaw: NDArray[np.float64]

    @property
    def end_position(self) -> NDArray[np.float64]:
        """Centre after the last frame, metres, world frame, (3,)."""
        return self.position[-1] if len(self.position) else self.start_position

    @property
    def turn(self) -> float:
        """Net rotation about z from start to end, radians (may exceed ±π)."""
        return float(self.yaw[-1] - self.start_yaw) if len(self.yaw) else 0.0

    @property
    def displacement(self) -> float:
        """Straight-line distance from start to end in the table plane, metres."""
        return float(np.linalg.norm((self.end_position - self.start_position)[:2]))

    @property
    def travel(self) -> float:
        """Path length in the table plane, frame to frame, metres (≥ displacement)."""
        path = np.vstack([self.start_position[None, :2], self.position[:, :2]])
        return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())


@dataclass
class ReplayResult:
    """What a replay measured and wrote.

    Attributes:
        source: the folder or video replayed.
        fps: camera frames per second of the scene (simulated time per frame 1/fps).
        contacts: tracked contacts per frame, (T,).
        particles: particle bodies per frame, (T,).
        timings: seconds per frame for each pipeline stage (``FrameReport.timings``),
            each (T,).
        objects: each object's track, by name, in scene order.
        wall_seconds: the whole replay, reading and drawing included, seconds.
        scene: the scene configuration used.
        files: the files written.
    """

    source: Path
    fps: float
    contacts: NDArray[np.int64]
    particles: NDArray[np.int64]
    timings: dict[str, NDArray[np.float64]]
    objects: dict[str, ObjectTrack]
    wall_seconds: float
    scene: SceneConfig
    files: list[Path] = field(default_factory=list)

    @property
    def frames(self) -> int:
        """Camera frames replayed."""
        return len(self.contacts)

    @property
    def pipeline_seconds(self) -> float:
        """Seconds spent in the pipeline's stages (sensing to physics), all frames."""
        return float(sum(t.sum() for t in self.timings.values()))

    @property
    def pipeline_fps(self) -> float:
        """Frames per second of the pipeline alone (no reading, drawing or writing)."""
        seconds = self.pipeline_seconds
        return self.frames / seconds if seconds > 0 else float("nan")

    def summary(self) -> dict[str, Any]:
        """Plain JSON-ready figures; lengths in metres, angles in radians, times in ms."""

        def stats(values: NDArray[np.int64]) -> dict[str, float]:
            if not len(values):
                return {"mean": 0.0, "max": 0}
            return {"mean": float(values.mean()), "max": int(values.max())}

        def rounded(values: NDArray[np.float64]) -> list[float]:
            # Micrometres and microradians: enough for any plot, a third of the size.
            return [round(float(v), 6) for v in values]

        stage_ms = {
            stage: 1000.0 * float(t.mean()) if len(t) else 0.0 for stage, t in self.timings.items()
        }
        return {
            "source": str(self.source),
            "frames": self.frames,
            "fps": self.fps,
            "simulated_seconds": self.frames / self.fps,
            "contacts": stats(self.contacts),
            "particles": stats(self.particles),
            "stage_mean_ms": stage_ms,
            "frame_mean_ms": sum(stage_ms.values()),
            "pipeline_fps": self.pipeline_fps,
            "real_time_factor": self.pipeline_fps / self.fps,
            "wall_seconds": self.wall_seconds,
            "objects": {
                name: {
                    "start_position_m": [float(v) for v in track.start_position],
                    "end_position_m": [float(v) for v in track.end_position],
                    "start_yaw_rad": track.start_yaw,
                    "end_yaw_rad": math.remainder(track.start_yaw + track.turn, 2 * math.pi),
                    "turn_rad": track.turn,
                    "displacement_m": track.displacement,
                    "travel_m": track.travel,
                }
                for name, track in self.objects.items()
            },
            "files": [str(p) for p in self.files],
            "scene": to_dict(self.scene),
            "per_frame": {
                "contacts": [int(v) for v in self.contacts],
                "particles": [int(v) for v in self.particles],
                "objects": {
                    name: {
                        "x_m": rounded(track.position[:, 0]),
                        "y_m": rounded(track.position[:, 1]),
                        "yaw_rad": rounded(track.yaw),
                    }
                    for name, track in self.objects.items()
                },
            },
        }

    def text(self) -> str:
        """A few lines for people: counts, timings, and each object's move."""
        s = self.summary()
        lines = [
            f"source: {self.source}",
            f"frames: {self.frames} ({s['simulated_seconds']:.2f} s simulated at {self.fps:g} fps)",
            f"contacts per frame: mean {s['contacts']['mean']:.2f}  max {s['contacts']['max']}",
            f"particles per frame: mean {s['particles']['mean']:.1f}  max {s['particles']['max']}",
            "stage mean ms: "
            + "  ".join(f"{k} {v:.3f}" for k, v in s["stage_mean_ms"].items())
            + f"  (frame {s['frame_mean_ms']:.3f})",
            f"pipeline: {self.pipeline_fps:.1f} frames/s, {s['real_time_factor']:.2f}× real time",
        ]
        for name, track in self.objects.items():
            start, end = track.start_position, track.end_position
            lines.append(
                f"{name}: ({100 * start[0]:.2f}, {100 * start[1]:.2f}) cm "
                f"{math.degrees(track.start_yaw):.1f}° → "
                f"({100 * end[0]:.2f}, {100 * end[1]:.2f}) cm "
                f"{math.degrees(track.start_yaw + track.turn):.1f}°; "
                f"moved {100 * track.displacement:.2f} cm, travelled "
                f"{100 * track.travel:.2f} cm, turned {math.degrees(track.turn):.1f}°"
            )
        return "\n".join(lines)


# -- pictures ------------------------------------------------------------------------


def draw_table(
    sim: Simulation,
    mask: Mask,
    contacts: ContactFrame,
    scale: int,
    objects: Sequence[ObjectConfig] | None = None,
) -> NDArray[np.uint8]:
    """One frame of the table, unlabelled: the mask (grey), object outlines (blue),
    tracked contours (coloured by contact id) and particles (red).

    Args:
        mask: the frame's contact mask, camera pixels, shape (H, W).
        contacts: the contacts tracked in ``mask``.
        scale: canvas pixels per camera pixel.
        objects: the objects to outline (default: every object of the scene).
    """
    surface = sim.surface
    canvas = draw_mask(mask, scale)
    for obj in sim.config.objects if objects is None else objects:
        position, quaternion = sim.object_pose(obj.name)
        outline = footprint(obj, position, yaw_of(quaternion))
        draw_polyline(canvas, surface, outline, _OBJECT_COLOUR, scale, thickness=2)
    for contact in contacts:
        draw_polyline(canvas, surface, contact.contour, id_colour(contact.id), scale)
    particles = sim.particle_positions()
    if len(particles):
        draw_points(canvas, surface, particles[:, :2], _PARTICLE_COLOUR, scale, radius=2.0)
    return canvas


def _picture(sim: Simulation, mask: Mask, report: FrameReport, scale: int) -> NDArray[np.uint8]:
    """The whole table at one frame: mask, object outlines, contours, particles, labels."""
    surface = sim.surface
    canvas = draw_table(sim, mask, report.contacts, scale)
    put_label(canvas, f"frame {report.index}  t {report.index / surface.fps:.3f} s", 0)
    put_label(canvas, f"contacts {report.n_contacts}  particles {report.n_particles}", 1)
    return canvas


class _VideoOut:
    """Annotated frames to an MP4 as they come (constant memory) or a GIF at the end."""

    def __init__(self, path: Path, fps: float) -> None:
        self.path = path
        self.fps = fps
        self._writer: Any = None
        self._kept: list[NDArray[np.uint8]] = []
        self._stride = max(1, round(fps / _GIF_FPS)) if path.suffix == ".gif" else 1

    def add(self, index: int, picture: NDArray[np.uint8]) -> None:
        if self.path.suffix == ".gif":
            if index % self._stride == 0:
                self._kept.append(picture)
            return
        if self._writer is None:
            h, w = picture.shape[:2]
            fourcc = cv2.VideoWriter.fourcc(*"mp4v")
            self._writer = cv2.VideoWriter(str(self.path), fourcc, self.fps, (w, h))
            if not self._writer.isOpened():
                raise OSError(f"OpenCV could not write {self.path}")
        self._writer.write(picture)

    def close(self) -> Path:
        if self._writer is not None:
            self._writer.release()
            self._writer = None
        if self._kept:
            write_animation(self._kept, self.path, self.fps / self._stride)
            self._kept = []
        return self.path


# -- the replay ----------------------------------------------------------------------


def replay(
    source: str | Path,
    out: str | Path,
    config: str | Path | dict[str, Any] | SceneConfig | None = None,
    fps: float | None = None,
    limit: int | None = None,
    progress: Progress | None = None,
    *,
    video: VideoFormat = "mp4",
    threshold: int = DEFAULT_THRESHOLD,
    scale: int | None = None,
    progress_every: int = 100,
) -> ReplayResult:
    """Run recorded masks through a scene; write an annotated video and a summary.

    Args:
        source: a folder of mask images, one image or a video file (see
            :func:`read_masks`).
        out: folder for ``replay.mp4`` (or ``replay.gif``), ``summary.json`` and
            ``summary.txt``; created if missing, files in it overwritten.
        config: the scene: a file in ``envs_configs/``, a dict, a ``SceneConfig`` or
            ``None``: the folder's ``scene.json`` where it has one (a recording of
            ``graspenv serve --record``), else the built-in scene. Its surface
            resolution is the mask size.
        fps: camera frames per second of the recording; overrides the scene's
            ``surface.fps`` (simulated seconds per mask) and is the video's rate.
            ``None`` keeps the scene's; a video reporting another rate is warned of.
        limit: replay at most this many frames (``None``: all).
        progress: called as ``progress(frames_done, frames_total_or_None)`` every
            ``progress_every`` frames and after the last one (a video's total is
            OpenCV's estimate).
        video: ``"mp4"`` (streamed, any length) or ``"gif"`` (one frame in every few,
            about 20 per second, held in memory: for short clips).
        threshold: touched = grey value > ``threshold`` (see :func:`read_masks`).
        scale: picture pixels per camera pixel, an integer (``None``: 2 for an MP4,
            1 for a GIF).
        progress_every: frames between ``progress`` calls.

    Returns:
        Per-frame contact and particle counts, stage timings and object tracks, and
        the files written.

    Raises:
        FileNotFoundError: ``source`` or the scene file does not exist.
        ValueError: a bad source (see :func:`read_masks`) or argument.
        ConfigError: a bad scene or ``fps``.
        OSError: OpenCV could not write the video.
    """
    if video not in ("mp4", "gif"):
        raise ValueError(f"video must be 'mp4' or 'gif', got {video!r}")
    if limit is not None and (isinstance(limit, bool) or limit < 1):
        raise ValueError(f"limit must be a positive number of frames or None, got {limit!r}")
    if scale is None:
        scale = 2 if video == "mp4" else 1
    if isinstance(scale, bool) or not isinstance(scale, int) or scale < 1:
        raise ValueError(f"scale must be a positive integer, got {scale!r}")
    if progress_every < 1:
        raise ValueError(f"progress_every must be >= 1, got {progress_every}")
    threshold = _check_threshold(threshold)
    source = Path(source)
    out = Path(out)
    if config is None and (source / RECORDED_SCENE).is_file():
        config = source / RECORDED_SCENE
    scene = load_config(config) if fps is None else load_config(config, surface={"fps": fps})
    opened = _open(source)
    if (
        fps is None
        and opened.fps is not None
        and not math.isclose(opened.fps, scene.surface.fps, rel_tol=0.01)
    ):
        warnings.warn(
            f"{source} is recorded at {opened.fps:g} fps but the scene simulates "
            f"{scene.surface.fps:g} fps; pass fps={opened.fps:g} to replay it at its own rate",
            UserWarning,
            stacklevel=2,
        )
    total = opened.count if limit is None or opened.count is None else min(limit, opened.count)
    out.mkdir(parents=True, exist_ok=True)

    contacts: list[int] = []
    particles: list[int] = []
    timings: dict[str, list[float]] = {stage: [] for stage in STAGES}
    positions: dict[str, list[NDArray[np.float64]]] = {o.name: [] for o in scene.objects}
    yaws: dict[str, list[float]] = {o.name: [] for o in scene.objects}
    sink = _VideoOut(out / f"replay.{video}", scene.surface.fps)
    started = time.perf_counter()
    with make_simulation(scene) as sim:
        start = {name: sim.object_pose(name) for name in sim.object_names}
        previous = {name: yaw_of(q) for name, (_, q) in start.items()}
        unwrapped = dict(previous)
        masks = _masks(opened, scene.surface.resolution, threshold)
        try:
            for index, mask in enumerate(itertools.islice(masks, limit)):
                report = sim.step(mask)
                contacts.append(report.n_contacts)
                particles.append(report.n_particles)
                for stage in STAGES:
                    timings[stage].append(report.timings[stage])
                for name in sim.object_names:
                    position, q = sim.object_pose(name)
                    now = yaw_of(q)
                    unwrapped[name] += yaw_step(now, previous[name])
                    previous[name] = now
                    positions[name].append(position)
                    yaws[name].append(unwrapped[name])
                sink.add(index, _picture(sim, mask, report, scale))
                done = index + 1
                if progress is not None and done % progress_every == 0:
                    progress(done, total)
        finally:
            masks.close()  # releases a video capture left part-read by ``limit``
            written = sink.close()
    if progress is not None and contacts and len(contacts) % progress_every:
        progress(len(contacts), total)

    result = ReplayResult(
        source=source,
        fps=scene.surface.fps,
        contacts=np.asarray(contacts, np.int64),
        particles=np.asarray(particles, np.int64),
        timings={stage: np.asarray(t, float) for stage, t in timings.items()},
        objects={
            name: ObjectTrack(
                name=name,
                start_position=np.asarray(start[name][0], float),
                start_yaw=yaw_of(start[name][1]),
                position=np.asarray(positions[name], float).reshape(-1, 3),
                yaw=np.asarray(yaws[name], float),
            )
            for name in positions
        },
        wall_seconds=time.perf_counter() - started,
        scene=scene,
        files=[written, out / "summary.json", out / "summary.txt"],
    )
    (out / "summary.json").write_text(json.dumps(result.summary(), indent=2) + "\n")
    (out / "summary.txt").write_text(result.text() + "\n")
    return result
