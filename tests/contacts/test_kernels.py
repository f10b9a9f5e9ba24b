"""The compiled per-frame kernels against their plain-numpy forms (``reference.py``)
on random inputs: outlines and areas bit for bit, resampling to rounding, anchors
exactly, and the tracker's candidate sweep against the rules applied to every pair."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from graspenv.config import ContactConfig
from graspenv.contacts import matching
from graspenv.contacts.extract import find_components_batch, outlines_from_chains
from graspenv.contacts.resample import orient_ccw_batch, resample_closed_batch
from graspenv.contacts.tracking import ContactTracker
from graspenv.surface.geometry import Surface

from . import reference


def _random_mask(rng: np.random.Generator, shape: tuple[int, int] = (120, 160)) -> np.ndarray:
    """Ellipses, lines, single pixels and salt: every kind of outline there is."""
    mask = np.zeros(shape, np.uint8)
    rows, columns = shape
    for _ in range(int(rng.integers(1, 8))):
        kind = int(rng.integers(0, 4))
        x, y = int(rng.uniform(0, columns)), int(rng.uniform(0, rows))
        if kind == 0:
            axes = (int(rng.integers(1, 15)), int(rng.integers(1, 15)))
            cv2.ellipse(mask, (x, y), axes, float(rng.uniform(0, 180)), 0, 360, 255, -1)
        elif kind == 1:
            end = (int(rng.uniform(0, columns)), int(rng.uniform(0, rows)))
            cv2.line(mask, (x, y), end, 255, int(rng.integers(1, 3)))
        elif kind == 2:
            mask[y, x] = 255
        else:
            mask[rng.random(shape) < 0.01] = 255
    return mask


def test_outlines_areas_and_centroids_match_the_numpy_form() -> None:
    rng = np.random.default_rng(0)
    for _ in range(150):
        mask = _random_mask(rng)
        components, outlines, bounds = find_components_batch(mask)
        chains = [c.chain for c in components]
        if not chains:
            continue
        expected, expected_bounds = reference.outlines_from_chains(chains)
        np.testing.assert_array_equal(bounds, expected_bounds)
        np.testing.assert_array_equal(outlines, expected)
        np.testing.assert_array_equal(outlines_from_chains(chains)[0], expected)
        for component in components:
            moments = cv2.moments(component.chain.reshape(-1, 1, 2))
            enclosed = abs(moments["m00"])
            count = len(component.chain)
            assert component.area == (enclosed + 0.5 * count + 1.0 if count > 1 else 1.0)
            if enclosed > 0:
                centroid = np.array([moments["m10"], moments["m01"]]) / moments["m00"]
                np.testing.assert_allclose(component.centroid, centroid, rtol=0, atol=1e-12)


def test_orientation_and_resampling_match_the_numpy_form() -> None:
    rng = np.random.default_rng(1)
    for _ in range(300):
        count = int(rng.integers(1, 6))
        polylines = [
            np.cumsum(rng.normal(size=(int(rng.integers(3, 60)), 2)), axis=0) * 0.01
            + rng.normal(size=2)
            for _ in range(count)
        ]
        points = np.concatenate(polylines)
        bounds = np.cumsum([0] + [len(p) for p in polylines]).astype(np.intp)
        starts = np.array([p.mean(axis=0) for p in polylines]) + rng.normal(size=(count, 2)) * 0.02
        starts[rng.random(count) < 0.3] = np.nan
        oriented = orient_ccw_batch(points, bounds)
        np.testing.assert_array_equal(oriented, reference.orient_ccw_batch(points, bounds))
        resampled, resampled_bounds = resample_closed_batch(oriented, bounds, 0.004, starts)
        expected, expected_bounds = reference.resample_closed_batch(oriented, bounds, 0.004, starts)
        np.testing.assert_array_equal(resampled_bounds, expected_bounds)
        # The kernel measures arc length along each polyline from its own start, the
        # numpy form along all of them: the same points to rounding.
        np.testing.assert_allclose(resampled, expected, rtol=0, atol=1e-13)


def test_anchors_match_the_numpy_form() -> None:
    rng = np.random.default_rng(2)
    for _ in range(2000):
        sizes = rng.integers(1, 30, int(rng.integers(1, 5)))
        has = rng.random(int(sizes.sum())) < rng.uniform(0.0, 1.0)
        bounds = np.cumsum([0, *sizes]).astype(np.intp)
        np.testing.assert_array_equal(
            matching._anchors(has, bounds), reference.anchors(has, bounds)
        )


@pytest.fixture
def surface() -> Surface:
    return Surface()


def _blob_frames(rng: np.random.Generator, surface: Surface, frames: int) -> list[np.ndarray]:
    """Discs that drift, touch, merge and split: every rule of the tracker fires."""
    count = 25
    centres = rng.uniform([60, 60], [580, 420], (count, 2))
    velocity = rng.normal(0.0, 6.0, (count, 2))
    radius = rng.uniform(3, 14, count)
    masks = []
    for _ in range(frames):
        mask = np.zeros(surface.shape, np.uint8)
        for (x, y), r in zip(centres, radius, strict=True):
            if rng.random() < 0.9:  # some flicker: lift-offs and touch-downs
                cv2.circle(mask, (int(x), int(y)), int(r), 255, -1)
        centres += velocity
        masks.append(mask)
    return masks


def _blobs(mask: np.ndarray, surface: Surface) -> list[reference.Blob]:
    """The mask's components in raster order, in world units, as the tracker sees them."""
    components, outlines, bounds = find_components_batch(mask)
    if not components:
        return []
    world = orient_ccw_batch(surface.pixel_to_world(outlines), bounds)
    return [
        reference.Blob(world[bounds[i] : bounds[i + 1]], surface.pixel_to_world(c.centroid))
        for i, c in enumerate(components)
    ]


def test_tracker_rules_match_the_rules_applied_to_every_pair(surface: Surface) -> None:
    """The sweep finds exactly the candidates all pairs would: each blob keeps the
    same previous id, with the same sources, as the rules run over every pair."""
    rng = np.random.default_rng(3)
    config = ContactConfig(min_area=0.0)
    checked = {"kept": 0, "merged": 0, "split": 0}
    for _ in range(4):
        tracker = ContactTracker(surface, config)
        previous = None
        for mask in _blob_frames(rng, surface, 30):
            frame = tracker.update(mask)
            blobs = _blobs(mask, surface)
            if previous is not None:
                keeps, sources = reference.match_rules(previous.contacts, blobs, 0.03)
                by_centroid = {tuple(c.centroid.tolist()): c for c in frame}
                for blob, kept, source in zip(blobs, keeps, sources, strict=True):
                    contact = by_centroid[tuple(blob.centroid.tolist())]
                    assert contact.is_new == (kept is None)
                    if kept is not None:
                        assert contact.id == kept
                    assert contact.sources == source
                    checked["kept"] += kept is not None
                    checked["merged"] += kept is not None and len(source) > 1
                    checked["split"] += kept is None and len(source) == 1
            previous = frame
    # The scenes exercise every rule.
    assert min(checked.values()) > 0, checked


def test_tracker_cost_grows_linearly_with_speckles(surface: Surface) -> None:
    """A thousand specks a frame are tracked (the all-pairs test took seconds); the
    rules still hold for them (each continues, splits or lands once)."""
    rng = np.random.default_rng(4)
    tracker = ContactTracker(surface, ContactConfig(min_area=0.0))
    for _ in range(3):
        mask = np.zeros(surface.shape, np.uint8)
        rows = rng.integers(0, surface.shape[0] - 3, 1000)
        columns = rng.integers(0, surface.shape[1] - 3, 1000)
        for r, c in zip(rows, columns, strict=True):
            mask[r : r + 3, c : c + 3] = 255
        frame = tracker.update(mask)
        assert len(frame) == len(find_components_batch(mask)[0]) > 900
        assert len(set(frame.ids)) == len(frame)


def test_direct_exhaustive_search_matches_the_blocked_product() -> None:
    """The compiled search of small pairs names the same successors as
    match_exhaustive's matrix product (random contours: no exact ties)."""
    rng = np.random.default_rng(5)
    for _ in range(500):
        pairs = int(rng.integers(1, 5))
        previous, current = [], []
        for _ in range(pairs):
            n = int(rng.integers(3, 60))
            m = max(3, n + int(rng.integers(-3, 4)))
            t = np.linspace(0.0, 2 * np.pi, n, endpoint=False) + rng.uniform(0, 1)
            u = np.linspace(0.0, 2 * np.pi, m, endpoint=False) + rng.uniform(-0.3, 0.3)
            radius = rng.uniform(0.005, 0.012)
            previous.append(radius * np.column_stack([np.cos(t), np.sin(t)]))
            current.append(
                radius * rng.uniform(0.9, 1.1) * np.column_stack([np.cos(u), np.sin(u)])
                + rng.normal(size=2) * 0.002
            )
        p_bounds = np.cumsum([0] + [len(p) for p in previous]).astype(np.intp)
        q_bounds = np.cumsum([0] + [len(q) for q in current]).astype(np.intp)
        window = int(rng.integers(0, 7))
        match = matching.correspond_batch(
            np.concatenate(previous), p_bounds, np.concatenate(current), q_bounds, window,
            "exhaustive",
        )  # fmt: skip
        for c, (p, q) in enumerate(zip(previous, current, strict=True)):
            expected = matching.match_exhaustive(p, q, window) + q_bounds[c]
            np.testing.assert_array_equal(match.successor[p_bounds[c] : p_bounds[c + 1]], expected)


def _noisy_stream(rng: np.random.Generator, frames: int) -> list[np.ndarray]:
    """Fingertips that touch down, move (some faster than their width a frame) and
    lift, under salt, dropouts and holes: what the vote and the fill act on."""
    rows, columns = 120, 160
    fingers = [
        (rng.uniform(10, 150), rng.uniform(10, 110), rng.uniform(-12, 12), rng.uniform(-12, 12))
        for _ in range(int(rng.integers(1, 5)))
    ]
    spans = [sorted(rng.integers(0, frames, 2).tolist()) for _ in fingers]
    stream = []
    for f in range(frames):
        mask = np.zeros((rows, columns), np.uint8)
        for (x, y, vx, vy), (down, up) in zip(fingers, spans, strict=True):
            if down <= f <= up:
                centre = (int(x + vx * (f - down)) % columns, int(y + vy * (f - down)) % rows)
                cv2.circle(mask, centre, int(rng.integers(4, 9)), 255, -1)
        mask[rng.random(mask.shape) < 0.01] = 255  # salt
        mask[rng.random(mask.shape) < 0.02] = 0  # dropouts and holes
        stream.append(mask)
    # A frame with nothing on the table and one touched all over.
    stream[int(rng.integers(0, frames))][:] = 0
    stream[int(rng.integers(0, frames))][:] = int(rng.integers(1, 256))
    return stream


@pytest.mark.parametrize(
    ("vote", "close", "fill", "min_area"),
    [
        (3, 0, 0, 4.0),
        (5, 0, 0, 4.0),
        (3, 5, 2, 4.0),
        (5, 5, 2, 9.0),
        (1, 5, 2, 4.0),
        (3, 0, 2, 1.0),
        (15, 3, 1, 4.0),
    ],
)
def test_the_mask_clean_ups_match_their_whole_image_form(
    vote: int, close: int, fill: int, min_area: float
) -> None:
    from graspenv.contacts.cleanup import MaskCleaner

    rng = np.random.default_rng(100 * vote + 10 * close + fill)
    config = ContactConfig(vote_frames=vote, close_px=close, fill_px=fill)
    for _ in range(6):
        stream = _noisy_stream(rng, 30)
        cleaner = MaskCleaner(config, min_area)
        expected = reference.clean_masks(stream, vote, close, fill, min_area)
        for mask, want in zip(stream, expected, strict=True):
            got = cleaner(mask)
            np.testing.assert_array_equal(got, want)
            got[:] = 1  # the caller's to change: the cleaner keeps copies
        cleaner.reset()  # and forgets them: the stream again, from the start, as bools
        for mask, want in zip(stream, expected, strict=True):
            np.testing.assert_array_equal(cleaner(mask != 0), want)
