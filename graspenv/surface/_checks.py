"""Argument checks shared by the surface modules: a bad value from a user becomes a
ValueError that names the argument and says what was expected."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray


def finite(value: Any, name: str) -> float:
    """``value`` as a float; ValueError unless it is a finite real number."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number, got {value!r}") from None
    if not math.isfinite(number):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return number


def positive(value: Any, name: str) -> float:
    """``value`` as a float; ValueError unless it is finite and > 0."""
    number = finite(value, name)
    if number <= 0.0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return number


def non_negative(value: Any, name: str) -> float:
    """``value`` as a float; ValueError unless it is finite and >= 0."""
    number = finite(value, name)
    if number < 0.0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return number


def count(value: Any, name: str, minimum: int = 0) -> int:
    """``value`` as an int; ValueError unless it is an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def vector2(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """``value`` as a new finite float array of shape (2,)."""
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be 2 finite numbers (x, y), got {value!r}") from None
    if array.shape != (2,) or not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be 2 finite numbers (x, y), got {value!r}")
    return array


def points(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """``value`` as a finite float array of shape (N, 2) (N may be 0)."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an array of shape (N, 2), got {value!r}") from None
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(f"{name} must have shape (N, 2), got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must hold finite values only")
    return array
