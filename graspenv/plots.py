"""The project's charts, drawn with matplotlib (the Agg backend: no display needed):
line charts (learning curves, noise levels, frame cost), grouped bar charts (the
strategy benchmark), speed-against-error scatters with their Pareto front (the
fidelity benchmark) and annotated heat maps (the grasp-space grid).

Each chart comes back as a BGR ``uint8`` image of the size asked for, so pictures
can be put side by side and written with :func:`write_png`. matplotlib is the
``plots`` extra (``pip install 'graspenv[plots]'``; the ``train`` and ``dev`` extras
include it); without it a chart raises a ModuleNotFoundError that says so.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "HeatPanel",
    "bar_chart",
    "heat_maps",
    "line_chart",
    "pareto_chart",
    "pareto_front",
    "write_png",
]

#: Colour-blind-safe palette (Okabe–Ito).
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#D55E00", "#56B4E9", "#F0E442", "#000000")
INK = "#282828"
MUTED = "#787878"
_DPI = 100


def _pyplot() -> Any:
    """matplotlib's pyplot on the Agg backend, or an ImportError naming the extra."""
    try:
        import matplotlib
    except ImportError as error:
        raise ModuleNotFoundError(
            "graspenv's charts need matplotlib: pip install 'graspenv[plots]'",
            name="matplotlib",
        ) from error
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    from cycler import cycler

    plt.rcParams.update(
        {
            "axes.prop_cycle": cycler(color=PALETTE),
            "axes.edgecolor": INK,
            "axes.labelcolor": INK,
            "axes.titlesize": 11,
            "axes.labelsize": 9,
            "xtick.labelsize": 8,
            "ytick.labelsize": 8,
            "legend.fontsize": 8,
            "legend.frameon": False,
            "axes.grid": True,
            "grid.color": "#e1e1e1",
            "axes.axisbelow": True,
        }
    )
    return plt


def _figure(size: tuple[int, int]) -> tuple[Figure, Axes]:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(size[0] / _DPI, size[1] / _DPI), dpi=_DPI)
    return fig, ax


def _image(fig: Figure, path: str | Path | None) -> NDArray[np.uint8]:
    """The figure as a BGR image (written as PNG when ``path`` is given), closed."""
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())  # type: ignore[attr-defined]
    image = np.ascontiguousarray(rgba[:, :, 2::-1])
    _pyplot().close(fig)
    if path is not None:
        write_png(image, path)
    return image


def line_chart(
    series: Mapping[str, tuple[Sequence[float], Sequence[float]]],
    path: str | Path | None,
    title: str,
    xlabel: str,
    ylabel: str,
    ylim: tuple[float, float] | None = None,
    size: tuple[int, int] = (720, 420),
    categories: Sequence[str] = (),
    guides: Mapping[str, float] | None = None,
) -> NDArray[np.uint8]:
    """One line per series ``name → (x, y)``, points marked (non-finite y left out);
    with ``categories`` the x values 0, 1, ... are those names; each of ``guides``
    (``name → y``, a target) a dashed grey line across. Written as PNG when ``path``
    is given."""
    fig, ax = _figure(size)
    for name, (x, y) in series.items():
        xs, ys = np.asarray(x, float), np.asarray(y, float)
        keep = np.isfinite(ys)
        ax.plot(xs[keep], ys[keep], marker="o", markersize=3, linewidth=1.6, label=name)
    for name, level in (guides or {}).items():
        ax.axhline(level, color="0.35", linestyle="--", linewidth=1.2, label=name)
    xs_all = [float(v) for x, _ in series.values() for v in x]
    if xs_all:
        ax.set_xlim(min(0.0, min(xs_all)), max(xs_all) if max(xs_all) > 0 else 1.0)
    if categories:
        ax.set_xticks(range(len(categories)), list(categories))
        ax.set_xlim(-0.2, len(categories) - 0.8)
    if ylim is not None:
        ax.set_ylim(*ylim)
    ax.set(title=title, xlabel=xlabel, ylabel=ylabel)
    if series:
        ax.legend(loc="best")
    fig.tight_layout()
    return _image(fig, path)


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
    out. ``errors`` gives (low, high) whiskers per bar, as values. Written as PNG
    when ``path`` is given."""
    n = max(len(series), 1)
    width = size[0] if size else max(480, 90 + len(groups) * (30 * n + 40))
    fig, ax = _figure((width, size[1] if size else 420))
    slot = 0.8 / n
    centres = np.arange(len(groups), dtype=float)
    for s, (name, values) in enumerate(series.items()):
        heights = np.asarray(values, float)
        keep = np.isfinite(heights)
        x = centres - 0.4 + slot * (s + 0.5)
        ax.bar(x[keep], heights[keep] - ylim[0], slot * 0.92, bottom=ylim[0], label=name)
        if errors is not None and name in errors:
            bounds = np.asarray(errors[name], float)
            mid = np.where(keep, heights, np.nan)
            low = np.maximum(mid - bounds[:, 0], 0.0)[keep]
            high = np.maximum(bounds[:, 1] - mid, 0.0)[keep]
            ax.errorbar(
                x[keep], heights[keep], yerr=[low, high], fmt="none", ecolor=INK, elinewidth=1,
                capsize=3,
            )  # fmt: skip
    ax.set_xticks(centres, list(groups), fontsize=8)
    ax.set_xlim(-0.5, len(groups) - 0.5)
    ax.set_ylim(*ylim)
    ax.set(title=title, ylabel=ylabel)
    ax.grid(axis="x", visible=False)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=min(n, 6))
    fig.tight_layout()
    return _image(fig, path)


def write_png(img: NDArray[np.uint8], path: str | Path) -> Path:
    """Write a BGR image as PNG (its folders made as needed)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(path), img, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
        raise OSError(f"could not write {path}")
    return path


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
    fig, ax = _figure(size)
    front = pareto_front(points)
    shown = [i for i, (x, y) in enumerate(points) if x > 0 and np.isfinite(y)]

    def error(y: float) -> float:
        return max(y, floor) if log_error else y

    off = [i for i in shown if i not in front]
    ax.scatter(
        [points[i][0] for i in off], [error(points[i][1]) for i in off], s=12, color=INK,
        zorder=3,
    )  # fmt: skip
    ax.plot(
        [points[i][0] for i in front], [error(points[i][1]) for i in front], marker="o",
        markersize=6, linewidth=2, color=PALETTE[1], zorder=4, label="Pareto front",
    )  # fmt: skip
    for i in shown:
        if i in front or labels[i] in labelled:
            ax.annotate(
                labels[i], (points[i][0], error(points[i][1])), xytext=(5, 5),
                textcoords="offset points", fontsize=7, color=INK if i in front else MUTED,
            )  # fmt: skip
    from matplotlib.ticker import FuncFormatter

    plain = FuncFormatter(lambda value, _: f"{value:g}")
    ax.set_xscale("log")
    ax.xaxis.set_major_formatter(plain)
    ax.xaxis.set_minor_formatter(plain)
    if log_error:
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(plain)
    else:
        top = max((points[i][1] for i in shown), default=1.0)
        ax.set_ylim(0.0, 1.12 * max(top, 1e-9))
    ax.margins(x=0.12)
    ax.set(title=title, xlabel=xlabel, ylabel=ylabel)
    ax.legend(loc="best")
    fig.tight_layout()
    return _image(fig, path)


def sorted_errors(
    title: str,
    panels: Sequence[tuple[str, Mapping[str, Sequence[float]], float]],
    note: str = "",
    size: tuple[int, int] = (1080, 380),
) -> NDArray[np.uint8]:
    """Side-by-side panels, each series' values sorted and drawn against their share
    of the series (0 to 1), so that the share beyond the target reads off the x
    axis; the target dashed at ±target, NaN left out.

    Args:
        title: the figure's title.
        panels: ``(title, {series name: values}, target)`` per panel, the target in
            the values' unit.
        note: a line under the panels.
        size: the picture's width and height, pixels.

    Returns:
        The picture, BGR.
    """
    plt = _pyplot()
    fig, axes = plt.subplots(
        1, len(panels), figsize=(size[0] / _DPI, size[1] / _DPI), dpi=_DPI, squeeze=False
    )
    for ax, (label, series, target) in zip(axes[0], panels, strict=True):
        for name, values in series.items():
            raw = np.asarray(values, float)
            ys = np.sort(raw[np.isfinite(raw)])
            if ys.size:
                xs = (np.arange(ys.size) + 0.5) / ys.size
                ax.plot(
                    xs, ys, marker="o", markersize=3, linewidth=1.0, label=f"{name} ({ys.size})"
                )
        for level in (-target, target):
            ax.axhline(level, color="0.35", linestyle="--", linewidth=1.2)
        ax.set(title=label, xlabel="share of the cells, sorted by error", xlim=(0.0, 1.0))
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper left")
    fig.suptitle(title, fontsize=11)
    if note:
        fig.text(0.5, 0.01, note, ha="center", va="bottom", fontsize=8, color=MUTED)
    fig.tight_layout(rect=(0.0, 0.05 if note else 0.0, 1.0, 1.0))
    return _image(fig, None)


class HeatPanel:
    """One panel of :func:`heat_maps`: a table of values coloured by their size
    against a target.

    Args:
        title: the panel's title.
        values: shape (rows, columns), NaN where there is no value; row 0 is drawn at
            the bottom.
        target: the |value| drawn at the middle of the colour scale (green under it,
            red at twice it).
        hatched: shape like ``values``, True where a cell is drawn hatched (not
            counted); None for none.
    """

    def __init__(
        self,
        title: str,
        values: NDArray[np.float64],
        target: float,
        hatched: NDArray[np.bool_] | None = None,
    ) -> None:
        self.title = title
        self.values = np.asarray(values, float)
        self.target = float(target)
        self.hatched = (
            np.zeros(self.values.shape, bool) if hatched is None else np.asarray(hatched, bool)
        )


def _signed(value: float) -> str:
    if not math.isfinite(value):
        return "-"
    return f"{value:+.2f}" if abs(value) < 10 else f"{value:+.0f}"


def heat_maps(
    title: str,
    panels: Sequence[HeatPanel],
    x_labels: Sequence[str],
    y_labels: Sequence[str],
    xlabel: str,
    ylabel: str,
    note: str = "",
    cell: tuple[int, int] = (74, 40),
    text: Callable[[float], str] | None = None,
) -> NDArray[np.uint8]:
    """Side-by-side annotated heat maps sharing their axes, each cell's value printed
    in it and coloured green (0) through yellow (at the panel's target) to red
    (twice it and beyond); grey where there is no value."""
    plt = _pyplot()
    from matplotlib.colors import LinearSegmentedColormap

    scale = LinearSegmentedColormap.from_list(
        "target", [(0.0, "#5ac878"), (0.5, "#f0dc50"), (1.0, "#dc4646")]
    ).with_extremes(bad="#c8c8c8")
    rows, columns = len(y_labels), len(x_labels)
    width = 90 + len(panels) * (columns * cell[0] + 40)
    height = 110 + rows * cell[1]
    fig, axes = plt.subplots(
        1, len(panels), figsize=(width / _DPI, height / _DPI), dpi=_DPI, squeeze=False,
        sharey=True,
    )  # fmt: skip
    show = text or (
        lambda v: "-" if not math.isfinite(v) else f"{v:+.2f}" if abs(v) < 10 else f"{v:+.0f}"
    )
    for ax, panel in zip(axes[0], panels, strict=True):
        ratio = np.abs(panel.values) / panel.target / 2.0
        ax.imshow(
            np.ma.masked_invalid(np.clip(ratio, 0.0, 1.0)), cmap=scale, vmin=0.0, vmax=1.0,
            origin="lower", aspect="auto",
        )  # fmt: skip
        for (r, c), value in np.ndenumerate(panel.values):
            ax.text(c, r, show(value), ha="center", va="center", fontsize=7.5, color=INK)
            if panel.hatched[r, c]:
                ax.add_patch(
                    plt.Rectangle(
                        (c - 0.5, r - 0.5), 1, 1, fill=False, hatch="///", edgecolor=MUTED,
                        linewidth=0,
                    )
                )  # fmt: skip
        ax.set_xticks(range(columns), list(x_labels), fontsize=7.5)
        ax.set_yticks(range(rows), list(y_labels), fontsize=7.5)
        ax.set_xticks(np.arange(columns + 1) - 0.5, minor=True)
        ax.set_yticks(np.arange(rows + 1) - 0.5, minor=True)
        ax.grid(which="minor", color="white", linewidth=2)
        ax.grid(which="major", visible=False)
        ax.tick_params(which="minor", length=0)
        ax.set_title(panel.title, fontsize=9)
        ax.set_xlabel(xlabel)
    axes[0][0].set_ylabel(ylabel)
    fig.suptitle(title, fontsize=10, x=0.01, ha="left")
    if note:
        fig.text(0.01, 0.01, note, fontsize=7.5, color=MUTED)
    fig.tight_layout(rect=(0.0, 0.05 if note else 0.0, 1.0, 1.0))
    return _image(fig, None)
