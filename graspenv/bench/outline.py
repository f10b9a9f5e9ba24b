"""Measure the traced and offset outlines against analytic ellipses.

Run: ``.venv/bin/python -m graspenv.bench.outline`` (from the project root).
Fingertip ellipses of 6-12 mm semi-axes at the default table's ~0.955 mm pixels,
rendered by pixel-centre sampling and by ``cv2.ellipse``; errors are signed distances
from outline points (vertices and edge midpoints) to the analytic boundary, pixels.
"""

from __future__ import annotations

import numpy as np

from graspenv.bench.contact_scenes import RASTERISERS, ellipse_mask, ellipse_signed_distance
from graspenv.config import OUTLINE_SMOOTHING
from graspenv.contacts.extract import find_components, find_outlines


def _with_midpoints(poly: np.ndarray) -> np.ndarray:
    return np.concatenate([poly, 0.5 * (poly + np.roll(poly, -1, axis=0))])


def main(count: int = 400, seed: int = 0) -> None:
    rng = np.random.default_rng(seed)
    shape = (64, 64)
    errors: dict[str, list[np.ndarray]] = {}
    lengths: dict[str, list[float]] = {}
    for _ in range(count):
        centre = rng.uniform(28.0, 36.0, size=2)
        axes = (float(rng.uniform(6.3, 12.6)), float(rng.uniform(6.3, 12.6)))
        angle = float(rng.uniform(0.0, np.pi))
        h = ((axes[0] - axes[1]) / (axes[0] + axes[1])) ** 2
        perimeter = np.pi * (axes[0] + axes[1]) * (1 + 3 * h / (10 + np.sqrt(4 - 3 * h)))
        for render in RASTERISERS:
            mask = ellipse_mask(shape, centre, axes, angle, render)
            (component,) = find_components(mask)
            smoothed = find_outlines(mask, 0.0, OUTLINE_SMOOTHING).outlines.points
            for name, poly in (
                ("traced", component.chain),
                ("offset", component.outline),
                ("smoothed", smoothed),
            ):
                pts = _with_midpoints(np.asarray(poly, dtype=float))
                d = ellipse_signed_distance(pts, centre, axes, angle)
                errors.setdefault(f"{render:12s} {name:8s}", []).append(d)
                closed = np.asarray(poly, dtype=float)
                length = np.linalg.norm(np.roll(closed, -1, axis=0) - closed, axis=1).sum()
                lengths.setdefault(f"{render:12s} {name:8s}", []).append(length / perimeter)
    print(f"{count} ellipses, semi-axes 6.3-12.6 px; signed distance to the analytic edge")
    print(f"{'render':12s} {'outline':8s} {'mean':>7s} {'rms':>6s} {'max|.|':>7s} {'length':>7s}")
    for key, chunks in errors.items():
        d = np.concatenate(chunks)
        ratio = float(np.mean(lengths[key]))
        print(
            f"{key} {d.mean():+7.3f} {np.sqrt((d**2).mean()):6.3f} {np.abs(d).max():7.3f}"
            f" {ratio:7.3f}"
        )
    print("length: outline length / analytic perimeter")


if __name__ == "__main__":
    main()
