"""The long fuzz (``graspenv bench --fuzz N``): its episodes cover what the issue asks,
they replay the same from a seed, and a small seeded sample keeps its record.

The sample's record is not a target: it lists the episodes that break an invariant
today, each with its cause, so that a new violation fails here and a fixed one does
too (update the list and the README's figure then). The long run's figures are the
README's ("Stability on hard cases").
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from graspenv.bench import fuzz
from graspenv.config import ConfigError, load_config

#: Seeds 0-23: the ones that break an invariant, and why. None since the sub-steps
#: follow the motion (physics.substep_travel): seed 0, a fingertip at 1.7 m/s that
#: drove a 2 g particle 1.08 mm into a 20 g cylinder in frame 8, now holds; seeds 14
#: and 20, a cylinder sinking into a slippery table, hold since cylinders have a foot.
KNOWN_BROKEN: dict[int, list[str]] = {}
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
    first, again = fuzz.play(13), fuzz.play(13)  # its particles meet the object
    assert (first.broken, first.first) == (again.broken, again.first)
    assert math.isfinite(first.deepest_mm) and first.deepest_mm == again.deepest_mm


def test_the_report_gives_the_overlap_tail(tmp_path: Path) -> None:
    # Overlaps of 0.0023, 0.0033, ... 1.0013 mm (no figure on a rounding tie), one
    # episode whose particles met an object without overlapping it and one in which
    # no particle had an object to overlap.
    outcomes = [fuzz.Outcome(k, "", deepest_mm=0.001 * k + 0.0003) for k in range(1, 1002)]
    outcomes[0].deepest_mm = 0.0
    outcomes.append(fuzz.Outcome(0, "", deepest_mm=-math.inf))
    report = fuzz.FuzzReport(outcomes, 1.0)
    tail = report.overlap_tail()
    assert "over 1000 touching episodes" in tail
    assert "median 0.502 mm, 99th percentile 0.991, 99.9th 1.000, max 1.001" in tail
    assert "502 past half of it" in tail
    lines = report.write(tmp_path / "fuzz.csv").read_text().splitlines()
    assert lines[0].startswith("seed,preset,") and lines[0].endswith(",deepest_mm")
    assert lines[3].startswith("3,default,") and lines[3].endswith(",0.0033")
    assert lines[-1].endswith(",")  # the episode with nothing to overlap: an empty cell
    assert "no particle touched" in fuzz.FuzzReport(outcomes[-1:], 1.0).overlap_tail()


def test_the_seeded_sample_keeps_its_record() -> None:
    broken = {seed: outcome.broken for seed in SAMPLE if (outcome := fuzz.play(seed)).broken}
    assert broken == KNOWN_BROKEN


#: Episodes of the long run (``graspenv bench --fuzz 10000``) that broke an invariant,
#: kept as named cases with their record today. Held since the pull onto a particle's
#: support is capped at ``physics.substep_travel`` a sub-step and follows the
#: support's slope: a 6.9 g box tipped on edge (509), particles climbing a ball's or
#: a tilted box's or cylinder's top (911, 4125, 8861), light boxes and cylinders
#: knocked about by fast fingertips (2371, 2934, 6416, 8716, 9984). Held since the
#: objects are reduced-coordinate bodies with 0.3 mm a sub-step (they broke by
#: 0.01-0.05 mm over the 1 mm allowed): a 5.3 g box struck at 3.65 m/s (1969), a
#: 439 g cylinder (4876) and a 767 g ball (5965) pressed by particles riding on their
#: tops. Held since a disc that fits under an overhang rests on the table: a 6.8 g
#: ball spun by particles put on its flank (2701). Held since a new contour point far
#: from its anchor is put down where it is: a 19.1 g cylinder of friction 1.56 with
#: two fingertips on its top whose contacts merge (6571), dragged to 1.06 times the
#: speed bound by particles that raced along the merged contour (0.24 times now).
#: Held since a particle's contacts form 1 mm before it touches
#: (``physics.contact_breaking_threshold``; 3.5 µm before): particles that closed on
#: a box faster than that in a sub-step and ended 1.03-1.23 mm inside it, on the top
#: of a 5.9 g box (1580), at the foot of a tall 20.5 g box tipping in a two-finger
#: squeeze (2054) and of a 103 g box under six fingers (3474). Held since a fast
#: frame may take 32 sub-steps (``physics.max_substeps``; 16 before): a 53.6 g box on
#: a table of friction 1.81, pushed at its foot by a particle under five fingers,
#: rattling in stick-slip (its spin changing sign every sub-step, about 10 rad/s) in
#: a frame at the old cap of 16, which let the particle 1.033 mm into it (9743;
#: 0.28 mm at 32). Held since a sub-step may move a point 0.25 mm, not 0.3: a 991 g
#: box of friction 1.95 on a table of friction 1.10, shoved by four fingertips at up
#: to 3.14 m/s, whose 99 g particle was driven 1.79 mm into it over five sub-steps
#: of frame 9 while the other fingers' particles pressed it back (4192; 0.15 mm now).
#: Held since a rocked cylinder has no side to be put down beside (a side for
#: cylinders leaning under 5 % of their radius was tried on 2026-12-06 and
#: reverted): particles put down beside the foot of a 1.62 kg cylinder of friction
#: 1.73 under five fingertips pressed it at 68 N, spun it to 17 rad/s and flung it
#: at 2.40 m/s against a bound of 1.97 (9947; put on its top face, they do not).
#: With the followed points smoothed (``proxy.smoothing`` 0.5, tried as the default
#: on 2026-12-07) it broke again, 2.01 m/s: particles put down beside their anchors
#: started up to 2.7 mm inside the leaning cylinder (no side to keep the offset
#: out), one pressed it at 434 N in a sub-step and it flew 9 cm up (without the
#: smoothing 77 mm, within the bound but no less wrong). A new particle beside its
#: anchor that would overlap a box's or a cylinder's footprint by more than a quarter
#: of its radius is now put down where its point is: the fingers push the cylinder
#: along at 0.68 m/s at most (tests/proxies/test_put_down.py; docs/stability.md,
#: "Seed 9947 again").
HELD = (
    509,
    911,
    1580,
    1969,
    2054,
    2371,
    2701,
    2934,
    3474,
    4125,
    4192,
    4876,
    5965,
    6416,
    6571,
    8716,
    8861,
    9743,
    9947,
    9984,
)


#: Episodes of the long run that break an invariant today, with their record: not a
#: target, so that a fix fails here too (then move the seed to HELD and update the
#: README). None since 4192 holds.
OPEN: dict[int, list[str]] = {}

#: Every named case's record: nothing broken for the held ones.
RECORD: dict[int, list[str]] = {seed: [] for seed in HELD} | OPEN


@pytest.mark.parametrize("seed", sorted(RECORD), ids=str)
def test_the_named_fuzz_cases_keep_their_record(seed: int) -> None:
    assert fuzz.play(seed).broken == RECORD[seed]


#: The same at the ``fast`` preset (the default without CCD), from its long run
#: (``graspenv bench --fuzz 10000 --preset fast``, docs/stability.md, "Stability on
#: hard cases"). Held since a bottom particle's fall carries no more than the pull's speed
#: from one sub-step to the next: a particle put down at the edge of a 6.3 g box,
#: its support measured on the box's top, slid off the edge under the press and fell
#: 10 mm in four sub-steps, 1.45 mm into the table without CCD (6581). Held since the
#: penetration limit also measures a point from the side its particle presses: a
#: 110 g box of friction 0.62 on a table of friction 0.09, six fingertips sliding
#: into it 1-5 mm inside its edge, their points never deeper than the 7 mm margin
#: from that edge while their particles, stopped at the face they entered by, fell
#: up to 45 mm behind and threw it off at 2.36 m/s against a bound of 2.11 (2575).
FAST_HELD = (2575, 6581)
FAST_OPEN: dict[int, list[str]] = {}
FAST_RECORD: dict[int, list[str]] = {seed: [] for seed in FAST_HELD} | FAST_OPEN


@pytest.mark.parametrize("seed", sorted(FAST_RECORD), ids=str)
def test_the_named_fast_fuzz_cases_keep_their_record(seed: int) -> None:
    assert fuzz.play(seed, preset="fast").broken == FAST_RECORD[seed]


def _must_not_play(seed: int, preset: str = "default", config: str | None = None) -> fuzz.Outcome:
    raise AssertionError("played an episode")


def test_fuzz_refuses_an_unknown_preset_before_it_plays(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fuzz, "play", _must_not_play)
    with pytest.raises(ValueError, match="fidelity must be one of"):
        fuzz.run_fuzz(1, preset="fastest")


def test_an_episode_takes_a_scene_files_settings(tmp_path: Path) -> None:
    """``--config``: the file's settings, the episode's own objects and table."""
    scene_file = tmp_path / "held.toml"
    scene_file.write_text("[proxy]\nhold_time = 0.05\n")
    plain, held = fuzz.episode(7), fuzz.episode(7, load_config(scene_file))
    assert held.scene.proxy.hold_time == 0.05 and plain.scene.proxy.hold_time == 0.0
    assert held.scene.objects == plain.scene.objects
    assert held.scene.replace(proxy={"hold_time": 0.0}) == plain.scene
    # The report names the file, so that a failing seed can be played again.
    assert "over held.toml" in fuzz.FuzzReport([], 1.0, "reference", "held.toml").text()


def test_fuzz_refuses_a_bad_scene_file_before_it_plays(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(fuzz, "play", _must_not_play)
    bad = tmp_path / "bad.toml"
    bad.write_text("[proxy]\nhold = 1\n")
    with pytest.raises(ConfigError, match="hold"):
        fuzz.run_fuzz(1, config=str(bad))
