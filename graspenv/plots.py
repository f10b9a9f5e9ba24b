"""Small charts drawn with OpenCV (the project's only image library): line charts
(learning curves), grouped bar charts (the strategy benchmark) and speed-against-
error scatters with their Pareto front (the fidelity benchmark)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["bar_chart", "line_chart", "pareto_chart", "pareto_front", "write_png"]

# Colour-blind-safe palette (Okabe–Ito), BGR.
PALETTE = [
    (178, 114, 0),
    (0, 159, 230),
    (115, 158, 0),
    (167, 121, 204),
    (0, 94, 213),
    (233, 180, 86),
    (66, 228, 240),
    (0, 0, 0),
]
FONT = cv2.FONT_HERSHEY_SIMPLEX
INK = (40, 40, 40)
MUTED = (120, 120, 120)
GRID = (225, 225, 225)


def _text(
    img: NDArray[np.uint8],
    text: str,
    org: tuple[int, int],
    scale: float = 0.45,
    anchor: str = "left",
    colour: tuple[int, int, int] = INK,
) -> None:
    (w, h), _ = cv2.getTextSize(text, FONT, scale, 1)
    x, y = org
    if anchor == "centre":
        x -= w // 2
    elif anchor == "right":
        x -= w
    cv2.putText(img, text, (x, y + h // 2), FONT, scale, colour, 1, cv2.LINE_AA)


def _ticks(lo: float, hi: float, n: int = 5) -> NDArray[np.float64]:
    span = hi - lo if hi > lo else 1.0
    raw = span / n
    step = 10 ** np.floor(np.log10(raw))
    for factor in (1, 2, 2.5, 5, 10):
        if step * factor >= raw:
            step *= factor
            break
    first = np.ceil(lo / step) * step
    return np.arange(first, hi + 1e-9 * span, step)


def _label(value: float) -> str:
    if value != 0 and (abs(value) >= 1e5 or abs(value) < 1e-2):
        return f"{value:.0e}".replace("e+0", "e").replace("e+", "e")
    return f"{value:g}"


class _Axes:
    def __init__(
        self,
        size: tuple[int, int],
        xlim: tuple[float, float],
        ylim: tuple[float, float],
        margin: tuple[int, int, int, int] = (70, 20, 45, 55),
    ) -> None:
        self.width, self.height = size
        self.left, self.right, self.top, self.bottom = margin
        self.xlim, self.ylim = xlim, ylim
        self.img = np.full((self.height, self.width, 3), 255, np.uint8)

    def x(self, value: float) -> int:
        lo, hi = self.xlim
        span = self.width - self.left - self.right
        return round(self.left + (value - lo) / max(hi - lo, 1e-12) * span)

    def y(self, value: float) -> int:
        lo, hi = self.ylim
        span = self.height - self.top - self.bottom
        return round(self.height - self.bottom - (value - lo) / max(hi - lo, 1e-12) * span)

    def frame(
        self, title: str, xlabel: str, ylabel: str, xticks: bool = True, yticks: bool = True
    ) -> None:
        img = self.img
        for tick in _ticks(*self.ylim) if yticks else ():
            cv2.line(img, (self.left, self.y(tick)), (self.width - self.right, self.y(tick)), GRID)
            _text(img, _label(tick), (self.left - 6, self.y(tick)), anchor="right")
        if xticks:
            for tick in _ticks(*self.xlim):
                _text(
                    img,
                    _label(tick),
                    (self.x(tick), self.height - self.bottom + 14),
                    anchor="centre",
                )
        cv2.rectangle(
            img, (self.left, self.top), (self.width - self.right, self.height - self.bottom), INK
        )
        _text(img, title, (self.width // 2, 18), 0.55, "centre")
        _text(img, xlabel, (self.width // 2, self.height - 14), anchor="centre")
        ylabel_img = np.full((22, self.height), 255, np.uint8)
        cv2.putText(
            ylabel_img,
            ylabel,
            (self.height // 2 - 4 * len(ylabel), 16),
            FONT,
            0.45,
            40,
            1,
            cv2.LINE_AA,
        )
        rotated = cv2.rotate(ylabel_img, cv2.ROTATE_90_COUNTERCLOCKWISE)
        img[:, 2:24] = np.minimum(img[:, 2:24], rotated[:, :, None])


def _legend(img: NDArray[np.uint8], names: Sequence[str], x: int, y: int) -> None:
    for i, name in enumerate(names):
        colour = PALETTE[i % len(PALETTE)]
        cv2.rectangle(img, (x, y + 18 * i - 5), (x + 12, y + 18 * i + 5), colour, -1)
        _text(img, name, (x + 18, y + 18 * i))


def line_chart(
    series: Mapping[str, tuple[Sequence[float], Sequence[float]]],
    path: str | Path | None,
    title: str,
    xlabel: str,
    ylabel: str,
    ylim: tuple[float, float] | None = None,
    size: tuple[int, int] = (720, 420),
) -> NDArray[np.uint8]:
    """One line per series ``name → (x, y)`` (points marked); written as PNG when
    ``path`` is given."""
    xs = [float(v) for x, _ in series.values() for v in x] or [0.0, 1.0]
    ys = [float(v) for _, y in series.values() for v in y if np.isfinite(v)] or [0.0, 1.0]
    axes = _Axes(size, (min(0.0, min(xs)), max(xs)), ylim or (min(ys), max(ys)))
    axes.frame(title, xlabel, ylabel)
    for i, (x, y) in enumerate(series.values()):
        colour = PALETTE[i % len(PALETTE)]
        points = [(axes.x(a), axes.y(b)) for a, b in zip(x, y, strict=True) if np.isfinite(b)]
        if len(points) > 1:
            cv2.polylines(axes.img, [np.array(points, np.int32)], False, colour, 2, cv2.LINE_AA)
        for p in points:
            cv2.circle(axes.img, p, 3, colour, -1, cv2.LINE_AA)
    _legend(axes.img, list(series), axes.left + 10, axes.top + 12)
    return _write(axes.img, path)


def bar_chart(
    groups: Sequence[str],
    series: Mapping[str, Sequence[float]],
    path: str | Path | None,
    title: str,
    ylabel: str,
    ylim: tuple[float, float] = (0.0, 1.0),
    errors: Mapping[str, Sequence[tuple[float, float]]] | None = None,
    size: tuple[int, int] | None = None,
) -> NDArray[np.uint8]:
    """Grouped bars: for each group (x axis) one bar per series; NaN values are left
    out. ``errors`` gives (low, high) whiskers per bar. Written as PNG when ``path``
    is given."""
    n = max(len(series), 1)
    width = size[0] if size else max(480, 90 + len(groups) * (30 * n + 40))
    axes = _Axes(
        (width, size[1] if size else 420), (0.0, float(len(groups))), ylim, (70, 20, 45, 75)
    )
    axes.frame(title, "", ylabel, xticks=False)
    slot = (axes.x(1.0) - axes.x(0.0)) * 0.8 / n
    for g, group in enumerate(groups):
        _text(axes.img, group, (axes.x(g + 0.5), axes.height - axes.bottom + 14), 0.42, "centre")
        for s, (name, values) in enumerate(series.items()):
            value = float(values[g])
            if not np.isfinite(value):
                continue
            x0 = int(axes.x(g + 0.1) + s * slot)
            x1 = int(x0 + slot - 2)
            colour = PALETTE[s % len(PALETTE)]
            cv2.rectangle(
                axes.img, (x0, axes.y(max(value, ylim[0]))), (x1, axes.y(ylim[0])), colour, -1
            )
            if errors is not None and name in errors:
                lo, hi = errors[name][g]
                xc = (x0 + x1) // 2
                cv2.line(axes.img, (xc, axes.y(lo)), (xc, axes.y(hi)), INK, 1, cv2.LINE_AA)
                for v in (lo, hi):
                    cv2.line(axes.img, (xc - 3, axes.y(v)), (xc + 3, axes.y(v)), INK, 1)
    legend_x = axes.left + 10
    for s, name in enumerate(series):
        colour = PALETTE[s % len(PALETTE)]
        x = legend_x
        cv2.rectangle(axes.img, (x, axes.height - 30), (x + 12, axes.height - 20), colour, -1)
        _text(axes.img, name, (x + 17, axes.height - 25))
        (w, _), _ = cv2.getTextSize(name, FONT, 0.45, 1)
        legend_x += w + 40
    return _write(axes.img, path)


def write_png(img: NDArray[np.uint8], path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(path), img, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
        raise OSError(f"could not write {path}")
    return path


def _write(img: NDArray[np.uint8], path: str | Path | None) -> NDArray[np.uint8]:
    if path is not None:
        write_png(img, path)
    return img


def pareto_front(points: Sequence[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point beats on both speed (x, higher is
    better) and error (y, lower is better), in increasing x."""
    order = sorted(range(len(points)), key=lambda i: (-points[i][0], points[i][1]))
    front, best = [], np.inf
    for i in order:
        y = points[i][1]
        if np.isfinite(y) and y < best:
            front.append(i)
            best = y
    return sorted(front, key=lambda i: points[i][0])


_LOG_TICKS = (0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)


def pareto_chart(
    labels: Sequence[str],
    points: Sequence[tuple[float, float]],
    path: str | Path | None,
    title: str,
    xlabel: str,
    ylabel: str,
    size: tuple[int, int] = (760, 460),
    log_error: bool = False,
    labelled: Sequence[str] = (),
) -> NDArray[np.uint8]:
    """Scatter of (speed, error) with a logarithmic speed axis; the Pareto front is
    joined and labelled, and so are the points named in ``labelled`` (in grey when
    off the front). Written as PNG when ``path`` is given.

    With ``log_error`` the error axis is logarithmic too (errors below 0.01 are drawn
    at 0.01), so one far outlier does not flatten every other point onto the floor.
    """
    floor = 0.01

    def error(y: float) -> float:
        return math.log10(max(y, floor)) if log_error else y

    finite = [(x, y) for x, y in points if x > 0 and np.isfinite(y)]
    xs = np.log10([x for x, _ in finite] or [1.0])
    ys = [error(y) for _, y in finite] or [1.0]
    span = max(float(xs.max() - xs.min()), 0.3)
    xlim = (float(xs.min()) - 0.08 * span, float(xs.max()) + 0.25 * span)
    if log_error:
        low, high = min(ys), max(ys)
        pad = 0.08 * max(high - low, 0.5)
        ylim = (low - pad, high + pad)
    else:
        ylim = (0.0, 1.12 * max(max(ys), 1e-9))
    axes = _Axes(size, xlim, ylim)
    axes.frame(title, xlabel, ylabel, xticks=False, yticks=not log_error)
    for value in _LOG_TICKS:
        lx = math.log10(value)
        if xlim[0] <= lx <= xlim[1]:
            column = axes.x(lx)
            cv2.line(axes.img, (column, axes.top), (column, axes.height - axes.bottom), GRID)
            _text(axes.img, f"{value:g}", (column, axes.height - axes.bottom + 14), anchor="centre")
        if log_error and ylim[0] <= lx <= ylim[1]:
            row = axes.y(lx)
            cv2.line(axes.img, (axes.left, row), (axes.width - axes.right, row), GRID)
            _text(axes.img, f"{value:g}", (axes.left - 6, row), anchor="right")
    front = pareto_front(points)
    placed = [(axes.x(math.log10(points[i][0])), axes.y(error(points[i][1]))) for i in front]
    if len(placed) > 1:
        cv2.polylines(axes.img, [np.array(placed, np.int32)], False, PALETTE[1], 2, cv2.LINE_AA)
    for i, (x, y) in enumerate(points):
        if x <= 0 or not np.isfinite(y):
            continue
        p = (axes.x(math.log10(x)), axes.y(error(y)))
        on_front = i in front
        cv2.circle(
            axes.img, p, 5 if on_front else 3, PALETTE[1] if on_front else INK, -1, cv2.LINE_AA
        )
        if on_front or labels[i] in labelled:
            colour = INK if on_front else MUTED
            _text(axes.img, labels[i], (p[0] + 7, p[1] - 8), 0.38, colour=colour)
    return _write(axes.img, path)
