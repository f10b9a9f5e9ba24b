"""Two settings of the grid, cell by cell (``python -m graspenv.bench.grid_pairs``)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

from graspenv.bench import grid
from graspenv.bench.grid_pairs import main, paired


def _results(turns: list[float], slips: list[float]) -> list[grid.CellResult]:
    cells = grid.placed([grid.BASE_CELL] * len(turns), seed=1)
    held = {
        "slide_error_pct": 0.1,
        "slide_along_pct": 0.08,
        "slide_across_pct": -0.06,
        "turn_margin": 5.0,
        "slide_margin": 5.0,
    }
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
    assert "| map | figure | 0 mean abs error | b mean abs error | b − 0 (± s.e.) |" in out
    assert "| boxes | turn (°) | 0.400 | 0.500 | +0.100 ± 0.252 | 3/3 | 2/3 | 0 |" in out
    assert "| boxes | slip (%) | 3.000 | 2.333 | -0.667 ± 0.667 | 2/3 | 3/3 | 0 |" in out
    assert "| all | slide (%) | 0.100 | 0.100 | +0.000 ± 0.000 | 3/3 | 3/3 | 0 |" in out
    # The slide's parts, as sizes: the part across the travel is negative here.
    assert "| all | slide along the travel (%) | 0.080 | 0.080 | +0.000 ± 0.000 |" in out
    assert "| all | slide across it (%) | 0.060 | 0.060 | +0.000 ± 0.000 |" in out
    assert "3 cells in pairs, from 1 and 2 files." in out


def test_pairs_a_side_does_not_count_or_lacks_are_left_out_and_said(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    first = _results([0.2, 3.0, 0.4], [1.0, 1.0, 1.0])
    second = _results([0.1, 0.0, 0.2], [1.0, 1.0, 1.0])
    second[1] = replace(second[1], turn_margin=1.0)  # counted by one side only
    first[2] = replace(first[2], slip_error_pct=math.nan)  # one side has no slip
    for part in (first, second):
        part[0] = replace(part[0], slip_error_pct=math.nan, slip_error_then_pct=math.nan)
    # Both sides' files in one folder: the names cannot tell them apart.
    grid.write_csv(first, tmp_path / "a.csv")
    grid.write_csv(second, tmp_path / "b.csv")
    assert main([str(tmp_path / "a.csv"), "--", str(tmp_path / "b.csv")]) == 0
    out = capsys.readouterr().out
    assert "| first mean abs error | second mean abs error | second − first (± s.e.) |" in out
    assert "| boxes | turn (°) | 0.300 | 0.150 | -0.150 ± 0.050 | 2/2 | 2/2 | 1 |" in out
    assert "| boxes | slip (%) | 1.000 | 1.000 | +0.000 ± — | 1/1 | 1/1 | 2 |" in out
    assert "| boxes | slip at the force then (%) | 1.000 | 1.000 | +0.000 ± 0.000 | 2/2 |" in out
    # A figure no pair has keeps its row.
    for part in (first, second):
        for i in range(3):
            part[i] = replace(part[i], slide_error_pct=math.nan)
    grid.write_csv(first, tmp_path / "a.csv")
    grid.write_csv(second, tmp_path / "b.csv")
    assert main([str(tmp_path / "a.csv"), "--", str(tmp_path / "b.csv")]) == 0
    assert "| boxes | slide (%) | — | — | — | — | — | 3 |" in capsys.readouterr().out


def test_sides_with_other_cells_or_bad_arguments_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Cells that differ in any parameter are other cells (here: the squeeze depth
    alone), each side's count said; bad arguments and unreadable files end in one
    line on stderr."""
    cells = _results([0.1, 0.2, 0.3], [1.0, 1.0, 1.0])
    deeper = [replace(r, cell=replace(r.cell, depth=0.004)) for r in cells[1:]]
    grid.write_csv(cells, tmp_path / "a.csv")
    grid.write_csv(cells[:1] + deeper, tmp_path / "b.csv")
    a, b = str(tmp_path / "a.csv"), str(tmp_path / "b.csv")

    def error(argv: list[str]) -> str:
        assert main(argv) == 2
        captured = capsys.readouterr()
        assert captured.out == "" and len(captured.err.splitlines()) == 1
        return captured.err

    assert "2 on the first side only, 2 on the second" in error([a, "--", b])
    assert "usage" in error([a, b])
    assert "at least one" in error([a, "--"])
    assert "cannot read" in error([a, "--", str(tmp_path / "missing.csv")])
    (tmp_path / "bad.csv").write_text("shape,footprint\nbox,0.06\n")
    assert "lacks the column" in error([a, "--", str(tmp_path / "bad.csv")])
    grid.write_csv([], tmp_path / "empty.csv")
    empty = str(tmp_path / "empty.csv")
    assert "no cells" in error([empty, "--", empty])
    twice = _results([0.1], [1.0]) * 2
    with pytest.raises(ValueError, match="twice"):
        paired(twice, twice)
