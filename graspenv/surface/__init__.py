"""The synthetic touch surface: contact shapes with exact motion, hands, scripted
finger motions, mask rendering and sensor noise (numpy and OpenCV only)."""

from __future__ import annotations

from graspenv.surface.geometry import Surface
from graspenv.surface.hand import Hand
from graspenv.surface.noise import TABLE_NOISE, SensorNoise
from graspenv.surface.render import AA_EDGE_BIAS, render_coverage, render_mask
from graspenv.surface.scripts import (
    FingerMotion,
    GroupMotion,
    Phase,
    Script,
    pinch_hand,
    release,
    side_strike,
    third_finger_push,
    top_rub,
    two_finger_pinch,
)
from graspenv.surface.shapes import (
    ContactShape,
    Fingertip,
    HandEdge,
    Palm,
    PolygonShape,
    Thumb,
)

__all__ = [
    "AA_EDGE_BIAS",
    "TABLE_NOISE",
    "ContactShape",
    "FingerMotion",
    "Fingertip",
    "GroupMotion",
    "Hand",
    "HandEdge",
    "Palm",
    "Phase",
    "PolygonShape",
    "Script",
    "SensorNoise",
    "Surface",
    "Thumb",
    "pinch_hand",
    "release",
    "render_coverage",
    "render_mask",
    "side_strike",
    "third_finger_push",
    "top_rub",
    "two_finger_pinch",
]
