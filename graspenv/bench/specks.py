"""The speck filter (``contacts.min_area``) against sensor noise, measured.

1. The canonical turn (``graspenv.bench.scenarios.turn_scene``) seen through flipped
   pixels (``SensorNoise.salt_pepper``), at several filter sizes: contacts a frame
   and the box's yaw error at the end of the turn.
2. The bench's noisy turn (holes, jitter, blur; no flipped pixels) on a 320 × 240
   table at 12 sub-pixel placements, at several filter sizes: the mean and largest
   |yaw error|.

Run: ``python -m graspenv.bench.specks`` (about two minutes).
"""

from __future__ import annotations

import math

import numpy as np

from graspenv.bench import scenarios
from graspenv.config import load_config
from graspenv.geometry import yaw_of
from graspenv.simulation import Simulation
from graspenv.surface.noise import SensorNoise
from graspenv.surface.render import render_mask


def flipped_pixels() -> None:
    print("| flipped pixels | min_area (pixels) | contacts a frame | yaw error |")
    print("|---|---|---|---|")
    base = load_config(None)
    for salt in (0.0, 0.0005, 0.002):
        for area in (0.0, 2.0, 4.0, 9.0):
            scene, script = scenarios.turn_scene(base.replace(contacts={"min_area": area}))
            noise = SensorNoise(salt_pepper=salt)
            rng = np.random.default_rng(0)
            with Simulation(scene) as sim:
                contacts = []
                for _, hand in script.frames(sim.surface):
                    mask = render_mask(hand, sim.surface)
                    contacts.append(sim.step(noise.apply(mask, rng) if salt else mask).n_contacts)
                yaw = yaw_of(sim.object_pose("box")[1])
            error = math.degrees(math.remainder(yaw - math.pi / 2, 2 * math.pi))
            print(f"| {100 * salt:.2f} % | {area:g} | {np.mean(contacts):.1f} | {error:+.2f}° |")


def low_resolution(placements: int = 12) -> None:
    print("\n| 320 × 240, noisy turn: min_area (pixels) | mean abs yaw error | largest |")
    print("|---|---|---|")
    for area in (0.0, 2.0, 4.0):
        base = load_config(None, surface={"resolution": [320, 240]}, contacts={"min_area": area})
        errors = [
            abs(scenarios.noisy(base, offset).errors["yaw_error_deg"])
            for offset in scenarios.placement_offsets(placements, base)
        ]
        print(f"| {area:g} | {np.mean(errors):.2f}° | {np.max(errors):.2f}° |")


if __name__ == "__main__":
    flipped_pixels()
    low_resolution()
