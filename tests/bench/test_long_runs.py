"""The long runs, behind ``make slow`` and never in ``make test``: the README's soak
and the first thousand episodes of the long fuzz (129 s together on two cores), and
the presets' drift that ``fidelity="auto"`` chooses by (90 s)."""

from __future__ import annotations

import math

import pytest

from graspenv.bench import fuzz
from graspenv.bench.frontier import run_bench
from graspenv.bench.scenarios import SCENARIOS
from graspenv.bench.soak import soak
from graspenv.config import PRESET_DRIFT_MM

pytestmark = pytest.mark.slow

#: Seeds 0-999 of the long fuzz that break an invariant today, and why; the same
#: kind of record as the seeded sample of ``test_fuzz.py`` (a new violation fails
#: here, and so does a fixed one: update the list and the README's figure then).
#: None since the pull onto a particle's support is capped and follows the support's
#: slope (graspenv/physics/control.py): seed 509, a 6.9 g box tipped on edge whose
#: new particle was pulled 26 mm down its tilted face at 2.4 m/s (1.07 mm inside
#: it), and seed 911, a particle climbing an 878 g ball's shoulder pulled into it by
#: the height measured at the frame's start (1.40 mm), now hold.
LONG_KNOWN_BROKEN: dict[int, list[str]] = {}


def test_the_soak_keeps_every_invariant_and_a_flat_memory() -> None:
    result = soak(100_000)
    assert result.frames == 100_000
    assert result.violations == 0, result.worst
    assert result.flat, result.rss


def test_a_thousand_fuzz_episodes_keep_their_record() -> None:
    report = fuzz.run_fuzz(1000, first_seed=0, workers=2)
    broken = {o.seed: o.broken for o in report.outcomes if o.broken}
    assert broken == LONG_KNOWN_BROKEN


def test_the_presets_drift_as_recorded_for_auto() -> None:
    """``PRESET_DRIFT_MM`` is each preset's worst drift against the reference over the
    bench's scenarios at three placements, as ``graspenv bench`` measures it; a change
    that moves a preset's final poses must record its new figure (and the README's)."""
    # The reference's own drift is 0 by definition; the slip has none (NaN).
    settings = {"preset:fast": "fast", "default": "default"}
    results = run_bench(list(settings), list(SCENARIOS), placements=3)
    for setting, preset in settings.items():
        drifts = [r.reference_drift_mm for r in results if r.setting == setting]
        worst = max(d for d in drifts if math.isfinite(d))
        assert worst == pytest.approx(PRESET_DRIFT_MM[preset], abs=0.01), (setting, worst)
