"""``graspenv replay``: masks from a folder or a video, through the default scene.

The recorded masks are rendered from a scripted finger striking the default box's
left face (as in :func:`graspenv.bench.interactions.side_strike_push`), so the
replay has something to find: one contact while the finger is down, none after it
lifts, and a box pushed along +x.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import cv2
import numpy as np
import pytest
from numpy.typing import NDArray

from graspenv.config import load_config
from graspenv.replay import ReplayResult, read_masks, replay
from graspenv.simulation import STAGES
from graspenv.surface.geometry import Surface
from graspenv.surface.render import render_mask
from graspenv.surface.scripts import side_strike

SCENE = load_config()
SURFACE = Surface.from_config(SCENE.surface)
RESOLUTION = SCENE.surface.resolution
SCALE = 2  # replay's default picture scale for an MP4
# Empty frames after the finger lifts: the contact must be gone in all of them.
AFTER = 8


def _strike_masks() -> list[NDArray[np.uint8]]:
    # The finger touches down 1 cm left of the box's face (x = -3 cm) and its leading
    # edge ends 2 cm past it.
    script = side_strike((-0.03, 0.0), 0.0, 0.008, clearance=0.01, depth=0.02)
    masks = [render_mask(hand, SURFACE) for _, hand in script.frames(SURFACE)]
    return masks + [np.zeros(SURFACE.shape, np.uint8)] * AFTER


@pytest.fixture(scope="module")
def strike() -> list[NDArray[np.uint8]]:
    return _strike_masks()


@pytest.fixture(scope="module")
def strike_folder(tmp_path_factory: pytest.TempPathFactory, strike: list) -> Path:
    # Unpadded numbers: a plain sort would put frame_10 before frame_2.
    folder = tmp_path_factory.mktemp("strike")
    for i, mask in enumerate(strike):
        assert cv2.imwrite(str(folder / f"frame_{i}.png"), mask)
    return folder


@pytest.fixture(scope="module")
def folder_run(
    tmp_path_factory: pytest.TempPathFactory, strike_folder: Path
) -> tuple[ReplayResult, Path]:
    out = tmp_path_factory.mktemp("out")
    return replay(strike_folder, out), out


def _video_frames(path: Path) -> tuple[int, tuple[int, int]]:
    capture = cv2.VideoCapture(str(path))
    count, size = 0, (0, 0)
    while True:
        ok, frame = capture.read()
        if not ok:
            break
        count += 1
        size = (frame.shape[1], frame.shape[0])
    capture.release()
    return count, size


def _write_mp4(path: Path, masks: list[NDArray[np.uint8]], fps: float) -> None:
    h, w = masks[0].shape
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), fps, (w, h))
    assert writer.isOpened()
    for mask in masks:
        writer.write(cv2.cvtColor(mask, cv2.COLOR_GRAY2BGR))
    writer.release()


# -- a folder of images ------------------------------------------------------------


def test_folder_replay_writes_a_full_frame_video(
    folder_run: tuple[ReplayResult, Path], strike: list
) -> None:
    result, out = folder_run
    video = out / "replay.mp4"
    assert result.files == [video, out / "summary.json", out / "summary.txt"]
    count, size = _video_frames(video)
    assert count == len(strike)
    assert size == (SCALE * RESOLUTION[0], SCALE * RESOLUTION[1])


def test_folder_summary_counts_every_image_and_finds_the_finger(
    folder_run: tuple[ReplayResult, Path], strike: list
) -> None:
    result, out = folder_run
    summary = json.loads((out / "summary.json").read_text())
    n = len(strike)
    assert summary["frames"] == n == result.frames
    per_frame = summary["per_frame"]["contacts"]
    assert len(per_frame) == n
    # One fingertip while it is down, nothing once the mask is empty.
    assert summary["contacts"]["max"] == 1
    assert per_frame[0] == 1
    assert per_frame[-AFTER:] == [0] * AFTER
    assert summary["contacts"]["mean"] == pytest.approx(np.mean(per_frame))
    assert summary["particles"]["max"] > 0
    assert summary["particles"]["mean"] == pytest.approx(np.mean(summary["per_frame"]["particles"]))
    assert summary["fps"] == SCENE.surface.fps
    assert summary["simulated_seconds"] == pytest.approx(n / SCENE.surface.fps)


def test_folder_summary_shows_the_box_pushed_along_the_strike(
    folder_run: tuple[ReplayResult, Path],
) -> None:
    _, out = folder_run
    box = json.loads((out / "summary.json").read_text())["objects"]["box"]
    start, end = np.array(box["start_position_m"]), np.array(box["end_position_m"])
    # The leading edge goes 2 cm past the face; the interaction test asks > 1 cm.
    assert end[0] - start[0] > 0.01
    assert abs(end[1] - start[1]) < 0.2 * (end[0] - start[0])
    assert box["displacement_m"] == pytest.approx(np.linalg.norm((end - start)[:2]))
    assert box["displacement_m"] <= box["travel_m"] < 1.5 * box["displacement_m"]
    assert box["end_yaw_rad"] == pytest.approx(
        math.remainder(box["start_yaw_rad"] + box["turn_rad"], 2 * math.pi)
    )
    trace = json.loads((out / "summary.json").read_text())["per_frame"]["objects"]["box"]
    assert trace["x_m"][-1] == pytest.approx(end[0], abs=1e-6)


def test_folder_summary_timings_and_text_agree(folder_run: tuple[ReplayResult, Path]) -> None:
    result, out = folder_run
    summary = json.loads((out / "summary.json").read_text())
    assert summary["pipeline_fps"] == pytest.approx(result.pipeline_fps)
    stage_ms = summary["stage_mean_ms"]
    assert list(stage_ms) == list(STAGES)
    assert all(v >= 0 for v in stage_ms.values())
    assert summary["frame_mean_ms"] == pytest.approx(sum(stage_ms.values()))
    assert summary["pipeline_fps"] == pytest.approx(1000.0 / summary["frame_mean_ms"])
    text = (out / "summary.txt").read_text()
    assert f"frames: {summary['frames']} " in text
    assert f"moved {100 * summary['objects']['box']['displacement_m']:.2f} cm" in text


def test_empty_masks_leave_the_box_where_it_was(tmp_path: Path) -> None:
    # The control for the strike: the box moves because of the masks, not by itself.
    folder = tmp_path / "empty"
    folder.mkdir()
    for i in range(10):
        cv2.imwrite(str(folder / f"{i}.png"), np.zeros(SURFACE.shape, np.uint8))
    result = replay(folder, tmp_path / "out")
    assert result.frames == 10
    assert result.contacts.max() == 0
    assert result.objects["box"].displacement < 1e-4


def test_limit_gif_and_progress(tmp_path: Path, strike_folder: Path) -> None:
    calls: list[tuple[int, int | None]] = []
    result = replay(
        strike_folder,
        tmp_path,
        limit=10,
        progress=lambda done, total: calls.append((done, total)),
        video="gif",
        progress_every=4,
    )
    assert result.frames == 10
    assert calls == [(4, 10), (8, 10), (10, 10)]
    assert result.files[0] == tmp_path / "replay.gif"
    ok, animation = cv2.imreadanimation(str(tmp_path / "replay.gif"))
    assert ok
    # One frame in every three at 60 fps (about 20 per second): frames 0, 3, 6, 9, at
    # the camera's resolution.
    assert len(animation.frames) == 4
    assert animation.frames[0].shape[:2] == SURFACE.shape
    assert json.loads((tmp_path / "summary.json").read_text())["frames"] == 10


def test_fps_overrides_the_scene_rate(tmp_path: Path, strike_folder: Path) -> None:
    result = replay(strike_folder, tmp_path, fps=30.0, limit=3)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert result.fps == summary["fps"] == 30.0
    assert summary["scene"]["surface"]["fps"] == 30.0
    assert summary["simulated_seconds"] == pytest.approx(0.1)


# -- reading masks -----------------------------------------------------------------


def test_folder_is_read_in_natural_order(tmp_path: Path) -> None:
    width, height = RESOLUTION
    for k in (1, 2, 10, 11, 3):
        mask = np.zeros((height, width), np.uint8)
        mask[0, :k] = 255  # frame k has k touched pixels
        cv2.imwrite(str(tmp_path / f"frame_{k}.png"), mask)
    (tmp_path / "notes.txt").write_text("not a frame")
    counts = [int(np.count_nonzero(m)) for m in read_masks(tmp_path, RESOLUTION)]
    assert counts == [1, 2, 3, 10, 11]


def test_threshold_rule(tmp_path: Path) -> None:
    width, height = RESOLUTION
    grey = np.zeros((height, width), np.uint8)
    grey[0, 0], grey[0, 1], grey[0, 2] = 100, 127, 128
    path = tmp_path / "grey.png"
    cv2.imwrite(str(path), grey)
    (default,) = read_masks(path, RESOLUTION)
    assert default.dtype == np.uint8
    assert default.shape == (height, width)
    assert np.flatnonzero(default).tolist() == [2]  # grey > 127
    assert set(np.unique(default).tolist()) == {0, 255}
    (any_light,) = read_masks(path, RESOLUTION, threshold=0)
    assert np.flatnonzero(any_light).tolist() == [0, 1, 2]
    with pytest.raises(ValueError, match="threshold"):
        read_masks(path, RESOLUTION, threshold=255)


def test_other_sizes_are_resized_with_one_warning(tmp_path: Path) -> None:
    width, height = RESOLUTION
    small = np.zeros((height // 2, width // 2), np.uint8)
    small[: height // 4, : width // 4] = 255  # the top-left quarter
    for i in range(3):
        cv2.imwrite(str(tmp_path / f"{i}.png"), small)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        masks = list(read_masks(tmp_path, RESOLUTION))
    assert len(caught) == 1
    assert "320×240" in str(caught[0].message)
    assert "640×480" in str(caught[0].message)
    assert all(m.shape == (height, width) for m in masks)
    assert np.count_nonzero(masks[0]) == (height // 2) * (width // 2)
    assert masks[0][: height // 2, : width // 2].all()


# -- a video -----------------------------------------------------------------------


def test_video_masks_survive_compression(tmp_path: Path, strike: list) -> None:
    path = tmp_path / "strike.mp4"
    _write_mp4(path, strike, SCENE.surface.fps)
    masks = list(read_masks(path, RESOLUTION))
    assert len(masks) == len(strike)
    for recorded, original in zip(masks, strike, strict=True):
        union = np.count_nonzero(recorded | original)
        same = np.count_nonzero(recorded & original)
        assert union == 0 or same / union > 0.9


def test_video_replay(tmp_path: Path, strike: list) -> None:
    path = tmp_path / "strike.mp4"
    _write_mp4(path, strike, SCENE.surface.fps)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # same rate as the scene: no warning
        result = replay(path, tmp_path / "out")
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["frames"] == len(strike) == result.frames
    assert summary["contacts"]["max"] == 1
    assert summary["per_frame"]["contacts"][-AFTER:] == [0] * AFTER
    box = summary["objects"]["box"]
    assert box["end_position_m"][0] - box["start_position_m"][0] > 0.01
    assert _video_frames(tmp_path / "out" / "replay.mp4")[0] == len(strike)


def test_video_at_another_rate_is_warned_of(tmp_path: Path, strike: list) -> None:
    path = tmp_path / "slow.mp4"
    _write_mp4(path, strike[:3], 30.0)
    with pytest.warns(UserWarning, match="fps=30"):
        replay(path, tmp_path / "out", limit=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert replay(path, tmp_path / "out", fps=30.0, limit=1).fps == 30.0


# -- errors a user can cause -------------------------------------------------------


def test_missing_source(tmp_path: Path) -> None:
    missing = tmp_path / "nowhere"
    with pytest.raises(FileNotFoundError, match="nowhere"):
        read_masks(missing, RESOLUTION)
    with pytest.raises(FileNotFoundError, match="nowhere"):
        replay(missing, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_empty_folder(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"no mask images in folder .*\.png"):
        read_masks(tmp_path, RESOLUTION)
    (tmp_path / "notes.txt").write_text("only notes here")
    with pytest.raises(ValueError, match="no mask images"):
        read_masks(tmp_path, RESOLUTION)


def test_unreadable_image(tmp_path: Path) -> None:
    cv2.imwrite(str(tmp_path / "frame_1.png"), np.zeros(SURFACE.shape, np.uint8))
    (tmp_path / "frame_2.png").write_bytes(b"not a png")
    masks = read_masks(tmp_path, RESOLUTION)
    assert next(masks).shape == SURFACE.shape
    with pytest.raises(ValueError, match=r"cannot read .*frame_2\.png as an image"):
        next(masks)


def test_a_file_that_is_not_a_video(tmp_path: Path) -> None:
    notes = tmp_path / "notes.txt"
    notes.write_text("hello")
    with pytest.raises(ValueError, match=r"cannot read .*notes\.txt as a video"):
        read_masks(notes, RESOLUTION)


def test_a_video_without_frames(tmp_path: Path) -> None:
    # An MJPG AVI with no frames opens but yields nothing.
    path = tmp_path / "empty.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 30.0, (64, 48))
    writer.release()
    with pytest.raises(ValueError, match=r"empty\.avi yields no frames"):
        read_masks(path, RESOLUTION)


def test_bad_arguments(tmp_path: Path, strike_folder: Path) -> None:
    with pytest.raises(ValueError, match="video"):
        replay(strike_folder, tmp_path, video="avi")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="limit"):
        replay(strike_folder, tmp_path, limit=0)
