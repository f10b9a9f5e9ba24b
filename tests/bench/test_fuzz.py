"""The long fuzz (``graspenv bench --fuzz N``): its episodes cover what the issue asks,
they replay the same from a seed, and a small seeded sample keeps its record.

The sample's record is not a target: it lists the episodes that break an invariant
today, each with its cause, so that a new violation fails here and a fixed one does
too (update the list and the README's figure then). The long run's figures are the
README's ("Stability on hard cases").
"""

from __future__ import annotations

import math

import numpy as np

from graspenv.bench import fuzz

#: Seeds 0-23: the ones that break an invariant, and why.
KNOWN_BROKEN = {
    # Since the particles weigh a tenth of the lightest object (2 g beside this 20 g
    # cylinder; proxy.mass_ratio): a fingertip at 1.7 m/s drives one 1.08 mm into
    # it in frame 8 (tolerance 1 mm). At a fixed 20 g it kept the invariants, but
    # 123 of seeds 0-999 broke one against 112 with the ratio. (Seeds 14 and 20, a
    # cylinder sinking into a slippery table, hold since cylinders have a foot.)
    0: ["inside_object"],
}
SAMPLE = range(24)


def test_episodes_cover_the_hard_space() -> None:
    episodes = [fuzz.episode(seed) for seed in range(400)]
    objects = [o for e in episodes for o in e.scene.objects]
    masses = [o.mass for o in objects]
    assert min(masses) < 0.01 and max(masses) > 2.5
    assert min(o.friction for o in objects) < 0.05 and max(o.friction for o in objects) > 1.9
    assert {o.shape for o in objects} == {"box", "cylinder", "sphere"}
    speeds = [math.hypot(*p.velocity) for e in episodes for p in e.fingers]
    assert max(speeds) > 4.5 and max(speeds) <= fuzz.MAX_SPEED
    assert sum(e.noise is not None for e in episodes) > 150
    assert sum(len(e.scene.objects) == 2 for e in episodes) > 25  # 40 of 400
    # The crossing pairs: two fingertips whose paths meet (their contacts merge).
    crossing = 0
    for e in episodes:
        for a, b in zip(e.fingers, e.fingers[1:], strict=False):
            meet = np.add(a.start, np.multiply(a.velocity, 0.25))
            if np.allclose(meet, np.add(b.start, np.multiply(b.velocity, 0.25)), atol=1e-9):
                crossing += 1
    assert crossing > 80


def test_an_episode_replays_the_same_from_its_seed() -> None:
    assert fuzz.episode(7) == fuzz.episode(7)
    first, again = fuzz.play(14), fuzz.play(14)
    assert (first.broken, first.first) == (again.broken, again.first)


def test_the_seeded_sample_keeps_its_record() -> None:
    broken = {seed: outcome.broken for seed in SAMPLE if (outcome := fuzz.play(seed)).broken}
    assert broken == KNOWN_BROKEN
