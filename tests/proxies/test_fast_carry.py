"""A gripped object carried off at a jerk: single particles grip it at the table.

A touch table sees only a fingertip's footprint, so a single layer of particles
presses an object's side a particle radius above the table. Carried off at a jerk,
an object tall for its depth along the motion turns about that low grip line
(its weight holds it only while the jerk's acceleration times its centre's height
above the line is below g times its half-depth) and tips out of the grip. Stacks
put contacts higher up its side and carry it (docs/accuracy.md, "A fast carry").
"""

from __future__ import annotations

import numpy as np
import pytest

from graspenv.bench.interactions import pinch, play
from graspenv.bench.scenarios import with_objects
from graspenv.config import ObjectConfig, load_config
from graspenv.simulation import Simulation

#: 5 cm across the grip, 4 cm along the carry, 4 cm tall, 100 g: its weight holds
#: it against a push at a particle's height up to about g · 20 / 18 = 11 m/s².
TALL_BOX = ObjectConfig(
    name="box", shape="box", size=(0.05, 0.04, 0.04), mass=0.1, position=(0.0, -0.05)
)
CARRY = 0.10  # metres along +y, at a constant speed from a standstill


def _carried(stack_layers: int, speed: float) -> float:
    """How far the box ends from where the fingers took it, as a share of the carry."""
    base = load_config(None, proxy={"stack_layers": stack_layers})
    frames = round(CARRY / speed * base.surface.fps)
    script = pinch(
        TALL_BOX, 0.003, slide=(0.0, CARRY), turn_frames=0, slide_frames=frames, hold_frames=10
    )
    with Simulation(with_objects(base, TALL_BOX)) as sim:
        travel = play(sim, script, "box").travel()
    return float(np.hypot(travel[0], travel[1] - CARRY)) / CARRY


def test_a_single_layer_carries_a_tall_box_off_slowly() -> None:
    # 0.1 m/s in one frame: 6 m/s², well under what tips it.
    assert _carried(1, 0.1) < 0.01


@pytest.mark.parametrize("speed", [0.3, 1.0])
def test_stacks_carry_a_tall_box_off_at_a_jerk(speed: float) -> None:
    # From a standstill to 0.3 m/s in a frame is 18 m/s²; to 1 m/s, 60 m/s².
    assert _carried(2, speed) < 0.01


def test_a_single_layer_loses_a_tall_box_jerked_off() -> None:
    """A measured limit (docs/accuracy.md, "A fast carry"): if a single layer comes
    to hold this box, the account there should be measured again."""
    assert _carried(1, 0.3) > 0.2
