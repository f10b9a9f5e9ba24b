"""Successors by exhaustive and fast search, and the particle correspondence."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from graspenv.bench.contact_scenes import fingertip_motion, hand_motion
from graspenv.contacts import (
    agreement,
    correspond,
    correspond_batch,
    match_exhaustive,
    match_fast,
    new_point_anchors,
    resample_closed,
    window_costs,
)

SQUARE = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], dtype=float)


def _naive(previous: np.ndarray, current: np.ndarray, window: int) -> np.ndarray:
    """The definition, written as plainly as possible."""
    n, m, h = len(previous), len(current), window // 2
    successor = []
    for k in range(n):
        costs = [
            sum(
                float(np.sum((previous[(k + i) % n] - current[(j + i) % m]) ** 2))
                for i in range(-h, h + 1)
            )
            for j in range(m)
        ]
        successor.append(int(np.argmin(costs)))
    return np.array(successor)


# -- exhaustive: hand-checked ---------------------------------------------------------


def test_exhaustive_follows_a_renumbered_contour() -> None:
    # Q[j] = P[j + 1], so P[k] sits at Q[k - 1].
    assert match_exhaustive(SQUARE, np.roll(SQUARE, -1, axis=0), window=2).tolist() == [
        3,
        0,
        1,
        2,
    ]


def test_exhaustive_with_more_current_points_than_previous() -> None:
    # The square with its edge midpoints: corners are at even indices of Q.
    current = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [1, 2], [0, 2], [0, 1]], float)
    assert match_exhaustive(SQUARE, current, window=0).tolist() == [0, 2, 4, 6]
    # With a window the neighbours count too; P's neighbours are two steps of Q away,
    # so the best alignment is unchanged.
    assert match_exhaustive(SQUARE, current, window=2).tolist() == [0, 2, 4, 6]


def test_window_overrules_the_nearest_point() -> None:
    # Previous k = 1 sits mid-way along (0,0), (1,0), (2,0). Current point 0 is its
    # nearest (0.4 away) but its neighbours are far off; current 2, 3, 4 run parallel
    # to the previous three at distance 1.
    previous = np.array([[0, 0], [1, 0], [2, 0], [1, -3]], float)
    current = np.array([[1, 0.4], [5, 5], [0, 1], [1, 1], [2, 1], [5, 0]])
    assert match_exhaustive(previous, current, window=0)[1] == 0
    # Window 2 at k = 1: j = 3 costs 1 + 1 + 1 = 3; j = 0 costs 25 + 0.16 + 34.
    assert match_exhaustive(previous, current, window=2)[1] == 3
    costs = window_costs(previous, current, np.array([0, 3, 0, 0]), 2)
    assert costs[1] == pytest.approx(3.0)


def test_equal_costs_go_to_the_smallest_index() -> None:
    previous = np.array([[0, 0]], float)
    current = np.array([[1, 0], [0, 5], [-1, 0]], float)  # j = 0 and j = 2 tie
    assert match_exhaustive(previous, current, window=0).tolist() == [0]
    assert match_fast(previous, current, window=0, search=1).tolist() == [0]


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 9),
    m=st.integers(1, 9),
    window=st.integers(0, 6),
)
def test_exhaustive_equals_the_definition(seed: int, n: int, m: int, window: int) -> None:
    rng = np.random.default_rng(seed)
    # Small integers: every cost is exact, so ties are real ties in both.
    previous = rng.integers(-3, 4, size=(n, 2)).astype(float)
    current = rng.integers(-3, 4, size=(m, 2)).astype(float)
    expected = _naive(previous, current, window)
    assert match_exhaustive(previous, current, window).tolist() == expected.tolist()
    # A search as wide as the contour is a full search: the same answer, ties too.
    assert match_fast(previous, current, window, search=m).tolist() == expected.tolist()


# -- fast against exhaustive ----------------------------------------------------------


@pytest.mark.parametrize("shift", [0, 1, 7, 200, 511])
def test_fast_finds_a_renumbering_of_the_same_contour(shift: int) -> None:
    t = np.linspace(0.0, 2.0 * np.pi, 512, endpoint=False)
    contour = np.stack([0.1 * np.cos(t) + 0.2, 0.06 * np.sin(t) - 0.1], axis=1)
    expected = (np.arange(512) + shift) % 512  # current[j] = contour[j - shift]
    current = np.roll(contour, shift, axis=0)
    assert match_fast(contour, current, 4, 3).tolist() == expected.tolist()
    assert match_exhaustive(contour, current, 4).tolist() == expected.tolist()


def test_fast_agrees_with_exhaustive_on_realistic_finger_motion() -> None:
    """Fingertips of 6-12 mm moving up to 0.5 m/s and turning up to 3 rad/s at 60 Hz,
    resampled at 2-4 mm from arbitrary starts, and hand outlines of 512 points.
    Measured on 2 000 pairs: 0.9995, every disagreement a point whose exhaustive
    successor is across the fingertip (see tests/contacts/measure_matching.py)."""
    rng = np.random.default_rng(1234)
    same = total = 0
    for _ in range(1000):
        previous, current = fingertip_motion(rng)
        fast = match_fast(previous, current, 4, 3)
        exact = match_exhaustive(previous, current, 4)
        same += int(np.sum(fast == exact))
        total += len(previous)
    for _ in range(4):
        previous, current = hand_motion(rng)
        assert agreement(previous, current, 4, 3) == 1.0
        same += len(previous)
        total += len(previous)
    assert total > 20_000
    assert same / total >= 0.999


def _from_predicted_start(previous: np.ndarray, current: np.ndarray) -> np.ndarray:
    """``current`` resampled as the persistent proxy does: from the point nearest the
    previous first point carried by the centroid's travel."""
    perimeter = float(np.sum(np.linalg.norm(np.roll(current, -1, 0) - current, axis=1)))
    start = previous[0] + current.mean(axis=0) - previous.mean(axis=0)
    return resample_closed(current, perimeter / len(current), start=start)


def test_fast_needs_no_fft_when_the_starts_correspond(monkeypatch: pytest.MonkeyPatch) -> None:
    """Hand outlines resampled from the predicted start are aligned by their correlation
    at the shifts near 0 alone, and give the same successors as from any other start
    (where the FFT aligns them) and as the exhaustive search."""
    rng = np.random.default_rng(5)
    pairs = []
    for _ in range(4):
        previous, current = hand_motion(rng)
        pairs.append((previous, _from_predicted_start(previous, current)))
    rolled = [match_fast(p, np.roll(q, 100, axis=0), 4, 3) for p, q in pairs]

    def no_fft(*args: object, **kwargs: object) -> None:
        raise AssertionError("the FFT was used")

    monkeypatch.setattr(np.fft, "fft", no_fft)
    for (previous, current), successor in zip(pairs, rolled, strict=True):
        fast = match_fast(previous, current, 4, 3)
        assert ((fast + 100) % len(current)).tolist() == successor.tolist()
        assert fast.tolist() == match_exhaustive(previous, current, 4).tolist()


def test_fast_on_a_long_contour_built_in_blocks() -> None:
    """2 048 points moving 4 mm: the fast matcher's table is built block by block."""
    t = np.linspace(0.0, 2.0 * np.pi, 2048, endpoint=False)
    radius = 0.075 * (1.0 + 0.15 * np.sin(5.0 * t))
    previous = np.stack([radius * np.cos(t), radius * np.sin(t)], axis=1)
    current = 1.005 * np.roll(previous, 700, axis=0) + [0.004, 0.0]
    assert agreement(previous, current, 4, 3) == 1.0


def test_agreement_is_a_fraction() -> None:
    rng = np.random.default_rng(3)
    previous, current = fingertip_motion(rng, speed_max=0.1)
    value = agreement(previous, current, 4, 0)
    assert 0.0 <= value <= 1.0
    assert agreement(previous, previous, 4, 3) == 1.0


def test_matchers_reject_bad_input() -> None:
    with pytest.raises(ValueError, match="shape"):
        match_fast(np.zeros((4, 3)), SQUARE, 4)
    with pytest.raises(ValueError, match="search"):
        match_fast(SQUARE, SQUARE, 4, -1)
    with pytest.raises(ValueError, match="window"):
        match_exhaustive(SQUARE, SQUARE, -2)
    with pytest.raises(ValueError, match="method"):
        correspond(SQUARE, SQUARE, 4, method="nearest")  # type: ignore[arg-type]


# -- correspondence -------------------------------------------------------------------


def test_new_point_anchors_hand_checked() -> None:
    has = np.array([True, False, False, True, False])
    # j=1: back 1 (to 0) vs forward 2 -> 0; j=2: forward 1 -> 3;
    # j=4: back 1 (to 3) ties forward 1 (to 0, round the end) -> the lower side, 3.
    assert new_point_anchors(has).tolist() == [-1, 0, 3, -1, 3]
    assert new_point_anchors(np.zeros(4, bool)).tolist() == [-1] * 4
    assert new_point_anchors(np.ones(4, bool)).tolist() == [-1] * 4
    assert new_point_anchors(np.array([False, False, True, False])).tolist() == [2, 2, -1, 2]


def test_correspond_hand_checked() -> None:
    # Two previous points name current 0; the cheaper (k = 1) keeps its particle.
    previous = np.array([[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]])
    current = np.array([[1.0, 0.0], [4.0, 5.0], [9.0, 9.0], [5.0, 6.0]])
    match = correspond(previous, current, window=0, method="exhaustive")
    assert match.successor.tolist() == [0, 0, 1]
    assert match.cost.tolist() == [1.0, 0.0, 1.0]
    assert match.predecessor.tolist() == [1, 2, -1, -1]
    assert match.kept.tolist() == [False, True, True]
    assert match.is_new.tolist() == [False, False, True, True]
    # j=2: back 1 step to j=1; j=3: forward 1 step round the end to j=0.
    assert match.anchor.tolist() == [-1, -1, 1, 0]
    with pytest.raises(ValueError):
        match.successor[0] = 2  # read-only


def _check_invariants(previous: np.ndarray, current: np.ndarray, method: str) -> None:
    match = correspond(previous, current, 4, method=method)  # type: ignore[arg-type]
    n, m = len(previous), len(current)
    successor, predecessor = match.successor, match.predecessor
    assert successor.shape == (n,) and predecessor.shape == (m,)
    assert np.all((successor >= 0) & (successor < m))
    assert np.all((predecessor >= -1) & (predecessor < n))
    reused = predecessor[predecessor >= 0]
    assert len(np.unique(reused)) == len(reused)  # each previous particle at most once
    for j in np.flatnonzero(predecessor >= 0):
        k = predecessor[j]
        assert successor[k] == j
        # the cheapest of the previous points naming j (lowest index on a tie)
        rivals = np.flatnonzero(successor == j)
        best = min(rivals, key=lambda r: (match.cost[r], r))
        assert k == best
    named = np.zeros(m, dtype=bool)
    named[successor] = True
    assert np.array_equal(named, predecessor >= 0)
    assert np.array_equal(match.kept, predecessor[successor] == np.arange(n))
    assert int(match.kept.sum()) == int(np.sum(predecessor >= 0))
    np.testing.assert_allclose(match.cost, window_costs(previous, current, successor, 4))
    anchor = match.anchor
    for j in range(m):
        if predecessor[j] >= 0:
            assert anchor[j] == -1
            continue
        a = anchor[j]
        assert predecessor[a] >= 0
        steps = min((a - j) % m, (j - a) % m)
        kept = np.flatnonzero(predecessor >= 0)
        assert steps == min(min((k - j) % m, (j - k) % m) for k in kept)
    for array in (match.successor, match.predecessor, match.kept, match.anchor, match.cost):
        assert not array.flags.writeable


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), method=st.sampled_from(["fast", "exhaustive", "auto"]))
def test_correspond_invariants_on_finger_motion(seed: int, method: str) -> None:
    previous, current = fingertip_motion(np.random.default_rng(seed))
    _check_invariants(previous, current, method)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 12), m=st.integers(1, 12))
def test_correspond_invariants_on_arbitrary_points(seed: int, n: int, m: int) -> None:
    rng = np.random.default_rng(seed)
    previous = rng.integers(-2, 3, size=(n, 2)).astype(float)  # many exact ties
    current = rng.integers(-2, 3, size=(m, 2)).astype(float)
    _check_invariants(previous, current, "exhaustive")
    _check_invariants(previous, current, "fast")


@pytest.mark.parametrize("method", ["exhaustive", "fast", "auto"])
def test_many_pairs_at_once_equal_one_pair_at_a_time(method: str) -> None:
    """Fingertips and, for auto, a hand outline (matched fast) in one call; indices
    run along all the contours."""
    rng = np.random.default_rng(11)
    pairs = [fingertip_motion(rng) for _ in range(9)]
    if method != "exhaustive":
        pairs.insert(4, hand_motion(rng, points=300))
    previous = np.concatenate([p for p, _ in pairs])
    current = np.concatenate([q for _, q in pairs])
    p_bounds = np.concatenate([[0], np.cumsum([len(p) for p, _ in pairs])])
    q_bounds = np.concatenate([[0], np.cumsum([len(q) for _, q in pairs])])
    batch = correspond_batch(previous, p_bounds, current, q_bounds, 4, method)  # type: ignore[arg-type]
    for c, (p, q) in enumerate(pairs):
        single = correspond(p, q, 4, method)  # type: ignore[arg-type]
        rows, cols = slice(p_bounds[c], p_bounds[c + 1]), slice(q_bounds[c], q_bounds[c + 1])
        assert (batch.successor[rows] - q_bounds[c]).tolist() == single.successor.tolist()
        np.testing.assert_allclose(batch.cost[rows], single.cost, rtol=1e-12)
        assert batch.kept[rows].tolist() == single.kept.tolist()
        local = np.where(batch.predecessor[cols] >= 0, batch.predecessor[cols] - p_bounds[c], -1)
        assert local.tolist() == single.predecessor.tolist()
        anchor = np.where(batch.anchor[cols] >= 0, batch.anchor[cols] - q_bounds[c], -1)
        assert anchor.tolist() == single.anchor.tolist()


def test_auto_refuses_a_negative_search_where_it_would_match_fast() -> None:
    rng = np.random.default_rng(2)
    previous, current = hand_motion(rng, points=300)  # 300 × 300 pairs: fast
    with pytest.raises(ValueError, match="search must be >= 0"):
        correspond(previous, current, 4, "auto", -1)
    small = fingertip_motion(rng)  # exhaustive: the search is not used
    assert len(correspond(*small, 4, "auto", -1).successor) == len(small[0])
