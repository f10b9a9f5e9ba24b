"""Two settings of the grid, cell by cell (``python -m graspenv.bench.grid_pairs``)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from graspenv.bench import grid
from graspenv.bench.grid_pairs import main, paired


def _results(turns: list[float], slips: list[float]) -> list[grid.CellResult]:
    cells = grid.placed([grid.BASE_CELL] * len(turns), seed=1)
    held = {"slide_error_pct": 0.1, "turn_margin": 5.0, "slide_margin": 5.0}
    return [
        grid.CellResult(
            cell, "boxes", turn_error_deg=t, slip_error_pct=s, slip_error_then_pct=s, **held
        )
        for cell, t, s in zip(cells, turns, slips, strict=True)
    ]


def test_the_cells_are_paired_and_the_differences_reported(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    first = _results([0.2, -0.4, 0.6], [1.0, -6.0, 2.0])
    second = _results([0.1, -0.2, 1.2], [1.0, 4.0, -2.0])
    # Files in another order, one run split over two files: pairs go by cell.
    grid.write_csv(first, tmp_path / "a" / "0" / "grid.csv")
    grid.write_csv(second[2:], tmp_path / "b" / "0" / "grid.csv")
    grid.write_csv(second[:2], tmp_path / "b" / "1" / "grid.csv")
    a = [str(tmp_path / "a" / "0" / "grid.csv")]
    b = [str(tmp_path / "b" / n / "grid.csv") for n in ("1", "0")]
    assert main([*a, "--", *b]) == 0
    out = capsys.readouterr().out
    # Turns |0.2, 0.4, 0.6| against |0.1, 0.2, 1.2|: means 0.4 and 0.5, paired
    # differences -0.1, -0.2, +0.6 (mean 0.1, s.e. 0.25), 1.2° beyond the target.
    assert "| boxes | turn (°) | 0.400 | 0.500 | +0.100 ± 0.252 | 3/3 | 2/3 |" in out
    assert "| boxes | slip (%) | 3.000 | 2.333 | -0.667 ± 0.667 | 2/3 | 3/3 |" in out
    assert "| all | slide (%) | 0.100 | 0.100 | +0.000 ± 0.000 | 3/3 | 3/3 |" in out
    assert "3 cells in pairs, from 1 and 2 files." in out


def test_a_turn_the_grip_cannot_hold_is_left_out_of_the_pairs(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    first = _results([0.2, 3.0], [1.0, 1.0])
    second = _results([0.1, 0.0], [1.0, 1.0])
    second[1] = replace(second[1], turn_margin=1.0)  # counted by one side only
    grid.write_csv(first, tmp_path / "a.csv")
    grid.write_csv(second, tmp_path / "b.csv")
    assert main([str(tmp_path / "a.csv"), "--", str(tmp_path / "b.csv")]) == 0
    out = capsys.readouterr().out
    assert "| boxes | turn (°) | 0.200 | 0.100 | -0.100 ± nan | 1/1 | 1/1 |" in out


def test_sides_with_other_cells_or_bad_arguments_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    grid.write_csv(_results([0.1, 0.2], [1.0, 1.0]), tmp_path / "a.csv")
    grid.write_csv(_results([0.1], [1.0]), tmp_path / "b.csv")
    a, b = str(tmp_path / "a.csv"), str(tmp_path / "b.csv")
    assert main([a, "--", b]) == 2
    assert "different cells (1 on one side only" in capsys.readouterr().out
    assert main([a, b]) == 2 and "usage" in capsys.readouterr().out
    assert main([a, "--"]) == 2 and "at least one" in capsys.readouterr().out
    twice = _results([0.1], [1.0]) * 2
    with pytest.raises(ValueError, match="twice"):
        paired(twice, twice)
