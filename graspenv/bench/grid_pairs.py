"""Two settings of the grasp-space grid, cell by cell.

Run the grid at each setting with the same seeds, then pair the cells::

    graspenv bench --grid --workers 2 --seed S --out A/S                      # S = 0 1 2 3
    graspenv bench --grid --workers 2 --seed S --preset reference --out B/S
    python -m graspenv.bench.grid_pairs A/*/grid.csv -- B/*/grid.csv

For each map and each figure (the turn and the slide in the cells both settings
count, the slide's parts along the travel and across it, the slip against Coulomb's
force at the settled normal force and at the force just before the slip, and the
same at the slip's onset), it gives each setting's mean
|error| over the cells both measured, the mean of the paired differences (second
minus first) with its standard error, and how many cells each puts within the
target. Pairing cancels what a cell's two runs share (the grasp and its place on
the table), so a setting's own effect shows at a few hundredths of a degree where
the cells' errors spread over tenths.
The placements (``--seed``) are the samples: one seed gives one run of each cell.

Prints Markdown; exits 2 if the two sides do not hold the same cells.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from graspenv.bench.grid import (
    SLIDE_TARGET_PCT,
    SLIP_TARGET_PCT,
    TURN_TARGET_DEG,
    Cell,
    CellResult,
    read_csv,
)
from graspenv.bench.results import pipe_table

__all__ = ["FIGURES", "main", "paired", "table"]

#: Each figure: its name, the CellResult field, its target, its unit, and which
#: cells it counts (a turn or slide only where the grip holds with the margin).
FIGURES: tuple[tuple[str, str, float, str, Callable[[CellResult], bool]], ...] = (
    ("turn", "turn_error_deg", TURN_TARGET_DEG, "°", lambda r: r.turn_counted),
    ("slide", "slide_error_pct", SLIDE_TARGET_PCT, "%", lambda r: r.slide_counted),
    ("slide along the travel", "slide_along_pct", SLIDE_TARGET_PCT, "%", lambda r: r.slide_counted),
    ("slide across it", "slide_across_pct", SLIDE_TARGET_PCT, "%", lambda r: r.slide_counted),
    ("slip", "slip_error_pct", SLIP_TARGET_PCT, "%", lambda r: True),
    ("slip at the force then", "slip_error_then_pct", SLIP_TARGET_PCT, "%", lambda r: True),
    ("slip, Bullet's normal tilt out", "slip_untilted_pct", SLIP_TARGET_PCT, "%", lambda r: True),
    ("slip at its onset", "slip_onset_error_pct", SLIP_TARGET_PCT, "%", lambda r: True),
    ("slip at its onset, force then", "slip_onset_then_pct", SLIP_TARGET_PCT, "%", lambda r: True),
)


def paired(
    first: Sequence[CellResult], second: Sequence[CellResult]
) -> list[tuple[CellResult, CellResult]]:
    """The two runs of each cell, in ``first``'s order.

    Args:
        first: one setting's results (one or more grid runs).
        second: the other's, with the same cells (map, grasp and place).

    Returns:
        (first's, second's) result of each cell.

    Raises:
        ValueError: a cell is on one side only, or twice on one side.
    """

    def keyed(results: Sequence[CellResult], side: str) -> dict[tuple[str, Cell], CellResult]:
        out: dict[tuple[str, Cell], CellResult] = {}
        for r in results:
            if (r.map, r.cell) in out:
                raise ValueError(f"the {side} side holds {r.map} {r.cell} twice")
            out[(r.map, r.cell)] = r
        return out

    a, b = keyed(first, "first"), keyed(second, "second")
    only_a, only_b = a.keys() - b.keys(), b.keys() - a.keys()
    if only_a or only_b:
        name, cell = min(only_a or only_b, key=str)
        raise ValueError(
            f"the two sides hold different cells: {len(only_a)} on the first side only, "
            f"{len(only_b)} on the second (e.g. {name} {cell}); run both with the same "
            "seeds and maps"
        )
    return [(a[k], b[k]) for k in a]


def table(pairs: Sequence[tuple[CellResult, CellResult]], names: tuple[str, str]) -> str:
    """Markdown: per map (and all), per figure, each side's mean abs error and count
    within the target, and the mean paired difference ± its standard error.

    Args:
        pairs: from :func:`paired`.
        names: the two sides' names, for the header.

    Returns:
        The table. A pair one side does not count (its margin under 2) or has no
        figure for (NaN) is left out of that figure, and the last column says how
        many were.
    """
    first, second = names
    header = (
        "map",
        "figure",
        f"{first} mean abs error",
        f"{second} mean abs error",
        f"{second} − {first} (± s.e.)",
        f"{first} within",
        f"{second} within",
        "left out",
    )
    groups: dict[str, list[tuple[CellResult, CellResult]]] = {}
    for pair in pairs:
        groups.setdefault(pair[0].map, []).append(pair)
    groups["all"] = list(pairs)
    rows = []
    for name, group in groups.items():
        for label, field, target, unit, counts in FIGURES:
            both = [(p, q) for p, q in group if counts(p) and counts(q)]
            a = np.array([abs(getattr(p, field)) for p, _ in both], dtype=float)
            b = np.array([abs(getattr(q, field)) for _, q in both], dtype=float)
            keep = np.isfinite(a) & np.isfinite(b)
            a, b = a[keep], b[keep]
            figures = ["—"] * 5
            if a.size:
                diff = b - a
                error = "—"
                if diff.size > 1:
                    error = f"{float(np.std(diff, ddof=1) / math.sqrt(diff.size)):.3f}"
                figures = [
                    f"{a.mean():.3f}",
                    f"{b.mean():.3f}",
                    f"{diff.mean():+.3f} ± {error}",
                    f"{int(np.sum(a <= target))}/{a.size}",
                    f"{int(np.sum(b <= target))}/{b.size}",
                ]
            rows.append((name, f"{label} ({unit})", *figures, len(group) - a.size))
    return pipe_table(header, rows)


def main(argv: Sequence[str]) -> int:
    """``FIRST.csv … -- SECOND.csv …``: print the paired table (exit 0), or say on
    stderr what is wrong with the arguments or the files (exit 2)."""
    args = list(argv)
    if args.count("--") != 1:
        return _fail("usage: python -m graspenv.bench.grid_pairs FIRST.csv ... -- SECOND.csv ...")
    cut = args.index("--")
    sides = args[:cut], args[cut + 1 :]
    if not all(sides):
        return _fail("each side needs at least one grid.csv")
    try:
        results = [[r for path in side for r in read_csv(Path(path))] for side in sides]
        pairs = paired(*results)
    except OSError as error:
        return _fail(f"cannot read {error.filename}: {error.strerror}")
    except (KeyError, ValueError) as error:
        text = f"a file lacks the column {error}" if isinstance(error, KeyError) else error
        return _fail(f"{text}")
    if not pairs:
        return _fail("the files hold no cells")
    print(table(pairs, _side_names(sides)))
    print(f"\n{len(pairs)} cells in pairs, from {len(sides[0])} and {len(sides[1])} files.")
    return 0


def _fail(message: str) -> int:
    print(message, file=sys.stderr)
    return 2


def _side_names(sides: tuple[list[str], list[str]]) -> tuple[str, str]:
    """Each side's name: the folder its files share, or "first" and "second" where
    that does not tell them apart."""
    names = tuple(
        Path(os.path.commonpath([os.path.abspath(Path(p).parent) for p in paths])).name
        for paths in sides
    )
    if names[0] == names[1] or not all(names):
        return "first", "second"
    return names[0], names[1]


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
