"""Touches: validation, bounds, and where a touch lands on the table."""

from __future__ import annotations

import math

import numpy as np
import pytest

from graspenv.live.touches import (
    DEFAULT_RADIUS,
    MAX_SOURCES,
    MAX_TOUCHES,
    InputError,
    Touch,
    TouchBoard,
    parse_touches,
)
from graspenv.surface.geometry import Surface


def test_corners_and_centre_land_where_the_mask_has_them() -> None:
    surface = Surface()
    w, h = surface.size
    # The canvas's top left is the table's (-x, +y) corner, as the mask's row 0.
    for (x, y), world in [
        ((0, 0), (-w / 2, h / 2)),
        ((1, 1), (w / 2, -h / 2)),
        ((0.5, 0.5), (0, 0)),
    ]:
        centre = Touch(x, y).shape(surface).centre
        np.testing.assert_allclose(centre, world, atol=1e-12)


def test_radii_scale_with_the_table_and_default_to_a_fingertip() -> None:
    surface = Surface()
    shape = Touch(0.5, 0.5, rx=0.02, ry=0.04).shape(surface)
    np.testing.assert_allclose(shape.radii, (0.02 * surface.size[0], 0.04 * surface.size[1]))
    assert Touch(0.5, 0.5).shape(surface).radii == (DEFAULT_RADIUS, DEFAULT_RADIUS)
    # A screen-clockwise rotation is clockwise seen from above: negative about +z.
    assert Touch(0.5, 0.5, angle=0.3).shape(surface).angle == pytest.approx(-0.3)


def test_parse_accepts_what_browsers_send() -> None:
    touches = parse_touches(
        [{"x": 0.25, "y": 0.75, "rx": 0.01, "ry": None, "angle": 0.5}, {"x": 1, "y": 0}]
    )
    assert touches == [Touch(0.25, 0.75, 0.01, None, 0.5), Touch(1.0, 0.0)]
    assert parse_touches([{"x": 0.5, "y": 0.5, "rx": 0, "ry": 0}])[0].rx is None


@pytest.mark.parametrize(
    "items, words",
    [
        ("not a list", "must be a list"),
        ([1], "must be an object"),
        ([{"x": math.nan, "y": 0.5}], "finite"),
        ([{"x": math.inf, "y": 0.5}], "finite"),
        ([{"x": 0.5, "y": 1.5}], "in [0.0, 1.0]"),
        ([{"x": 0.5}], "must be a number"),
        ([{"x": "0.5", "y": 0.5}], "must be a number"),
        ([{"x": True, "y": 0.5}], "must be a number"),
        ([{"x": 0.5, "y": 0.5, "rx": -0.1}], "rx"),
        ([{"x": 0.5, "y": 0.5, "angle": 1e9}], "angle"),
        ([{"x": 0.5, "y": 0.5}] * (MAX_TOUCHES + 1), f"at most {MAX_TOUCHES}"),
    ],
)
def test_parse_rejects_bad_touches(items: object, words: str) -> None:
    with pytest.raises(InputError) as err:
        parse_touches(items)
    assert words in str(err.value)


def test_the_board_merges_sources_and_bounds_them() -> None:
    board = TouchBoard()
    board.put("a", [Touch(0.1, 0.1)])
    board.put("b", [Touch(0.2, 0.2), Touch(0.3, 0.3)])
    assert len(board.touches()) == 3 and board.sources == 2
    board.put("a", [])
    assert board.touches() == [Touch(0.2, 0.2), Touch(0.3, 0.3)]
    board.drop("b")
    assert board.touches() == []
    for i in range(MAX_SOURCES):
        board.put(f"s{i}", [Touch(0.5, 0.5)])
    with pytest.raises(InputError, match="sources"):
        board.put("one too many", [Touch(0.5, 0.5)])
    with pytest.raises(InputError, match="touches per source"):
        board.put("s0", [Touch(0.5, 0.5)] * (MAX_TOUCHES + 1))
