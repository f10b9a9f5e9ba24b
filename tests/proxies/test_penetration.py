"""The penetration limit (``proxy.penetration_limit``): a particle whose point lies
too deep inside an object goes on the top face, measured from the nearest side and
from the side the particle is at."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.typing import NDArray

from graspenv.bench.grid import Cell, slip_run
from graspenv.bench.interactions import FINGER_RADIUS, with_objects
from graspenv.config import ObjectConfig, SceneConfig, load_config
from graspenv.simulation import FrameReport, Simulation
from graspenv.surface.hand import Hand
from graspenv.surface.render import render_mask
from graspenv.surface.scripts import FingerMotion, Phase, Script
from graspenv.surface.shapes import Fingertip

# 12 x 6 x 3 cm, long along x, centred on the table's origin.
LONG_BOX = ObjectConfig(name="box", shape="box", size=(0.12, 0.06, 0.03), mass=0.11, friction=0.6)


def _along_the_edge(overlap: float, travel: float = 0.024, frames: int = 30) -> tuple[float, int]:
    """Two fingertips slide along the box's +y edge into its two ends, towards each
    other, each ``overlap`` inside the edge, ``travel`` metres past its end face.

    Returns the deepest that any particle below the top face lay behind its point
    (from the side it is at, less its radius; metres) over the run, and how many
    particles were ever on the top face."""
    scene = with_objects(load_config(None), LONG_BOX)
    half_x, half_y = LONG_BOX.size[0] / 2, LONG_BOX.size[1] / 2
    r = FINGER_RADIUS
    y = half_y + r - overlap
    start = half_x + r + 0.002
    hand = Hand()
    hand.add("left", Fingertip((-start, y), radii=(r, r)), touching=False)
    hand.add("right", Fingertip((start, y), radii=(r, r)), touching=False)
    shift = travel + 0.002
    down = {name: FingerMotion(touching=True) for name in ("left", "right")}
    slide = {
        "left": FingerMotion(touching=True, translation=(shift, 0.0)),
        "right": FingerMotion(touching=True, translation=(-shift, 0.0)),
    }
    script = Script(hand, [Phase(3, down), Phase(frames, slide), Phase(10)])
    deepest, on_top = 0.0, set()
    with Simulation(scene) as sim:
        radius = sim.world.pool.radius
        for _, frame_hand in script.frames(sim.surface):
            command = sim.step(render_mask(frame_hand, sim.surface)).command
            if command.particles.size == 0:
                continue
            bottom = command.particles.reshape(len(command.targets), -1)[:, 0]
            at = sim.world.pool.positions(bottom)
            top = at[:, 2] > LONG_BOX.size[2]
            on_top.update(bottom[top].tolist())
            inside = np.all(np.abs(command.targets) < (half_x, half_y), axis=1)
            rows = inside & ~top
            if not rows.any():
                continue
            normal = sim.world.footprint_side(at[rows, :2], 2.0 * radius)[2]
            offset = at[rows, :2] - command.targets[rows]
            behind = np.abs(np.einsum("ij,ij->i", offset, normal)) - radius
            deepest = max(deepest, float(behind.max()))
    return deepest, len(on_top)


def test_a_finger_sliding_in_along_an_edge_puts_its_particles_on_top() -> None:
    """Points 2-4 mm inside the long edge never pass the margin from that edge, but
    the particles stopped at the end face fall behind them as the fingers go on:
    measured from the end face, they go on the top face once they are more than the
    margin and a radius behind (9 mm; up to 10 mm read after a frame's travel).
    Without the measure from the particle's side they fell 18-21 mm behind, the
    whole travel, pushing on the end faces with the clamp's force. The test holds
    the measure itself; its radius of slack is the cylinder test's below."""
    proxy = load_config(None).proxy
    limit = proxy.penetration_margin + 2.0 * proxy.particle_radius
    for overlap in (0.002, 0.004):
        deepest, on_top = _along_the_edge(overlap)
        assert on_top > 0
        assert deepest < limit, f"{overlap=}: a particle fell {1000 * deepest:.1f} mm behind"


def test_a_deep_squeeze_on_a_small_cylinder_keeps_its_grip_through_a_push(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A 3 cm, 2 kg cylinder squeezed 6 mm (within the 7 mm margin) by 5 mm
    fingertips and pushed across the grip. Where CCD holds a squeezed particle (its
    sweep the particle's size, ``physics.ccd_sphere = 1``, the default until
    2026-12-06) the particle lies up to 7.5 mm behind its point measured from its
    side, more than the margin, so the measure from a particle's side allows a
    radius more. With the margin alone it put a gripping particle on the top face
    and the cylinder slipped 19.5 % short of Coulomb's force instead of 4.5 %. At
    the default the deepest reads 6.5 mm."""
    cell = Cell(shape="cylinder", footprint=0.03, mass=2.0, depth=0.006, finger_radius=0.005)
    for scene in (load_config(None), load_config(None, physics={"ccd_sphere": 1.0})):
        assert not _lifted_in_the_push(cell, scene, monkeypatch)


def _lifted_in_the_push(
    cell: Cell, scene: SceneConfig, monkeypatch: pytest.MonkeyPatch
) -> set[int]:
    """The particles that went on the cylinder's top face while it was squeezed and
    pushed until it slipped (:func:`graspenv.bench.grid.slip_run`)."""
    lifted: set[int] = set()
    step = Simulation.step

    def watched(sim: Simulation, mask: NDArray[np.uint8]) -> FrameReport:
        report = step(sim, mask)
        command = report.command
        if command.particles.size:
            bottom = command.particles.reshape(len(command.targets), -1)[:, 0]
            on_top = sim.world.pool.positions(bottom)[:, 2] > cell.height
            lifted.update(bottom[on_top].tolist())
        return report

    with monkeypatch.context() as patch:
        patch.setattr(Simulation, "step", watched)
        errors = slip_run(scene, cell).errors
    assert math.isfinite(errors["slip_force_n"]), errors
    return lifted
