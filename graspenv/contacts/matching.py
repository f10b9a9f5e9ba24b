"""Point correspondence between a contact's previous and current contour.

This is step 4 of the persistent particle proxy (Wilson, ITS 2009; see DESIGN.md):
which current contour point each previous point moved to, and so which particle each
current point inherits. Pure numpy, no frames of its own: pass both contours in the
same frame (metres, world frame in the pipeline), closed, with the same orientation,
each resampled evenly (their counts N and M may differ).

**Window cost.** With h = ``window // 2`` (an odd window n behaves as n - 1), the cost
of pairing previous point k with current point j is

    D[k, j] = Σ_{i=-h..h} ||P[(k+i) mod N] − Q[(j+i) mod M]||²

so each contour keeps its own circular indexing. The *successor* of k is the j with
the smallest D[k, j]; equal costs go to the smallest j.

**Exhaustive** (:func:`match_exhaustive`, the paper's reference): D is the squared
distance between the (2h+1)-point windows seen as vectors, so the whole N × M table is
a matrix product, computed in row blocks small enough that BLAS keeps to one thread
and memory stays bounded.

**Fast** (:func:`match_fast`): one global cyclic alignment of the two contours by FFT
cross-correlation (Q resampled to N points for this estimate only; translation-free,
since a common shift cannot change which cyclic offset fits best), then each point's
own argmin within ±S indices of its aligned index. The exhaustive cost is not
translation-free: where the finger's motion runs along the contour, the best window
lies about (t·tangent)/spacing indices behind the globally aligned one (t the centroid
displacement), so the aligned index includes that per-point term and S only has to
absorb the shape's deformation. Window sums come from cumulative sums along each
diagonal j − k of the cost table: O(N · (S + |N − M| + |t|/spacing)) rather than
O(N · M · n). A point whose minimum lands on the edge of its range searches again
around that minimum until it lies inside, which follows the cost downhill past S.

**Measured** (window 4, S = 3; ``python -m tests.contacts.measure_matching``). Fast
and exhaustive successors agree on 99.95 % of 40 001 fingertip points (6-12 mm
ellipses rendered at the table's pixels, one 60 Hz frame at up to 0.5 m/s and
±3 rad/s, 2-4 mm spacing, arbitrary start points) and on 100 % of 20 480 points of
512-point hand outlines. All disagreements come at 0.39-0.5 m/s and none is a tie:
the exhaustive successor lies across the fingertip, on contour running the other way,
because a 7-8 mm step brings the new trailing side nearer the old leading side than
the new leading side is. Time with one BLAS thread: at 512 points fast 0.24 ms,
exhaustive 0.55 ms (2.3×; 4.4× at 1 024); below about 256 points the exhaustive
search is the cheaper, as the fast path's fixed cost of a few dozen numpy calls
(about 0.12 ms here) outweighs the N × M product. Hence ``correspond(method="auto")``.

**Particles** (:func:`correspond`): DESIGN's rule made one-to-one. The predecessor of
current point j is, among the previous points whose successor is j, the one with the
smallest window cost D[k, j] (the smallest k on a tie); j has no predecessor (−1) when
no previous point names it. Current point j reuses the particle of its predecessor;
without one it gets a new particle. Previous point k keeps its particle exactly when
``predecessor[successor[k]] == k``; otherwise the particle is released. So every
previous particle goes to at most one current point and every current point has at
most one previous particle. A new particle starts at the particle of its *anchor*: the
nearest current point along the contour (fewest index steps, the lower-index side on
a tie) that has a predecessor.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "Correspondence",
    "agreement",
    "correspond",
    "match_exhaustive",
    "match_fast",
    "new_point_anchors",
    "window_costs",
]

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

# The exhaustive matcher's row blocks stay under OpenBLAS's threading threshold
# (m·n·k < 65536·4 multiply-adds): a threaded product of this size gains nothing, and
# when another process holds a core it waits on it, measured at 10-20 ms instead of
# 0.5 ms for 512 points on two cores. This also bounds the block's memory.
_SINGLE_THREAD_MACS = 1 << 18
# correspond(method="auto") searches exhaustively up to this many point pairs.
_AUTO_EXHAUSTIVE = 256 * 256
_NO_INDEX = np.iinfo(np.intp).max  # sorts after every real index


def _contour(points: ArrayLike, name: str) -> FloatArray:
    array = np.asarray(points, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 2 or len(array) < 1:
        raise ValueError(f"{name} must have shape (N, 2) with N >= 1, got {array.shape}")
    return array


def _half(window: int) -> int:
    if window < 0:
        raise ValueError(f"window must be >= 0, got {window}")
    return int(window) // 2


def _windows(points: FloatArray, half: int) -> FloatArray:
    """Each point's circular window of 2h+1 points, flattened: shape (N, 2(2h+1))."""
    n = len(points)
    index = (np.arange(n)[:, None] + np.arange(-half, half + 1)[None, :]) % n
    return points[index].reshape(n, -1)


def match_exhaustive(previous: ArrayLike, current: ArrayLike, window: int) -> IntArray:
    """Successor of every previous point by searching every current point.

    Args:
        previous: previous contour P, shape (N, 2), closed, metres (any common frame).
        current: current contour Q, shape (M, 2), same frame and orientation.
        window: n of the window cost (2·(n // 2) + 1 points per window).

    Returns:
        successor, shape (N,), indices into ``current``: for each k the j minimising
        D[k, j] (module docstring), the smallest j on a tie. O(N·M·n) time, memory
        bounded by row blocks.
    """
    p = _contour(previous, "previous")
    q = _contour(current, "current")
    half = _half(window)
    # About a point of P: the expanded square below cancels less, and integer test
    # contours stay exact.
    origin = p[0]
    pw = _windows(p - origin, half)
    qw = _windows(q - origin, half)
    # D = ||a||² + ||b||² - 2 a·b; ||a||² is the same along a row, so it is left out
    # of the argmin.
    q_norm = np.einsum("ij,ij->i", qw, qw)
    q_scaled = np.ascontiguousarray(-2.0 * qw.T)
    successor = np.empty(len(p), dtype=np.intp)
    rows = min(len(p), max(1, (_SINGLE_THREAD_MACS - 1) // (len(q) * qw.shape[1])))
    # One buffer for every block: fresh temporaries cost more in allocation and page
    # faults than the arithmetic they hold (measured: 3.7 ms against 0.5 ms).
    buffer = np.empty((rows, len(q)))
    for begin in range(0, len(p), rows):
        cost = buffer[: min(rows, len(p) - begin)]
        np.matmul(pw[begin : begin + rows], q_scaled, out=cost)
        cost += q_norm
        successor[begin : begin + rows] = np.argmin(cost, axis=1)
    return successor


def window_costs(
    previous: ArrayLike, current: ArrayLike, successor: ArrayLike, window: int
) -> FloatArray:
    """Window cost D[k, successor[k]] of given pairs, computed directly.

    Args:
        previous: previous contour P, shape (N, 2), metres.
        current: current contour Q, shape (M, 2), same frame.
        successor: indices into ``current``, shape (N,).
        window: n of the window cost.

    Returns:
        Shape (N,), metres² (the frame's unit squared).
    """
    p = _contour(previous, "previous")
    q = _contour(current, "current")
    half = _half(window)
    j = np.asarray(successor, dtype=np.intp)
    offsets = np.arange(-half, half + 1)
    gap = p[(np.arange(len(p))[:, None] + offsets) % len(p)]
    gap = gap - q[(j[:, None] + offsets) % len(q)]
    return np.einsum("ijk,ijk->i", gap, gap)


def _complex(points: FloatArray) -> ComplexArray:
    """Points (N, 2) as x + iy: the fast matcher's arithmetic is then a few flat passes."""
    return points[:, 0] + 1j * points[:, 1]


@dataclass(frozen=True, eq=False)
class _Plan:
    """Index arrays of the fast matcher that depend only on the sizes (cached)."""

    k: IntArray  # 0..N-1
    drift: FloatArray  # k·M/N - k: where the diagonal j - k sits at a pure rescale
    lower: IntArray  # Q index below k·M/N (Q resampled to N points)
    upper: IntArray
    weight: FloatArray
    after: IntArray  # k + 1 and k - 1, circular
    before: IntArray
    walk: IntArray  # P indices k - h .. N - 1 + h, circular
    reach: IntArray  # the same, unwrapped


@functools.lru_cache(maxsize=128)
def _plan(n: int, m: int, half: int) -> _Plan:
    k = np.arange(n)
    position = np.multiply(k, m / n, dtype=np.float64)
    lower = position.astype(np.intp)
    reach = np.arange(-half, n + half)
    plan = _Plan(
        k=k,
        drift=np.subtract(position, k, dtype=np.float64),
        lower=lower,
        upper=(lower + 1) % m,
        weight=np.subtract(position, lower, dtype=np.float64),
        after=(k + 1) % n,
        before=(k - 1) % n,
        walk=reach % n,
        reach=reach,
    )
    for array in vars(plan).values():
        array.setflags(write=False)
    return plan


def _aligned_diagonal(p: ComplexArray, q: ComplexArray, plan: _Plan) -> IntArray:
    """j - k (unwrapped) at which the fast search for each point k of P is centred.

    One global cyclic shift from the FFT cross-correlation, plus each point's lag
    along the contour from the centroid's travel (module docstring).
    """
    n, m = len(p), len(q)
    # Q resampled to N points by index, which is by arc length for an even contour.
    q_n = q if n == m else q[plan.lower] + plan.weight * (q[plan.upper] - q[plan.lower])
    spectrum_p, spectrum_q = np.fft.fft(np.stack([p, q_n]), axis=1)
    cross = np.conj(spectrum_p) * spectrum_q
    cross[0] = 0.0  # centres both contours: their position must not weigh on the shape
    # corr[d] = Σ_k Re(conj(p̃_k) q̃_{k+d}) = Σ_k P̃[k]·Q̃'[k+d]
    corr = np.fft.ifft(cross).real
    best = int(np.argmax(corr))
    shift = float(best)
    if n >= 3:
        left, mid, right = float(corr[best - 1]), float(corr[best]), float(corr[(best + 1) % n])
        curvature = left - 2.0 * mid + right
        if curvature < 0.0:  # a parabola through the peak places it between samples
            shift += 0.5 * (left - right) / curvature
    travel = complex(spectrum_q[0] - spectrum_p[0]) / n  # centroid displacement
    tangent = p[plan.after] - p[plan.before]
    # The window of a point whose finger moves along the contour fits best that many
    # points behind: (travel · unit tangent) / spacing, with |tangent| ≈ 2 × spacing
    # on an evenly resampled contour, so the divisor is mean(|tangent|²) / 2.
    squared = np.vdot(tangent, tangent).real
    lag = (tangent * travel.conjugate()).real
    if squared > 0.0:
        lag *= 2.0 * n / squared
    else:
        lag[:] = 0.0
    diagonal = plan.drift - lag
    diagonal += shift * (m / n)
    return np.rint(diagonal).astype(np.intp)


def _pick(cost: FloatArray, first: IntArray, m: int) -> IntArray:
    """Column of each row's smallest cost; equal costs go to the smallest j mod M, as
    ``argmin`` over j does in the exhaustive search.

    Row r's candidates are the consecutive unwrapped indices ``first[r] + column``, so
    the first minimum along a row is already the smallest j unless the row wraps past
    a multiple of M; only those rows are looked at again.
    """
    chosen = np.argmin(cost, axis=1)
    width = cost.shape[1]
    wraps = np.flatnonzero(first % m > m - width)
    if wraps.size:
        sub = cost[wraps]
        j = (first[wraps, None] + np.arange(width)) % m
        j = np.where(sub == sub.min(axis=1, keepdims=True), j, _NO_INDEX)
        chosen[wraps] = np.argmin(j, axis=1)
    return chosen


def _local_costs(
    p: ComplexArray, q: ComplexArray, half: int, rows: IntArray, first: IntArray, width: int
) -> FloatArray:
    """D[k, j] for k = rows (R,) and j = first + 0..width-1 (unwrapped), by gathering."""
    offsets = np.arange(-half, half + 1)
    previous = p[(rows[:, None] + offsets) % len(p)]  # (R, W)
    columns = first[:, None, None] + np.arange(width)[:, None] + offsets  # (R, C, W)
    gap = q[columns % len(q)] - previous[:, None, :]
    return np.sum((gap * gap.conj()).real, axis=2)


def _match_fast(p: ComplexArray, q: ComplexArray, half: int, search: int) -> IntArray:
    n, m = len(p), len(q)
    plan = _plan(n, m, half)
    width = 2 * search + 1
    base = _aligned_diagonal(p, q, plan)
    low = int(base.min()) - search
    # Diagonals repeat every M; never build more than M distinct ones.
    count = min(int(base.max()) + search - low + 1, m)
    # Row d pairs P[k + i] with Q[k + i + low + d] along the diagonal j - k = low + d,
    # the P index running h beyond both ends so windows that cross the end of either
    # contour pair the right points. Row d is row 0 shifted by d: a strided view.
    span = n + 2 * half
    strip = q[np.arange(low - half, low - half + count + span - 1) % m]
    shifted = np.lib.stride_tricks.as_strided(
        strip, shape=(count, span), strides=(strip.strides[0], strip.strides[0]), writeable=False
    )
    gap = p[plan.walk] - shifted
    total = np.zeros((count, span + 1))
    np.cumsum((gap * gap.conj()).real, axis=1, out=total[:, 1:])
    window_sum = total[:, 2 * half + 1 :] - total[:, :n]  # (diagonal - low, k)
    offset = base - low - search
    if count == m:
        offset %= m
    flat = (offset * n + plan.k)[:, None] + n * np.arange(width)
    if count == m:
        flat %= m * n
    cost = np.take(window_sum, flat)
    first = base + plan.k - search  # the unwrapped j of column 0
    chosen = _pick(cost, first, m)
    successor = first + chosen

    # A minimum on the edge of the range may continue beyond it: search again around
    # it until the minimum is inside (each round's cost is no larger than the last).
    if search > 0 and width < m:
        rows = np.flatnonzero(chosen % (2 * search) == 0)
        for _ in range(m // search + 1):
            if rows.size == 0:
                break
            first = successor[rows] - search
            chosen = _pick(_local_costs(p, q, half, rows, first, width), first, m)
            successor[rows] = first + chosen
            rows = rows[chosen % (2 * search) == 0]
    return successor % m


def match_fast(previous: ArrayLike, current: ArrayLike, window: int, search: int = 3) -> IntArray:
    """Successor of every previous point by a global alignment and a local search.

    Args:
        previous: previous contour P, shape (N, 2), closed, metres (any common frame).
        current: current contour Q, shape (M, 2), same frame and orientation.
        window: n of the window cost (module docstring).
        search: half-width S of each point's search, current-contour indices.

    Returns:
        successor, shape (N,), indices into ``current``: each k's minimum of D[k, j]
        over the 2S+1 indices j around its aligned index (the smallest j on a tie).
        Equal to :func:`match_exhaustive` wherever the global minimum lies in that
        range.
    """
    p = _contour(previous, "previous")
    q = _contour(current, "current")
    if search < 0:
        raise ValueError(f"search must be >= 0, got {search}")
    return _match_fast(_complex(p), _complex(q), _half(window), int(search))


def agreement(previous: ArrayLike, current: ArrayLike, window: int, search: int = 3) -> float:
    """Fraction of previous points whose fast and exhaustive successors are equal.

    Args:
        previous: previous contour, shape (N, 2), metres.
        current: current contour, shape (M, 2), same frame and orientation.
        window: n of the window cost.
        search: the fast matcher's half-width S.

    Returns:
        A number in [0, 1].
    """
    fast = match_fast(previous, current, window, search)
    exact = match_exhaustive(previous, current, window)
    return float(np.mean(fast == exact))


def new_point_anchors(has_predecessor: ArrayLike) -> IntArray:
    """For each current point without a predecessor, the nearest one with a predecessor.

    Args:
        has_predecessor: shape (M,), bool, along a closed contour.

    Returns:
        Shape (M,), indices into the contour: for a point without a predecessor, the
        point with one reached in the fewest index steps walking either way round the
        contour (the lower-index side, j - d, on a tie); -1 for points that have a
        predecessor, and everywhere when no point has one.
    """
    has = np.asarray(has_predecessor, dtype=bool)
    m = len(has)
    anchor = np.full(m, -1, dtype=np.intp)
    kept = np.flatnonzero(has)
    if kept.size == 0 or kept.size == m:
        return anchor
    lone = np.flatnonzero(~has)
    after = np.searchsorted(kept, lone)  # first kept index above each lone point
    ahead = kept[after % kept.size]
    behind = kept[after - 1]  # index -1 wraps to the last kept point
    forward = (ahead - lone) % m
    backward = (lone - behind) % m
    anchor[lone] = np.where(backward <= forward, behind, ahead)
    return anchor


@dataclass(frozen=True, eq=False)
class Correspondence:
    """Which particle every current contour point inherits (module docstring).

    Attributes:
        successor: shape (N,), for each previous point k the current point it moved
            to, indices into the current contour.
        cost: shape (N,), the window cost D[k, successor[k]], metres² (the frame's
            unit squared).
        predecessor: shape (M,), for each current point j the previous point whose
            particle it reuses, or -1 for a new particle.
        kept: shape (N,), bool, whether previous point k's particle is reused (by
            ``successor[k]``); the others are released.
        anchor: shape (M,), for each new current point the current point whose
            particle it starts beside (:func:`new_point_anchors`); -1 for points with
            a predecessor.
    """

    successor: IntArray
    cost: FloatArray
    predecessor: IntArray
    kept: NDArray[np.bool_]
    anchor: IntArray

    @property
    def is_new(self) -> NDArray[np.bool_]:
        """Shape (M,), bool: current points that get a new particle."""
        return self.predecessor < 0


def correspond(
    previous: ArrayLike,
    current: ArrayLike,
    window: int,
    method: Literal["fast", "exhaustive", "auto"] = "fast",
    search: int = 3,
) -> Correspondence:
    """Successors, predecessors and particle reuse between two contours.

    Args:
        previous: previous contour P, shape (N, 2), closed, metres (any common frame).
        current: current contour Q, shape (M, 2), same frame and orientation.
        window: n of the window cost.
        method: ``"fast"`` (:func:`match_fast`), ``"exhaustive"``
            (:func:`match_exhaustive`), or ``"auto"``: exhaustive while N·M is at
            most 256², where it was measured to be the cheaper of the two (the fast
            matcher's fixed cost of a few dozen numpy calls outweighs the N × M
            product below about 256 points; fingertip contours have 10-60).
        search: the fast matcher's half-width S.

    Returns:
        A :class:`Correspondence` whose arrays are read-only.
    """
    p = _contour(previous, "previous")
    q = _contour(current, "current")
    if method == "auto":
        method = "exhaustive" if len(p) * len(q) <= _AUTO_EXHAUSTIVE else "fast"
    if method == "fast":
        successor = match_fast(p, q, window, search)
    elif method == "exhaustive":
        successor = match_exhaustive(p, q, window)
    else:
        raise ValueError(f"method must be 'fast', 'exhaustive' or 'auto', got {method!r}")
    cost = window_costs(p, q, successor, window)
    n, m = len(p), len(q)
    # Among the previous points naming the same successor, the cheapest (then the
    # lowest index) comes first; it is that current point's predecessor.
    order = np.lexsort((np.arange(n), cost, successor))
    first = np.ones(n, dtype=bool)
    first[1:] = successor[order[1:]] != successor[order[:-1]]
    predecessor = np.full(m, -1, dtype=np.intp)
    predecessor[successor[order[first]]] = order[first]
    kept = predecessor[successor] == np.arange(n)
    anchor = new_point_anchors(predecessor >= 0)
    for array in (successor, cost, predecessor, kept, anchor):
        array.setflags(write=False)
    return Correspondence(successor, cost, predecessor, kept, anchor)
