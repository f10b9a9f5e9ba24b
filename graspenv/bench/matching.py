"""Measure the fast matcher against the exhaustive one: agreement and speed.

Run from the project root (an optional argument: fingertip frame pairs, default 2000)::

    .venv/bin/python -m graspenv.bench.matching

The exhaustive matcher's row blocks keep BLAS to one thread: on this busy two-core
machine a threaded product of 512 points took 10-20 ms instead of 0.5 ms, which would
flatter the ratio. Times are the best of interleaved runs, so a neighbour's load
slows both matchers alike.

Realistic sample: fingertip ellipses of 6-12 mm semi-axes rendered at the default
table's pixels, moving one 60 Hz frame at a speed uniform up to 0.5 m/s and turning
uniformly within ±3 rad/s, contours resampled at 2-4 mm from arbitrary start points
(point counts differ frame to frame); plus hand-sized lobed outlines of 512 points.
"""

from __future__ import annotations

import functools
import sys
import timeit
from collections.abc import Callable

import numpy as np

from graspenv.bench.contact_scenes import DT, fingertip_motion, hand_motion
from graspenv.contacts.matching import (
    _aligned_diagonal,
    _complex,
    _plan,
    match_exhaustive,
    match_fast,
    window_costs,
)
from graspenv.contacts.resample import resample_closed

WINDOW = 4
SEARCH = 3
Pair = tuple[np.ndarray, np.ndarray]


def _agreement(pairs: int, make: Callable[[np.random.Generator], Pair], seed: int) -> None:
    rng = np.random.default_rng(seed)
    total = 0
    several_peaks = 0
    by_speed: dict[int, list[int]] = {}
    misses: list[tuple[int, float, bool, bool]] = []
    for _ in range(pairs):
        p, q = make(rng)
        fast = match_fast(p, q, WINDOW, SEARCH)
        exact = match_exhaustive(p, q, WINDOW)
        several_peaks += _correlation_peaks(p, q) > 1
        differ = np.flatnonzero(fast != exact)
        speed = float(np.linalg.norm(q.mean(axis=0) - p.mean(axis=0))) / DT
        bucket = by_speed.setdefault(min(int(speed / 0.1), 5), [0, 0])
        bucket[0] += len(p)
        bucket[1] += len(differ)
        total += len(p)
        if len(differ):
            p_c, plan = _complex(p), _plan(len(p), len(q), WINDOW // 2, SEARCH)
            aligned = _aligned_diagonal(p_c, _complex(q), p_c.take(plan.walk), plan)
            aligned = aligned + np.arange(len(p))
            cost_fast = window_costs(p, q, fast, WINDOW)
            cost_exact = window_costs(p, q, exact, WINDOW)
            m = len(q)
            tangent_p = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
            tangent_q = np.roll(q, -1, axis=0) - np.roll(q, 1, axis=0)
            for k in differ:
                offset = (exact[k] - aligned[k] + m // 2) % m - m // 2
                tie = bool(np.isclose(cost_fast[k], cost_exact[k], rtol=1e-12, atol=0.0))
                # The exhaustive pick lies on a stretch of contour running the other way.
                across = float(tangent_p[k] @ tangent_q[exact[k]]) < 0.0
                misses.append((int(offset), speed, tie, across))
    print(
        f"  successors: {total}, disagreements: {len(misses)}, "
        f"agreement: {1.0 - len(misses) / total:.5f}"
    )
    print(f"  pairs whose centred correlation has more than one local maximum: {several_peaks}")
    for b in sorted(by_speed):
        n, d = by_speed[b]
        print(f"  centroid speed {0.1 * b:.1f}-{0.1 * (b + 1):.1f} m/s: {1.0 - d / n:.5f} of {n}")
    if misses:
        offsets = np.array([abs(o) for o, _, _, _ in misses])
        speeds = np.array([s for _, s, _, _ in misses])
        ties = sum(int(t) for _, _, t, _ in misses)
        reversed_count = sum(int(a) for _, _, _, a in misses)
        print(
            f"  disagreements: |exhaustive - aligned index| {offsets.min()}-{offsets.max()} "
            f"(median {np.median(offsets):.0f}), at speeds {speeds.min():.2f}-"
            f"{speeds.max():.2f} m/s, equal costs (ties): {ties}"
        )
        print(f"  exhaustive pick on a stretch of contour running the other way: {reversed_count}")


def _correlation_peaks(p: np.ndarray, q: np.ndarray) -> int:
    """Local maxima over all cyclic shifts of the correlation of the centred contours
    (Q resampled to len(p) points by index), which the fast matcher aligns by."""
    n, m = len(p), len(q)
    position = np.arange(n) * (m / n)
    closed = np.concatenate([q, q[:1]])
    q_n = np.stack([np.interp(position, np.arange(m + 1), closed[:, i]) for i in (0, 1)], 1)
    a = (p - p.mean(axis=0)) @ [1.0, 1j]
    b = (q_n - q_n.mean(axis=0)) @ [1.0, 1j]
    corr = np.fft.ifft(np.conj(np.fft.fft(a)) * np.fft.fft(b)).real
    return int(np.sum((corr > np.roll(corr, 1)) & (corr >= np.roll(corr, -1))))


def _predicted_start(make: Callable[[np.random.Generator], Pair]) -> Callable[..., Pair]:
    """``make`` with the current contour resampled as the persistent proxy resamples it:
    from the point nearest the previous first point carried by the centroid's travel."""

    def aligned(rng: np.random.Generator) -> Pair:
        p, q = make(rng)
        perimeter = float(np.sum(np.linalg.norm(np.roll(q, -1, 0) - q, axis=1)))
        start = p[0] + q.mean(axis=0) - p.mean(axis=0)
        return p, resample_closed(q, perimeter / len(q), start=start)

    return aligned


def _lobed(points: int, grow: float = 1.0, shift: float = 0.0) -> np.ndarray:
    """A hand-like lobed outline resampled to about ``points`` points, metres."""
    t = np.linspace(0.0, 2.0 * np.pi, 4000, endpoint=False)
    r = 0.075 * grow * (1.0 + 0.15 * np.sin(5.0 * t))
    outline = np.stack([r * np.cos(t) + shift, r * np.sin(t)], axis=1)
    perimeter = float(np.sum(np.linalg.norm(np.roll(outline, -1, 0) - outline, axis=1)))
    return resample_closed(outline, perimeter / grow / points, start=outline[int(400 * grow)])


def _time(function: Callable[[], object], budget: float = 0.02) -> float:
    """Seconds per call, best of three runs of about ``budget`` seconds each."""
    calls = max(1, int(budget / max(min(timeit.repeat(function, number=1, repeat=3)), 1e-6)))
    return min(timeit.repeat(function, number=calls, repeat=3)) / calls


def _speed() -> None:
    for points in (32, 128, 256, 512, 1024, 2048):
        p, q = _lobed(points), _lobed(points, grow=1.005, shift=0.004)
        # Both start at the same point of the outline, as the persistent proxy resamples
        # them; rolled by a third, the fast matcher needs its FFT.
        rolled = np.roll(q, len(q) // 3, axis=0)
        fast: list[float] = []
        fast_rolled: list[float] = []
        exact: list[float] = []
        for _ in range(7):  # interleaved, so a busy neighbour slows all alike
            fast.append(_time(functools.partial(match_fast, p, q, WINDOW, SEARCH)))
            fast_rolled.append(_time(functools.partial(match_fast, p, rolled, WINDOW, SEARCH)))
            exact.append(_time(functools.partial(match_exhaustive, p, q, WINDOW)))
        f, r, e = min(fast), min(fast_rolled), min(exact)
        print(
            f"  N={len(p):5d}, M={len(q):5d}: fast {f * 1e6:6.0f} µs ({e / f:4.1f}x), "
            f"from arbitrary starts {r * 1e6:6.0f} µs ({e / r:4.1f}x), "
            f"exhaustive {e * 1e6:6.0f} µs"
        )


def main() -> None:
    pairs = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    print(f"window n={WINDOW}, search S={SEARCH}")
    print(f"fingertips, {pairs} frame pairs:")
    _agreement(pairs, fingertip_motion, seed=1)
    print("hand outlines, 40 frame pairs of 512 points:")
    _agreement(40, hand_motion, seed=2)
    print("the same, resampled from the predicted start (the fast matcher skips its FFT):")
    _agreement(40, _predicted_start(hand_motion), seed=2)
    print("speed (best of interleaved runs):")
    _speed()


if __name__ == "__main__":
    main()
