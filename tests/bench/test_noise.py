"""The sensor-noise bench: its runs, its table and its files."""

from __future__ import annotations

from pathlib import Path

import pytest

from graspenv.bench import noise
from graspenv.bench.grid import Cell, placed


def test_a_noisy_grasp_is_mended_by_filling_flickering_dropouts(tmp_path: Path) -> None:
    cell = placed([Cell()], 0)[0]
    clean = noise.measure(("clean", "speck filter", cell, 0, None, "default"))
    assert clean.ok and not clean.dropped
    # FTIR-like masks: its flickering dropouts cut the fingertips' edges and the box
    # lags the turn by degrees; filled from the last frame, the grasp holds.
    raw = noise.measure(("ftir", "speck filter", cell, 0, None, "default"))
    filled = noise.measure(("ftir", "filter + fill 2 px", cell, 0, None, "default"))
    assert abs(raw.turn_error_deg) > noise.TURN_TARGET_DEG
    assert filled.ok, filled
    runs = [clean, raw, filled]
    paths = noise.write_outputs(runs, tmp_path)
    assert [p.name for p in paths] == ["noise.csv", "noise.md", "noise.png"]
    assert noise.read_csv(tmp_path / "noise.csv") == runs
    table = (tmp_path / "noise.md").read_text()
    assert "| ftir | filter + fill 2 px |" in table and "| clean | speck filter |" in table


def test_a_grasp_under_di_masks_holds_once_each_pixel_is_voted_on() -> None:
    # A 20 g box under the DI level: its edge jitter takes the turn degrees short
    # through the speck filter alone; voted over three masks, closed and filled, the
    # grasp meets both targets.
    cell = placed([Cell(mass=0.02)], 0)[0]
    raw = noise.measure(("di", "speck filter", cell, 0, None, "default"))
    voted = noise.measure(("di", "vote 3 + close 5 + fill 2", cell, 0, None, "default"))
    assert abs(raw.turn_error_deg) > 2 * noise.TURN_TARGET_DEG
    assert voted.ok, voted


def test_the_bench_plays_the_levels_and_seeds_asked_for() -> None:
    jobs = noise._jobs(noise.CELLS, None, "default", (3, 4), ("di",))
    assert {job[0] for job in jobs} == {"di"} and {job[3] for job in jobs} == {3, 4}
    assert len(jobs) == 2 * len(noise.CELLS) * len(noise.CLEANUPS)
    with pytest.raises(ValueError, match=r"levels must be .* got \['dim'\]"):
        noise.run_noise(levels=["dim"])
    with pytest.raises(ValueError, match=r"seeds must be .* got \[\]"):
        noise.run_noise(seeds=[])
    with pytest.raises(ValueError, match=r"seeds must be .* got \[-1\]"):
        noise.run_noise(seeds=[-1])


def test_a_scene_files_clean_ups_do_not_carry_into_the_benchs_own() -> None:
    # Every clean-up sets every clean-up setting: the DI table's file (vote, closing
    # and fill on) leaves "speck filter" plain.
    di_table = Path(__file__).resolve().parents[2] / "envs_configs" / "di_table.toml"
    base = noise.base_scene(str(di_table), "default")
    plain = base.replace(**noise.CLEANUPS["speck filter"]).contacts
    assert (plain.vote_frames, plain.close_px, plain.fill_px) == (1, 0, 0)
