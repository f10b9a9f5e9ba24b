"""The charts of graspenv/plots.py: sizes, colours where the values say, the front."""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from graspenv.plots import HeatPanel, heat_maps, line_chart, pareto_chart, sorted_errors


def test_heat_maps_colour_cells_by_their_error_over_the_target(tmp_path: Path) -> None:
    values = np.array([[0.0, 2.0], [10.0, np.nan]])
    image = heat_maps(
        "title", [HeatPanel("turn", values, target=1.0)], ["a", "b"], ["p", "q"], "x", "y"
    )
    assert image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3
    hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
    saturated = hsv[:, :, 1] > 120
    hue = hsv[:, :, 0]
    green = saturated & (hue > 45) & (hue < 85)  # the 0 error
    red = saturated & ((hue < 8) | (hue > 170))  # 10 and 2, at or past twice the target
    assert green.sum() > 500 and red.sum() > 1000


def test_pareto_chart_and_line_chart_write_pngs_of_their_size(tmp_path: Path) -> None:
    points = [(100.0, 1.0), (200.0, 0.5), (50.0, 2.0), (400.0, 3.0)]
    pareto = pareto_chart(
        ["a", "b", "c", "d"], points, tmp_path / "p.png", "t", "x", "y", size=(600, 400)
    )
    assert pareto.shape == (400, 600, 3)
    line = line_chart(
        {"s": ([0, 1, 2], [1.0, np.nan, 3.0])}, tmp_path / "l.png", "t", "x", "y",
        size=(500, 300), categories=["one", "two", "three"],
    )  # fmt: skip
    assert line.shape == (300, 500, 3)
    for name in ("p.png", "l.png"):
        assert cv2.imread(str(tmp_path / name)) is not None


def test_without_matplotlib_a_chart_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(ModuleNotFoundError, match=r"graspenv\[plots\]") as raised:
        line_chart({"s": ([0, 1], [0.0, 1.0])}, None, "t", "x", "y")
    assert raised.value.name == "matplotlib"


def test_sorted_errors_draw_each_panel_with_its_series() -> None:
    panels = [
        ("turn", {"boxes": [0.5, -0.2, np.nan], "cylinders": [1.5]}, 1.0),
        ("slip", {"boxes": [], "cylinders": [-3.0, 7.0]}, 5.0),
    ]
    image = sorted_errors("title", panels, note="dashed: the target", size=(800, 300))
    assert image.shape == (300, 800, 3)
    # Something drawn in colour (the series), not a blank figure.
    hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
    assert (hsv[:, :, 1] > 120).sum() > 100
