"""Culling (``proxy.cull``): contour points that cannot touch an object soon have no
physics body, and get one before they can touch it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from graspenv.bench.interactions import BOX, FINGER_RADIUS, with_objects
from graspenv.config import SceneConfig, load_config
from graspenv.simulation import FrameReport, Simulation
from graspenv.surface.render import render_mask
from graspenv.surface.scripts import side_strike

DEFAULT = with_objects(load_config(None), BOX)


def _strike(scene: SceneConfig, speed: float) -> tuple[list[FrameReport], np.ndarray]:
    """A fingertip touching down 4 cm left of the box's face and moving into it
    (its leading edge 1 cm past the face) at about ``speed`` m/s."""
    face = (BOX.position[0] - BOX.size[0] / 2, BOX.position[1])
    travel = 0.05
    frames = max(2, round(travel / speed * scene.surface.fps))
    script = side_strike(face, 0.0, FINGER_RADIUS, clearance=0.04, depth=0.01, strike_frames=frames)
    with Simulation(scene) as sim:
        reports = [
            sim.step(render_mask(hand, sim.surface)) for _, hand in script.frames(sim.surface)
        ]
        position, _ = sim.object_pose("box")
    return reports, position


def test_a_hand_far_from_every_object_has_no_bodies() -> None:
    reports, _ = _strike(DEFAULT, 0.1)
    first = reports[0]
    assert first.n_contacts == 1
    # 4 cm from the face, nothing can touch the box in the next frame.
    assert first.n_particles == 0
    assert first.command.culled > 10


def test_without_culling_every_point_has_a_body() -> None:
    scene = DEFAULT.replace(proxy={"cull": False})
    reports, _ = _strike(scene, 0.1)
    first = reports[0]
    assert first.command.culled == 0
    assert first.n_particles == len(first.contacts.contacts[0].contour) > 10


@pytest.mark.parametrize("speed", [0.1, 0.5, 2.0])
def test_an_approaching_finger_gets_bodies_before_it_reaches_the_object(speed: float) -> None:
    """The first bodies appear while the contour is still clear of the box face (no
    particle is born inside the box, however fast the finger comes), and the box is
    pushed as far as without culling (at 2 m/s the three-frame strike lifts the
    particles onto the box's top, with or without culling)."""
    reports, position = _strike(DEFAULT, speed)
    face = BOX.position[0] - BOX.size[0] / 2
    embodied = [r for r in reports if r.command.particles.size]
    assert embodied, "the finger never got a body"
    first = embodied[0]
    leading = first.command.targets[:, 0].max()
    assert leading < face, f"first bodies at x = {leading:.4f}, past the face at {face}"
    _, unculled = _strike(DEFAULT.replace(proxy={"cull": False}), speed)
    if speed <= 0.5:
        assert position[0] > BOX.position[0] + 0.005  # the strike pushed it
    assert math.hypot(*(position[:2] - unculled[:2])) < 0.002


def test_a_squeezing_finger_keeps_bodies_only_on_the_side_facing_the_object() -> None:
    reports, _ = _strike(DEFAULT, 0.1)
    pressing = reports[-8]  # the leading edge is past the face
    assert pressing.command.particles.size > 0
    assert pressing.command.culled > 0
    # Every body is near the face; the trailing side (a finger diameter back) has none.
    face = BOX.position[0] - BOX.size[0] / 2
    assert pressing.command.targets[:, 0].min() > face - FINGER_RADIUS
