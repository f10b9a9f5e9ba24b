"""``graspenv demo``: the paper's signature interaction on the built-in scene.

Two fingertips come down either side of the box, squeeze it, turn it 90° in place
and slide it 10 cm, then lift. Every frame is rendered into a contact mask and sent
through the whole pipeline. The demo writes an animation and a contact sheet of the
frames (mask, tracked contours, particles, the box's outline) and prints the box's
yaw and travel against the fingers'.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.bench.interactions import pinch
from graspenv.config import ObjectConfig, SceneConfig, load_config
from graspenv.contacts.tracking import ContactFrame
from graspenv.geometry import yaw_of, yaw_step
from graspenv.replay import draw_table
from graspenv.simulation import Simulation
from graspenv.surface.render import render_mask
from graspenv.surface.scripts import Script
from graspenv.viz import contact_sheet, put_label, write_animation

__all__ = ["DemoResult", "pinch_script", "run_demo"]

# How far each finger pushes into the box's face once squeezing, and the moves.
DEPTH = 0.003
TURN = math.pi / 2
SLIDE = (0.10, 0.0)


def pinch_script(obj: ObjectConfig) -> Script:
    """Squeeze ``obj`` across its x extent, turn it 90° in place, slide it 10 cm, lift."""
    return pinch(
        obj, DEPTH, turn=TURN, slide=SLIDE, turn_frames=90, slide_frames=90, hold_frames=15
    )


@dataclass
class DemoResult:
    """What the demo measured and wrote."""

    finger_turn: float
    object_turn: float
    finger_travel: float
    object_travel: float
    frames: int
    sim_seconds: float
    wall_seconds: float
    warm_up_seconds: float = 0.0
    files: list[Path] = field(default_factory=list)

    def summary(self) -> str:
        yaw_error = math.degrees(self.object_turn - self.finger_turn)
        slide = self.object_travel / self.finger_travel if self.finger_travel else float("nan")
        return "\n".join(
            [
                f"compiled kernels ready in {self.warm_up_seconds:.1f} s (compiled on a "
                "machine's first run, loaded from the cache after)",
                f"frames: {self.frames} ({self.sim_seconds:.2f} s simulated in "
                f"{self.wall_seconds:.2f} s, "
                f"{self.sim_seconds / self.wall_seconds:.1f}× real time)",
                f"turn:  fingers {math.degrees(self.finger_turn):7.2f}°  box "
                f"{math.degrees(self.object_turn):7.2f}°  error {yaw_error:+.2f}°",
                f"slide: fingers {100 * self.finger_travel:7.2f} cm box "
                f"{100 * self.object_travel:7.2f} cm  ratio {slide:.3f}",
            ]
        )


# Pictures are drawn at twice the camera resolution and cropped around the action.
_SCALE = 2
_HALF_CROP = 300
# The animation keeps every third frame at half size: small enough for a README.
_GIF_STRIDE = 3


def _picture(
    sim: Simulation,
    mask: NDArray[np.uint8],
    contacts: ContactFrame,
    obj: ObjectConfig,
    centre: NDArray[np.float64],
    labels: list[str],
) -> NDArray[np.uint8]:
    """One annotated frame: mask (grey), box (blue), contours (by id), particles (red).

    Args:
        centre: world point the picture is centred on, metres, shape (2,).
    """
    surface = sim.surface
    canvas = draw_table(sim, mask, contacts, _SCALE, [obj])
    h, w = canvas.shape[:2]
    c = (surface.world_to_pixel(centre) + 0.5) * _SCALE
    lo = np.clip(np.round(c).astype(int) - _HALF_CROP, 0, [w - 2 * _HALF_CROP, h - 2 * _HALF_CROP])
    crop = np.ascontiguousarray(
        canvas[lo[1] : lo[1] + 2 * _HALF_CROP, lo[0] : lo[0] + 2 * _HALF_CROP]
    )
    for row, text in enumerate(labels):
        put_label(crop, text, row)
    return crop


def _warm_up(scene: SceneConfig, script: Script, frames: int = 40) -> float:
    """Play the script's first frames once, untimed by the demo, so that its speed
    is the pipeline's and not numba's: seconds it took (the kernels compile on a
    machine's first run and load from the cache after)."""
    start = time.perf_counter()
    with Simulation(scene) as sim:
        for index, hand in script.frames(sim.surface):
            if index >= frames:
                break
            sim.step(render_mask(hand, sim.surface))
    return time.perf_counter() - start


def run_demo(
    out: Path, config: str | Path | SceneConfig | None = None, frames: int | None = None
) -> DemoResult:
    """Run the squeeze–turn–slide on a scene's first object and write pictures.

    Args:
        out: folder for ``demo.gif``, ``demo.png`` and ``demo.txt`` (created).
        config: scene (default: the built-in one, a 6 cm box).
        frames: stop after this many camera frames (default: the whole script).

    Returns:
        The measured turn and travel of the fingers and the object, and the files.
    """
    scene = load_config(config)
    if not scene.objects:
        raise ValueError("the demo needs a scene with at least one object")
    obj = scene.objects[0]
    script = pinch_script(obj)
    total = script.n_frames if frames is None else min(frames, script.n_frames)
    ranges = dict(script.phase_ranges())
    out.mkdir(parents=True, exist_ok=True)

    pictures: list[NDArray[np.uint8]] = []
    sheet: list[NDArray[np.uint8]] = []
    sheet_frames = {
        ranges["touch"][-1],
        ranges["squeeze"][-1],
        ranges["turn"][len(ranges["turn"]) // 2],
        ranges["turn"][-1],
        ranges["slide"][len(ranges["slide"]) // 2],
        ranges["slide"][-1],
    }
    warm_up = _warm_up(scene, script)
    wall = 0.0
    with Simulation(scene) as sim:
        start_position, start_q = sim.object_pose(obj.name)
        yaw = unwrapped = yaw_of(start_q)
        first_hand = None
        last_hand = None
        for index, hand in script.frames(sim.surface):
            if index >= total:
                break
            first_hand = first_hand or hand
            mask = render_mask(hand, sim.surface)
            report = sim.step(mask)
            wall += report.total_time
            _, q = sim.object_pose(obj.name)
            new_yaw = yaw_of(q)
            unwrapped += yaw_step(new_yaw, yaw)
            yaw = new_yaw
            if hand.is_touching("thumb"):
                last_hand = hand
            phase = next(name for name, r in ranges.items() if index in r)
            labels = [
                f"frame {index:3d}  {phase}",
                f"particles {report.n_particles}  box yaw "
                f"{math.degrees(unwrapped - yaw_of(start_q)):6.1f} deg",
            ]
            centre = np.asarray(obj.position) + np.asarray(SLIDE) / 2
            picture = _picture(sim, mask, report.contacts, obj, centre, labels)
            if index % _GIF_STRIDE == 0:
                half = cv2.resize(picture, None, fx=0.5, fy=0.5, interpolation=cv2.INTER_AREA)
                pictures.append(np.array(half).astype(np.uint8))
            if index in sheet_frames:
                sheet.append(picture)
        end_position, _ = sim.object_pose(obj.name)

    assert first_hand is not None
    finger_turn = 0.0
    finger_travel = 0.0
    if last_hand is not None:
        a0 = first_hand["index"].centre - first_hand["thumb"].centre
        a1 = last_hand["index"].centre - last_hand["thumb"].centre
        finger_turn = math.atan2(a0[0] * a1[1] - a0[1] * a1[0], float(a0 @ a1))
        m0 = (first_hand["index"].centre + first_hand["thumb"].centre) / 2
        m1 = (last_hand["index"].centre + last_hand["thumb"].centre) / 2
        finger_travel = float(np.linalg.norm(m1 - m0))
    result = DemoResult(
        finger_turn=finger_turn,
        object_turn=unwrapped - yaw_of(start_q),
        finger_travel=finger_travel,
        object_travel=float(np.linalg.norm((end_position - start_position)[:2])),
        frames=min(total, script.n_frames),
        sim_seconds=total / scene.surface.fps,
        wall_seconds=wall,
        warm_up_seconds=warm_up,
    )
    result.files.append(
        write_animation(pictures, out / "demo.gif", scene.surface.fps / _GIF_STRIDE)
    )
    if sheet:
        png = out / "demo.png"
        cv2.imwrite(str(png), contact_sheet(sheet, columns=3))
        result.files.append(png)
    text = out / "demo.txt"
    text.write_text(result.summary() + "\n")
    result.files.append(text)
    return result
