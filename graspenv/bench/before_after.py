"""Before against after: the bench errors, the interactions table and the strategy
benchmark of two runs of the project, side by side.

A change that makes things faster must keep the results. Run the same three
commands on both trees, then compare the folders::

    graspenv interactions --out DIR/interactions.md
    graspenv bench --replays 1 --out DIR/bench
    graspenv compare --episodes 100 --out DIR/compare
    python -m graspenv.bench.before_after BEFORE_DIR AFTER_DIR

What counts as a change:

- **Bench errors** (``bench.csv``): each error is the mean |error| over sub-pixel
  placements, with the largest beside it. An after figure is *worse beyond the
  spread* when its mean |error| exceeds the before run's largest (worse on average
  than the before run was at any placement), and *better beyond the spread* when
  even its largest is below the before run's mean. The physics is chaotic in the
  last bits (a 1e-15 change moves a slide by millimetres), so no figure is expected
  to be bit-identical.
- **Interactions** (``interactions.md``): every figure of the persistent column, and
  whether each row's expectation still holds.
- **Strategy benchmark** (``compare.csv``): an after success rate outside the before
  run's 95 % Wilson interval.

Prints Markdown; exits 1 when a figure got worse beyond its spread or a success rate
left its interval.
"""

from __future__ import annotations

import csv
import math
import sys
from pathlib import Path


def _float(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return math.nan


def bench_rows(path: Path) -> dict[tuple[str, str], dict[str, float]]:
    with path.open() as f:
        return {
            (row["setting"], row["scenario"]): {k: _float(v) for k, v in row.items()}
            for row in csv.DictReader(f)
        }


def compare_bench(before: Path, after: Path) -> tuple[list[str], int]:
    a, b = bench_rows(before), bench_rows(after)
    lines = [
        "| setting | scenario | error | before mean abs (largest) | after mean abs (largest) "
        "| verdict |",
        "|---|---|---|---|---|---|",
    ]
    beyond = 0
    signs = {"worse": 0, "better": 0, "equal": 0}
    for key in sorted(set(a) & set(b)):
        for name in sorted(a[key]):
            if not name.startswith("abs_"):
                continue
            error = name[4:]
            largest = f"max_abs_{error}"
            values = (a[key][name], a[key].get(largest), b[key][name], b[key].get(largest))
            if any(v is None or math.isnan(v) for v in values):
                continue
            before_mean, before_max, after_mean, after_max = (float(v) for v in values)  # type: ignore[arg-type]
            signs[
                "worse"
                if after_mean > before_mean
                else "better"
                if after_mean < before_mean
                else "equal"
            ] += 1
            verdict = "within spread"
            if after_mean > before_max + 1e-12:  # worse on average than any placement was
                verdict = "**worse, beyond spread**"
                beyond += 1
            elif after_max < before_mean - 1e-12:  # every placement better than the mean
                verdict = "better, beyond spread"
            lines.append(
                f"| {key[0]} | {key[1]} | {error} | {before_mean:.4g} ({before_max:.4g}) | "
                f"{after_mean:.4g} ({after_max:.4g}) | {verdict} |"
            )
    # A systematic change moves most figures one way; chaos moves them both ways.
    lines.append("")
    lines.append(
        f"Mean |error| after against before: worse in {signs['worse']}, better in "
        f"{signs['better']}, equal in {signs['equal']} of {sum(signs.values())} figures."
    )
    return lines, beyond


def interaction_rows(path: Path) -> dict[tuple[str, str], list[str]]:
    rows = {}
    for line in path.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 4 or cells[0] in ("interaction", "") or set(cells[0]) <= {"-"}:
            continue
        rows[(cells[0], cells[1])] = cells[2:]
    return rows


def compare_interactions(before: Path, after: Path) -> tuple[list[str], int]:
    a, b = interaction_rows(before), interaction_rows(after)
    lines = [
        "| interaction | figure | expected | before (persistent) | after (persistent) |",
        "|---|---|---|---|---|",
    ]
    for key in a:
        if key not in b:
            continue
        expected = a[key][0]
        lines.append(f"| {key[0]} | {key[1]} | {expected} | {a[key][1]} | {b[key][1]} |")
    return lines, 0


def compare_strategies(before: Path, after: Path) -> tuple[list[str], int]:
    def rows(path: Path) -> dict[tuple[str, str], dict[str, float]]:
        with path.open() as f:
            return {
                (r["env_id"], r["agent"]): {k: _float(v) for k, v in r.items()}
                for r in csv.DictReader(f)
            }

    a, b = rows(before), rows(after)
    lines = [
        "| environment | agent | before success (95 % CI) | after success | verdict |",
        "|---|---|---|---|---|",
    ]
    beyond = 0
    for key in sorted(set(a) & set(b)):
        x, y = a[key], b[key]
        inside = x["success_ci_low"] - 1e-9 <= y["success_rate"] <= x["success_ci_high"] + 1e-9
        beyond += not inside
        lines.append(
            f"| `{key[0]}` | {key[1]} | {100 * x['success_rate']:.0f} % "
            f"({100 * x['success_ci_low']:.0f}–{100 * x['success_ci_high']:.0f} %) | "
            f"{100 * y['success_rate']:.0f} % | "
            f"{'within the interval' if inside else '**outside the interval**'} |"
        )
    return lines, beyond


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__)
        return 2
    before, after = (Path(p) for p in argv)
    total = 0
    sections = (
        ("Bench errors", "bench/bench.csv", compare_bench),
        ("Interactions", "interactions.md", compare_interactions),
        ("Strategy benchmark", "compare/compare.csv", compare_strategies),
    )
    for title, name, compare in sections:
        if not (before / name).exists() or not (after / name).exists():
            print(f"## {title}\n\n(missing {name} in one of the folders)\n")
            continue
        lines, beyond = compare(before / name, after / name)
        total += beyond
        print(f"## {title}\n")
        print("\n".join(lines))
        print(f"\n{beyond} beyond their spread.\n")
    return 1 if total else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
