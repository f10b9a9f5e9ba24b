"""Point correspondence between a contact's previous and current contour.

This is step 4 of the persistent particle proxy (Wilson, ITS 2009; docs/design.md, §2):
which current contour point each previous point moved to, and so which particle each
current point inherits. Numpy and compiled kernels, no frames of its own: pass both contours in the
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

**Fast** (:func:`match_fast`): one global cyclic alignment of the two contours, the
peak of their cross-correlation (Q resampled to N points for this estimate only;
translation-free, since a common shift cannot change which cyclic offset fits best),
then each point's own argmin within ±S indices of its aligned index. The peak is found
by FFT, unless the correlation computed directly at the shifts -8 .. 8 already peaks
strictly inside them, where the centred contours' cosine similarity is at least 0.98:
the persistent proxy's case, as it resamples the current contour from the predicted
first point. The correlation of two outlines of one contact has a single peak
(measured: no other local maximum in any pair of the sample below), so such a peak is
the FFT's; the cosine bound keeps other shapes on the FFT. The exhaustive cost is not
translation-free: where the finger's motion runs along the contour, the best window
lies about (t·tangent)/spacing indices behind the globally aligned one (t the centroid
displacement), so the aligned index includes that per-point term and S only has to
absorb the shape's deformation. Window sums run along each diagonal j − k of a table
of squared distances, built for blocks of points that span only the diagonals their
own points need: O(N · (S + |N − M| + |t|/spacing)) rather than O(N · M · n). A point
whose minimum lands on the edge of its range searches again around that minimum until
it lies inside, which follows the cost downhill past S.

**Measured** (window 4, S = 3; ``OPENBLAS_NUM_THREADS=1 python -m
graspenv.bench.matching``, figures from several runs). Fast and exhaustive
successors agree on 99.95 % of 40 001 fingertip points (6-12 mm ellipses rendered at
the table's pixels, one 60 Hz frame at up to 0.5 m/s and ±3 rad/s, 2-4 mm spacing,
arbitrary start points) and on 100 % of 20 480 points of 512-point hand outlines. All
disagreements come at 0.39-0.5 m/s and none is a tie: the exhaustive successor lies
across the fingertip, on contour running the other way, because a 7-8 mm step brings
the new trailing side nearer the old leading side than the new leading side is. The
same hand outlines resampled from the predicted start (no FFT) agree on 100 % too.
The fast path is a fixed sequence of about 45 numpy calls, so below about 128
points the exhaustive search is the cheaper (``correspond(method="auto")`` searches
exhaustively up to 256 × 256 point pairs); the measured times are in the README
("Matching: fast against exhaustive").

**Particles** (:func:`correspond`): the rule of docs/design.md (section 2, step 4) made
one-to-one. The predecessor of current point j is, among the previous points whose
successor is j, the one with the smallest window cost D[k, j] (the smallest k on a tie);
j has no predecessor (−1) when no previous point names it. Current point j reuses the
particle of its predecessor; without one it gets a new particle. Previous point k keeps
its particle exactly when ``predecessor[successor[k]] == k``; otherwise the particle is
released. So every previous particle goes to at most one current point and every current
point has at most one previous particle. A new particle starts at the particle of its
*anchor*: the nearest current point along the contour (fewest index steps, the
lower-index side on a tie) that has a predecessor.

**Many contacts** (:func:`correspond_batch`): every contact of a frame in one call,
each pair matched as above. The exhaustive searches of pairs up to 96 × 96 points
(fingertips, the per-frame case) run in one compiled call that sums every window cost
directly, so its costs are exact and equal costs go to the smallest j; it agrees with
the blocked product of :func:`match_exhaustive`, which larger pairs use, wherever
rounding does not decide a tie (``tests/contacts/test_kernels.py``). The particle
bookkeeping below is compiled too.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.jit import njit

__all__ = [
    "Correspondence",
    "agreement",
    "correspond",
    "correspond_batch",
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
# The fast matcher computes the correlation at shifts up to this far from 0 directly
# and skips the FFT when it peaks inside them, where the centred contours' cosine
# similarity reaches _ALIGNED_COSINE (module docstring).
_NEAR_SHIFTS = 8
_ALIGNED_COSINE = 0.98
# Most table entries (points × diagonals) the fast matcher builds at once.
_TABLE_SIZE = 1 << 14
# correspond_batch searches contour pairs of at most this many point pairs with the
# compiled direct search, larger ones with match_exhaustive's blocked product.
_DIRECT_PAIRS = 96 * 96


def _contour(points: ArrayLike, name: str) -> FloatArray:
    array = np.asarray(points, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 2 or len(array) < 1:
        raise ValueError(f"{name} must have shape (N, 2) with N >= 1, got {array.shape}")
    return array


def _half(window: int) -> int:
    if window < 0:
        raise ValueError(f"window must be >= 0, got {window}")
    return int(window) // 2


def _circular_windows(
    start: IntArray | int, centre: IntArray, size: IntArray | int, half: int
) -> IntArray:
    """Indices of the 2h+1-point circular window around each point ``centre`` of a
    contour that starts at ``start`` (along all contours laid end to end) and has
    ``size`` points; ``start`` and ``size`` per point or one for all; (K, 2h+1)."""
    steps = np.arange(-half, half + 1)
    wrapped = (centre[:, None] + steps) % np.asarray(size)[..., None]
    return np.asarray(start)[..., None] + wrapped


def _windows(points: FloatArray, half: int) -> FloatArray:
    """Each point's circular window of 2h+1 points, flattened: shape (N, 2(2h+1))."""
    n = len(points)
    return points[_circular_windows(0, np.arange(n), n, half)].reshape(n, -1)


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
    gap = p[_circular_windows(0, np.arange(len(p)), len(p), half)]
    gap = gap - q[_circular_windows(0, j, len(q), half)]
    return np.einsum("ijk,ijk->i", gap, gap)


def _complex(points: FloatArray) -> ComplexArray:
    """Points (N, 2) as x + iy, a view when they are contiguous: the fast matcher's
    arithmetic is then a few flat passes."""
    return np.ascontiguousarray(points).view(np.complex128)[:, 0]


@dataclass(frozen=True, eq=False)
class _Plan:
    """Index arrays of the fast matcher that depend only on the sizes (cached)."""

    pad: int  # max(h, 1): the tangent needs a neighbour each side even when h = 0
    walk: IntArray  # P indices k - pad .. N - 1 + pad, circular
    # Q resampled to N points, continued circularly _NEAR_SHIFTS points beyond each
    # end: for k = -_NEAR_SHIFTS .. N - 1 + _NEAR_SHIFTS (mod N), the Q indices below
    # and above k·M/N and the fraction between them.
    lower: IntArray
    upper: IntArray
    weight: FloatArray
    drift: FloatArray  # k·M/N - k: where the diagonal j - k sits at a pure rescale
    first: IntArray  # k - S: each point's first candidate j, less its aligned diagonal
    rows: IntArray  # 0 .. N - 1
    edge: NDArray[np.bool_]  # by column 0 .. 2S: on the edge of the search?


@functools.lru_cache(maxsize=128)
def _plan(n: int, m: int, half: int, search: int) -> _Plan:
    k = np.arange(n)
    pad = max(half, 1)
    position = np.multiply(k, m / n, dtype=np.float64)
    lower = position.astype(np.intp)
    ring = np.arange(-_NEAR_SHIFTS, n + _NEAR_SHIFTS) % n
    plan = _Plan(
        pad=pad,
        walk=np.arange(-pad, n + pad) % n,
        lower=lower[ring],
        upper=((lower + 1) % m)[ring],
        weight=np.subtract(position, lower, dtype=np.float64)[ring],
        drift=np.subtract(position, k, dtype=np.float64),
        first=k - search,
        rows=k,
        edge=np.arange(2 * search + 1) % max(2 * search, 1) == 0,
    )
    for array in vars(plan).values():
        if isinstance(array, np.ndarray):
            array.setflags(write=False)
    return plan


def _global_shift(p: ComplexArray, q_ring: ComplexArray) -> tuple[float, complex]:
    """The cyclic shift of Q that best fits P, and the centroid's travel from P to Q.

    Args:
        p: P, shape (N,), x + iy.
        q_ring: Q resampled to N points, continued circularly for _NEAR_SHIFTS
            points beyond each end: shape (N + 2·_NEAR_SHIFTS,), x + iy.

    Returns:
        (shift, travel): the shift in P's indices, fractional, in [-0.5, N); the
        travel in the points' unit, x + iy.
    """
    n = len(p)
    q_n = q_ring[_NEAR_SHIFTS : _NEAR_SHIFTS + n]
    total_p, total_q = complex(np.add.reduce(p)), complex(np.add.reduce(q_n))
    if n > 2 * _NEAR_SHIFTS:
        # The correlation at the shifts near 0, computed directly and uncentred
        # (centring takes the same amount off each): when it peaks inside them and the
        # contours fit well there, that peak is the FFT's (module docstring).
        near = np.correlate(q_ring, p, "valid").real
        best = int(near.argmax())
        if best < _NEAR_SHIFTS:  # a tie goes to the smallest shift mod N, as below
            other = _NEAR_SHIFTS + int(near[_NEAR_SHIFTS:].argmax())
            if near[other] == near[best]:
                best = other
        if 0 < best < 2 * _NEAR_SHIFTS:
            left, mid, right = near[best - 1 : best + 2].tolist()
            centred = mid - (total_p.conjugate() * total_q).real / n
            spread_p = np.vdot(p, p).real - abs(total_p) ** 2 / n
            spread_q = np.vdot(q_n, q_n).real - abs(total_q) ** 2 / n
            if centred > 0.0 and centred**2 >= _ALIGNED_COSINE**2 * spread_p * spread_q:
                shift = _peak(float((best - _NEAR_SHIFTS) % n), left, mid, right)
                return shift, (total_q - total_p) / n
    pair = np.empty((2, n), dtype=np.complex128)
    pair[0] = p
    pair[1] = q_n
    spectrum_p, spectrum_q = np.fft.fft(pair, axis=1)
    cross = np.conj(spectrum_p) * spectrum_q
    cross[0] = 0.0  # centres both contours: their position must not weigh on the shape
    # corr[d] = Σ_k Re(conj(p̃_k) q̃_{k+d}) = Σ_k P̃[k]·Q̃'[k+d]
    corr = np.fft.ifft(cross).real
    best = int(corr.argmax())
    shift = float(best)
    if n >= 3:
        shift = _peak(shift, *corr.take([best - 1, best, best + 1], mode="wrap").tolist())
    return shift, complex(spectrum_q[0] - spectrum_p[0]) / n


def _peak(shift: float, left: float, mid: float, right: float) -> float:
    """A sampled maximum moved between samples by the parabola through it and its
    neighbours (unmoved where they do not curve down)."""
    curvature = left - 2.0 * mid + right
    if curvature < 0.0:
        shift += 0.5 * (left - right) / curvature
    return shift


def _aligned_diagonal(
    p: ComplexArray, q: ComplexArray, p_walk: ComplexArray, plan: _Plan
) -> IntArray:
    """j - k (unwrapped) at which the fast search for each point k of P is centred.

    One global cyclic shift, plus each point's lag along the contour from the
    centroid's travel (module docstring). ``p_walk`` is ``p[plan.walk]``.
    """
    n, m = len(p), len(q)
    # Q resampled to N points by index, which is by arc length for an even contour.
    if n == m:
        q_ring = q.take(plan.lower)
    else:
        below = q.take(plan.lower)
        q_ring = q.take(plan.upper) - below
        q_ring *= plan.weight
        q_ring += below
    shift, travel = _global_shift(p, q_ring)
    pad = plan.pad
    tangent = p_walk[pad + 1 : pad + 1 + n] - p_walk[pad - 1 : pad - 1 + n]
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
    return np.rint(diagonal, out=diagonal).astype(np.intp)


def _pick(cost: FloatArray, first: IntArray, m: int) -> IntArray:
    """Column of each row's smallest cost; equal costs go to the smallest j mod M, as
    ``argmin`` over j does in the exhaustive search.

    Row r's candidates are the consecutive unwrapped indices ``first[r] + column``, so
    the first minimum along a row is already the smallest j unless the row wraps past
    a multiple of M. In those rows the columns after the wrap are made one ulp cheaper
    (in a copy), which moves equal costs onto them and changes no strict order.
    """
    chosen = cost.argmin(axis=1)
    width = cost.shape[1]
    residue = first % m
    wraps = (residue > m - width).nonzero()[0]
    if wraps.size:
        ranked = cost[wraps]
        after = np.arange(width) >= (m - residue[wraps])[:, None]
        np.nextafter(ranked, -np.inf, out=ranked, where=after)
        chosen[wraps] = ranked.argmin(axis=1)
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


def _candidate_costs(
    p_walk: ComplexArray,
    q: ComplexArray,
    base: IntArray,
    begin: int,
    lowest: int,
    highest: int,
    pad: int,
    half: int,
    search: int,
) -> FloatArray:
    """D[k, k + base[r] - S + c] for the points k = begin + r of a block, r < len(base),
    and the columns c = 0 .. 2S: shape (len(base), 2S + 1). ``lowest`` and ``highest``
    bound ``base``; ``p_walk`` is P[k - pad .. N - 1 + pad], circular."""
    size = len(base)
    width = 2 * search + 1
    count = highest - lowest + width
    # Row s of the table pairs P[begin + s - h] with Q[begin + s - h + lowest - S + d]
    # along the diagonal j - k = lowest - S + d, s running h beyond both ends of the
    # block so that the windows of its end points pair the right points. Row s + 1 is
    # row s moved one point along Q: a strided view of one strip of Q.
    span = size + 2 * half
    first = begin + lowest - search - half
    strip = q.take(np.arange(first, first + span + count - 1), mode="wrap")
    step = strip.strides[0]
    shifted = np.ndarray((span, count), np.complex128, strip, 0, (step, step))
    start = begin + pad - half
    gap = shifted - p_walk[start : start + span, None]
    squares = gap.view(np.float64)
    np.multiply(squares, squares, out=squares)
    table = squares[:, 0::2] + squares[:, 1::2]  # squared distances
    # Window sums down the table, in place: row r adds rows r + 1 .. r + 2h in pairs
    # (a running sum is a chain of dependent additions, several times slower).
    if half:
        pairs = table[:-1] + table[1:]
        for i in range(1, 2 * half, 2):
            table[:size] += pairs[i : i + size]
    # Each point's 2S + 1 candidates lie side by side in its row of the window sums:
    # the rows of a sliding view.
    flat = table[:size].reshape(-1)
    step = flat.strides[0]
    candidates = np.ndarray((len(flat) - width + 1, width), np.float64, flat, 0, (step, step))
    offset = np.arange(0, size * count, count)
    offset += base
    offset -= lowest
    cost: FloatArray = candidates[offset]
    return cost


def _match_fast(
    p: ComplexArray, q: ComplexArray, half: int, search: int
) -> tuple[IntArray, FloatArray]:
    """Successors, shape (N,), and their window costs D[k, successor[k]], shape (N,)
    (:func:`match_fast`)."""
    n, m = len(p), len(q)
    plan = _plan(n, m, half, search)
    width = 2 * search + 1
    p_walk = p.take(plan.walk)
    base = _aligned_diagonal(p, q, p_walk, plan)
    lowest, highest = int(base.min()), int(base.max())
    if highest - lowest >= m:  # diagonals repeat every M
        base %= m
        lowest, highest = int(base.min()), int(base.max())
    # Bounded blocks of points keep the table in the caches and its temporaries
    # small enough that the allocator neither maps nor returns memory on every call
    # (page faults cost more than the arithmetic); each block spans only the
    # diagonals its own points need.
    block = max(1, _TABLE_SIZE // (highest - lowest + width))
    if block >= n:
        cost = _candidate_costs(p_walk, q, base, 0, lowest, highest, plan.pad, half, search)
    else:
        blocks = []
        for begin in range(0, n, block):
            part = base[begin : begin + block]
            low, high = int(part.min()), int(part.max())
            blocks.append(
                _candidate_costs(p_walk, q, part, begin, low, high, plan.pad, half, search)
            )
        cost = np.concatenate(blocks)
    first = base + plan.first  # the unwrapped j of column 0
    chosen = _pick(cost, first, m)
    successor = first + chosen
    minimum = cost[plan.rows, chosen]

    # A minimum on the edge of the range may continue beyond it: search again around
    # it until the minimum is inside (each round's cost is no larger than the last).
    if search > 0 and width < m:
        rows = plan.edge.take(chosen).nonzero()[0]
        for _ in range(m // search + 1):
            if rows.size == 0:
                break
            first = successor[rows] - search
            local = _local_costs(p, q, half, rows, first, width)
            chosen = _pick(local, first, m)
            successor[rows] = first + chosen
            minimum[rows] = local[np.arange(len(rows)), chosen]
            rows = rows[plan.edge.take(chosen)]
    successor %= m
    return successor, minimum


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
    return _match_fast(_complex(p), _complex(q), _half(window), int(search))[0]


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
    return _anchors(has, np.array([0, len(has)], dtype=np.intp))


@njit
def _anchors(has: NDArray[np.bool_], bounds: IntArray) -> IntArray:
    """:func:`new_point_anchors` of many contours at once (contour c is
    ``has[bounds[c]:bounds[c + 1]]``); indices along all of them."""
    anchor = np.full(len(has), -1, np.intp)
    for c in range(len(bounds) - 1):
        lo, hi = bounds[c], bounds[c + 1]
        size = hi - lo
        last = -1  # the last point with a predecessor, walking forward
        for i in range(size):
            if has[lo + i]:
                last = i
        if last < 0:
            continue  # nothing kept: every point stays at -1
        first = 0  # the first point with a predecessor
        while not has[lo + first]:
            first += 1
        # Steps back to the nearest kept point walking forward, and steps ahead to it
        # walking backward, each starting from the kept point across the wrap.
        behind = np.empty(size, np.intp)
        steps = size - last - 1
        for i in range(size):
            steps = 0 if has[lo + i] else steps + 1
            behind[i] = steps
        ahead = np.empty(size, np.intp)
        steps = first
        for i in range(size - 1, -1, -1):
            steps = 0 if has[lo + i] else steps + 1
            ahead[i] = steps
        for i in range(size):
            if has[lo + i]:
                continue
            if behind[i] <= ahead[i]:
                anchor[lo + i] = lo + (i - behind[i]) % size
            else:
                anchor[lo + i] = lo + (i + ahead[i]) % size
    return anchor


@dataclass(frozen=True, eq=False)
class Correspondence:
    """Which particle every current contour point inherits (module docstring).

    Attributes:
        successor: shape (N,), for each previous point k the current point it moved
            to, indices into the current contour.
        cost: shape (N,), the window cost D[k, successor[k]], metres² (the frame's
            unit squared): computed directly for the exhaustive search, the fast
            matcher's own window sum for the fast one (equal up to rounding, which
            can settle an exact tie between two previous points differently).
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
            most 256² (fingertip contours have 10-60 points), where the paper's search
            was measured to cost at most twice the fast one (the fast matcher's fixed
            cost of a few dozen numpy calls outweighs the N × M product below about
            128 points).
        search: the fast matcher's half-width S.

    Returns:
        A :class:`Correspondence` whose arrays are read-only.
    """
    p = _contour(previous, "previous")
    q = _contour(current, "current")
    return correspond_batch(
        p, np.array([0, len(p)]), q, np.array([0, len(q)]), window, method, search
    )


def correspond_batch(
    previous: NDArray[np.float64],
    previous_bounds: IntArray,
    current: NDArray[np.float64],
    current_bounds: IntArray,
    window: int,
    method: Literal["fast", "exhaustive", "auto"] = "fast",
    search: int = 3,
) -> Correspondence:
    """:func:`correspond` for the contours of many contacts at once.

    Contour pair c is ``previous[previous_bounds[c]:previous_bounds[c + 1]]`` and
    ``current[current_bounds[c]:current_bounds[c + 1]]``; each pair is matched on its
    own, as :func:`correspond` matches it, but the small exhaustive searches
    (fingertips: the per-frame case) run in one compiled call (module docstring), so a
    frame costs a few calls however many fingers touch.

    Args:
        previous: the previous contours one after another, shape (N, 2), metres.
        previous_bounds: shape (C + 1,), from 0 to N, strictly increasing.
        current: the current contours one after another, shape (M, 2), same frame.
        current_bounds: shape (C + 1,), from 0 to M, strictly increasing.
        window, method, search: as for :func:`correspond`, for every pair.

    Returns:
        A :class:`Correspondence` whose indices run along all the contours (a
        successor of a point of pair c is a point of pair c's current contour).
    """
    if method not in ("fast", "exhaustive", "auto"):
        raise ValueError(f"method must be 'fast', 'exhaustive' or 'auto', got {method!r}")
    half = _half(window)
    n, m = np.diff(previous_bounds), np.diff(current_bounds)
    if method == "exhaustive":
        exhaustive = np.ones(len(n), dtype=bool)
    elif method == "fast":
        exhaustive = np.zeros(len(n), dtype=bool)
    else:
        exhaustive = n * m <= _AUTO_EXHAUSTIVE
    if search < 0 and not exhaustive.all():
        raise ValueError(f"search must be >= 0, got {search}")
    successor = np.empty(len(previous), dtype=np.intp)
    cost = np.empty(len(previous))
    # Small exhaustive searches in one compiled call; large ones and fast ones pair
    # by pair.
    small = exhaustive & (n * m <= _DIRECT_PAIRS)
    if small.any():
        _exhaustive_direct(
            np.ascontiguousarray(previous, dtype=np.float64),
            np.asarray(previous_bounds, dtype=np.intp),
            np.ascontiguousarray(current, dtype=np.float64),
            np.asarray(current_bounds, dtype=np.intp),
            small,
            half,
            successor,
            cost,
        )
    for c in np.flatnonzero(~small).tolist():
        lo, hi = previous_bounds[c], previous_bounds[c + 1]
        p = previous[lo:hi]
        q = current[current_bounds[c] : current_bounds[c + 1]]
        if exhaustive[c]:
            local = match_exhaustive(p, q, window)
            cost[lo:hi] = window_costs(p, q, local, window)
        else:
            local, cost[lo:hi] = _match_fast(_complex(p), _complex(q), half, int(search))
        successor[lo:hi] = local + current_bounds[c]
    predecessor, kept, anchor = _particles(
        successor, cost, np.asarray(current_bounds, dtype=np.intp)
    )
    for array in (successor, cost, predecessor, kept, anchor):
        array.setflags(write=False)
    return Correspondence(successor, cost, predecessor, kept, anchor)


@njit
def _exhaustive_direct(
    previous: FloatArray,
    previous_bounds: IntArray,
    current: FloatArray,
    current_bounds: IntArray,
    pairs: NDArray[np.bool_],
    half: int,
    successor: IntArray,
    cost: FloatArray,
) -> None:
    """The exhaustive search of each contour pair c with ``pairs[c]``: every window
    cost D[k, j] summed directly (exact, so the smallest j wins every tie); writes
    the successors (indices along all current contours) and their costs."""
    width = 2 * (2 * half + 1)
    for c in range(len(pairs)):
        if not pairs[c]:
            continue
        p_lo, q_lo = previous_bounds[c], current_bounds[c]
        n, m = previous_bounds[c + 1] - p_lo, current_bounds[c + 1] - q_lo
        # Each point's window as one flat vector: the inner loop then runs without
        # index arithmetic.
        p_windows = np.empty((n, width))
        q_windows = np.empty((m, width))
        for i in range(-half, half + 1):
            column = 2 * (i + half)
            for k in range(n):
                a = p_lo + (k + i) % n
                p_windows[k, column] = previous[a, 0]
                p_windows[k, column + 1] = previous[a, 1]
            for j in range(m):
                b = q_lo + (j + i) % m
                q_windows[j, column] = current[b, 0]
                q_windows[j, column + 1] = current[b, 1]
        for k in range(n):
            best, best_cost = 0, np.inf
            for j in range(m):
                total = 0.0
                for d in range(width):
                    gap = p_windows[k, d] - q_windows[j, d]
                    total += gap * gap
                if total < best_cost:
                    best, best_cost = j, total
            successor[p_lo + k] = q_lo + best
            cost[p_lo + k] = best_cost


@njit
def _particles(
    successor: IntArray, cost: FloatArray, current_bounds: IntArray
) -> tuple[IntArray, NDArray[np.bool_], IntArray]:
    """Predecessors, kept particles and anchors (module docstring) of a batch."""
    predecessor = np.full(current_bounds[-1], -1, np.intp)
    # Among the previous points naming the same successor the cheapest, then the
    # lowest index, is its predecessor.
    for k in range(len(successor)):
        j = successor[k]
        if predecessor[j] < 0 or cost[k] < cost[predecessor[j]]:
            predecessor[j] = k
    kept = np.empty(len(successor), np.bool_)
    for k in range(len(successor)):
        kept[k] = predecessor[successor[k]] == k
    return predecessor, kept, _anchors(predecessor >= 0, current_bounds)
