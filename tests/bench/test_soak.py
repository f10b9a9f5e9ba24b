"""The soak's machinery on a short run (the 100 000-frame soak is `graspenv bench
--soak 100000`, never in `make test`)."""

from __future__ import annotations

from pathlib import Path

import pytest

from graspenv.bench import soak as soak_module
from graspenv.bench.soak import SoakResult, soak


def test_short_soak_keeps_every_invariant(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(soak_module, "SAMPLE", 50)
    result = soak(400)  # more than two grasp cycles: touch-downs, turns, lift-offs
    assert result.frames == 400 and result.violations == 0
    assert [frame for frame, _ in result.rss] == list(range(50, 401, 50))
    assert result.worst["speed_ratio"] < 1.0
    assert result.write(tmp_path / "soak.csv").read_text().startswith("frame,rss_mb")


def test_growth_is_measured_after_settling() -> None:
    # A start-up peak, then 0.1 MB per sample: 1.8 MB from the settled sample.
    rss = [(i * 1000, 100.0 + (30.0 if i == 0 else 0.0) + 0.1 * i) for i in range(20)]
    result = SoakResult(20_000, 10.0, rss, 0, {})
    assert result.growth_mb == pytest.approx(0.1 * 19 - 0.1 * 1)
    assert result.flat
    leaking = SoakResult(20_000, 10.0, [(i, 100.0 + 2.0 * i) for i in range(20)], 0, {})
    assert not leaking.flat
