"""Contacts tracked across frames: ids, touch-down, lift-off, merges and splits."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from graspenv.bench.contact_scenes import Finger, render_fingers, world_ellipse_distance
from graspenv.config import ContactConfig
from graspenv.contacts import ContactFrame, ContactTracker, signed_area
from graspenv.surface.geometry import Surface

from .strategies import fingertips

TIP = (0.008, 0.006)  # fingertip semi-axes, metres


def _finger(x: float, y: float, axes: tuple[float, float] = TIP, angle: float = 0.0) -> Finger:
    return (np.array([x, y]), axes, angle)


def _frame(tracker: ContactTracker, fingers: list[Finger]) -> ContactFrame:
    return tracker.update(render_fingers(tracker.surface, fingers))


def _nearest(frame: ContactFrame, xy: tuple[float, float]) -> int:
    distances = [float(np.hypot(*(c.centroid - np.array(xy)))) for c in frame]
    return frame.contacts[int(np.argmin(distances))].id


# -- one frame -------------------------------------------------------------------------


def test_touch_down_gives_new_contacts_in_raster_order(tracker: ContactTracker) -> None:
    # Raster order: the upper finger (larger world y: smaller image row) comes first.
    frame = _frame(tracker, [_finger(-0.1, -0.1), _finger(0.1, 0.1)])
    assert frame.index == 0
    assert frame.ids == (0, 1)
    assert frame.removed == ()
    assert [c.status for c in frame] == ["new", "new"]
    assert [c.sources for c in frame] == [(), ()]
    assert frame[0].centroid[1] > 0.0 > frame[1].centroid[1]
    assert len(frame.new) == 2 and frame.continuing == ()
    assert 1 in frame and 7 not in frame and frame.get(7) is None
    with pytest.raises(KeyError):
        frame[7]


def test_empty_mask_gives_an_empty_frame(tracker: ContactTracker, surface: Surface) -> None:
    frame = tracker.update(np.zeros(surface.shape, dtype=bool))
    assert len(frame) == 0 and frame.ids == () and frame.removed == ()


@settings(max_examples=25, deadline=None)
@given(finger=fingertips)
def test_contact_geometry_in_the_world_frame(finger: Finger) -> None:
    surface = Surface()
    (contact,) = ContactTracker(surface, ContactConfig()).update(render_fingers(surface, [finger]))
    pixel = float(np.max(surface.pixel_size))
    # Within a pixel of the analytic ellipse, in metres, counter-clockwise from above.
    assert np.max(np.abs(world_ellipse_distance(contact.outline, finger))) < 0.75 * pixel
    assert np.max(np.abs(world_ellipse_distance(contact.contour, finger))) < 0.75 * pixel
    assert signed_area(contact.outline) > 0.0
    assert signed_area(contact.contour) > 0.0
    assert np.hypot(*(contact.centroid - finger[0])) < 0.35 * pixel
    a, b = finger[1]
    assert contact.area == pytest.approx(np.pi * a * b, rel=0.1)
    steps = np.linalg.norm(np.roll(contact.contour, -1, axis=0) - contact.contour, axis=1)
    assert abs(float(np.mean(steps)) - 0.004) < 0.1 * 0.004
    for array in (contact.contour, contact.outline, contact.centroid):
        assert not array.flags.writeable


def test_the_tracker_smooths_outlines_as_its_config_asks(surface: Surface) -> None:
    """``contacts.outline_smoothing`` reaches the tracker's compiled frame: its
    outlines lie nearer the fingertips' true edges (the staircase damped), not
    shrunk."""
    rng = np.random.default_rng(3)
    errors: dict[int, list[np.ndarray]] = {0: [], 6: []}
    for _ in range(20):
        centre = rng.uniform(-0.1, 0.1, size=2)
        finger = (centre, tuple(rng.uniform(0.006, 0.012, size=2)), float(rng.uniform(0, np.pi)))
        mask = render_fingers(surface, [finger])
        for passes, found in errors.items():
            tracker = ContactTracker(surface, ContactConfig(outline_smoothing=passes))
            (contact,) = tracker.update(mask)
            found.append(world_ellipse_distance(contact.outline, finger))
    plain, smoothed = (np.concatenate(errors[p]) for p in (0, 6))
    pixel = float(np.max(surface.pixel_size))
    assert abs(float(smoothed.mean() - plain.mean())) < 0.03 * pixel
    assert np.sqrt(np.mean(smoothed**2)) < 0.9 * np.sqrt(np.mean(plain**2))


def test_single_pixel_and_thin_line_still_have_a_contour(surface: Surface) -> None:
    tracker = ContactTracker(surface, ContactConfig(min_area=0.0))  # keep single pixels
    mask = np.zeros(surface.shape, dtype=np.uint8)
    mask[100, 100] = 1
    mask[300, 200:206] = 255
    frame = tracker.update(mask)
    assert len(frame) == 2
    pixel = surface.pixel_size
    for contact, (col, row) in zip(frame, [(100, 100), (202.5, 300)], strict=True):
        assert len(contact.contour) >= 3
        assert len({tuple(p) for p in contact.contour.tolist()}) == len(contact.contour)
        assert signed_area(contact.contour) > 0.0
        centre = surface.pixel_to_world(np.array([col, row]))
        np.testing.assert_allclose(contact.centroid, centre, atol=1e-9)
    dot, line = frame.contacts
    # Around the pixel's footprint, not on its centre.
    gap = np.abs(dot.contour - dot.centroid)
    assert np.all(gap <= 0.5 * pixel + 1e-12)
    assert np.all(np.max(gap / (0.5 * pixel), axis=1) > 0.99)
    assert dot.area == pytest.approx(float(np.prod(pixel)))
    assert line.area == pytest.approx(6 * float(np.prod(pixel)))


def test_min_area_drops_noise(surface: Surface) -> None:
    tracker = ContactTracker(surface, ContactConfig(min_area=5.0))
    mask = render_fingers(surface, [_finger(0.0, 0.0)])
    mask[10, 10] = True
    frame = tracker.update(mask)
    assert len(frame) == 1
    assert frame.contacts[0].area > 5.0 * float(np.prod(surface.pixel_size))


@pytest.mark.parametrize(("resolution", "kept"), [((640, 480), 1), ((320, 240), 3)])
def test_auto_min_area_keeps_its_size_in_millimetres(
    resolution: tuple[int, int], kept: int
) -> None:
    """ "auto" drops specks under 3.65 mm²: four pixels at 640 × 480, one at 320 × 240."""
    surface = Surface(resolution=resolution)
    tracker = ContactTracker(surface, ContactConfig())  # min_area = "auto"
    mask = np.zeros(surface.shape, np.uint8)
    mask[10, 10] = 255  # 1 pixel
    mask[30, 30:32] = 255  # 2 pixels
    mask[50:52, 50:52] = 255  # 4 pixels
    assert len(tracker.update(mask)) == kept


@pytest.mark.parametrize(
    ("mask", "fragment"),
    [
        (np.zeros((480, 641), np.uint8), "got shape (480, 641)"),
        (np.zeros((640, 480), bool), "got shape (640, 480)"),
        (np.zeros((480, 640), np.float32), "got dtype float32"),
        (np.zeros((480, 640, 1), np.uint8), "got 3-D array"),
        ([[0]], "got list"),
    ],
)
def test_bad_masks_raise_value_error(tracker: ContactTracker, mask: object, fragment: str) -> None:
    with pytest.raises(ValueError) as err:
        tracker.update(mask)
    assert "(H, W) = (480, 640)" in str(err.value)
    assert fragment in str(err.value)
    assert "bool or uint8" in str(err.value)


# -- frame to frame -------------------------------------------------------------------


@st.composite
def _finger_runs(draw: st.DrawFn) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Fingertip start points and per-frame step directions."""
    count = draw(st.integers(1, 4))
    frames = draw(st.integers(2, 6))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    slots = rng.permutation(8)[:count]
    starts = [np.array([-0.21 + 0.14 * (s % 4), -0.09 + 0.18 * (s // 4)]) for s in slots]
    steps = [rng.uniform(-1.0, 1.0, size=(frames - 1, 2)) for _ in range(count)]
    return starts, steps


# Each finger stays within this distance of its start: 14 cm between starts leaves
# 8 cm between any two fingers, so a finger's own last centroid is always its nearest.
_ROAM = 0.03


@settings(max_examples=30, deadline=None)
@given(run=_finger_runs(), speed=st.floats(0.0, 0.95), turn=st.floats(-3.0, 3.0))
def test_ids_stay_while_each_step_is_under_the_match_radius(
    run: tuple[list[np.ndarray], list[np.ndarray]], speed: float, turn: float
) -> None:
    surface, config = Surface(), ContactConfig()
    tracker = ContactTracker(surface, config)
    starts, steps = run
    positions = [start.copy() for start in starts]
    angles = [0.3 * i for i in range(len(starts))]
    first = _frame(tracker, [_finger(*p, angle=a) for p, a in zip(positions, angles, strict=True)])
    ids = {_nearest(first, tuple(p)): i for i, p in enumerate(positions)}
    assert sorted(ids) == list(range(len(starts)))
    for t in range(len(steps[0])):
        for i, step in enumerate(steps):
            # Every centroid travels at most speed × match radius per frame.
            direction = step[t] / max(float(np.linalg.norm(step[t])), 1e-12)
            moved = positions[i] + speed * config.match_radius * direction
            positions[i] = np.clip(moved, starts[i] - _ROAM, starts[i] + _ROAM)
            angles[i] += turn / surface.fps
        fingers = [_finger(*p, angle=a) for p, a in zip(positions, angles, strict=True)]
        frame = _frame(tracker, fingers)
        assert frame.index == t + 1
        assert frame.removed == ()
        assert sorted(frame.ids) == sorted(ids)
        for contact in frame:
            assert contact.status == "continuing"
            assert contact.sources == (contact.id,)
            finger = positions[ids[contact.id]]
            assert np.hypot(*(contact.centroid - finger)) < 0.001


def test_lift_off_removes_and_touch_down_takes_a_fresh_id(tracker: ContactTracker) -> None:
    a, b = _finger(-0.1, 0.0), _finger(0.1, 0.0)
    assert _frame(tracker, [a, b]).ids == (0, 1)
    frame = _frame(tracker, [b])
    assert frame.ids == (1,) and frame.removed == (0,)
    assert frame[1].status == "continuing"
    frame = _frame(tracker, [a, b])  # the same place, but a new touch
    assert frame.ids == (1, 2) and frame.removed == ()
    assert frame[2].status == "new" and frame[2].sources == ()
    frame = _frame(tracker, [])
    assert frame.ids == () and frame.removed == (1, 2)


def test_a_jump_beyond_the_match_radius_is_a_new_contact(tracker: ContactTracker) -> None:
    _frame(tracker, [_finger(0.0, 0.0)])
    frame = _frame(tracker, [_finger(0.0, 0.035)])  # 35 mm > 30 mm, no overlap
    assert frame.ids == (1,) and frame.removed == (0,)
    assert frame[1].status == "new" and frame[1].sources == ()


@settings(max_examples=20, deadline=None)
@given(
    angle=st.floats(0.0, 2.0 * np.pi),
    gap=st.floats(0.020, 0.026),
    closing=st.floats(0.010, 0.014),
    lean=st.floats(-0.3, 0.3),
)
def test_merge_keeps_the_nearest_id_and_lists_the_other(
    angle: float, gap: float, closing: float, lean: float
) -> None:
    surface = Surface()
    tracker = ContactTracker(surface, ContactConfig())
    # Tips 16 mm long along the axis: apart before, overlapping by at least 2 mm after.
    assume(gap - closing * (1.0 + 0.5 * lean) < 2 * TIP[0] - 0.002)
    axis = np.array([np.cos(angle), np.sin(angle)])
    left, right = -0.5 * gap * axis, 0.5 * gap * axis
    before = _frame(tracker, [(left, TIP, angle), (right, TIP, angle)])
    assert len(before) == 2
    # Both fingers move toward each other until they overlap: one blob, whose
    # centroid is nearer the finger that moved less.
    shift = 0.5 * closing * axis
    after = _frame(tracker, [(left + (1 + lean) * shift, TIP, angle), (right - shift, TIP, angle)])
    assert len(after) == 1
    (merged,) = after.contacts
    distances = {c.id: float(np.hypot(*(c.centroid - merged.centroid))) for c in before}
    assume(abs(distances[0] - distances[1]) > 1e-6)  # a near-tie could go either way
    keeper = min(distances, key=lambda i: (distances[i], i))
    (other,) = set(distances) - {keeper}
    assert merged.id == keeper
    assert merged.status == "continuing"
    assert merged.sources == (keeper, other)
    assert after.removed == (other,)


def test_merge_of_far_contacts_into_one_big_blob(tracker: ContactTracker) -> None:
    # Two contacts 8 cm apart; next frame a palm covers both: its centroid is more
    # than the match radius from either, yet it continues the nearer one.
    _frame(tracker, [_finger(-0.04, 0.0), _finger(0.045, 0.0)])
    frame = _frame(tracker, [_finger(0.0, 0.0, axes=(0.07, 0.02))])
    (palm,) = frame.contacts
    assert palm.id == 0  # (-0.04, 0) is the nearer to the palm's centre
    assert palm.status == "continuing"
    assert palm.sources == (0, 1)
    assert frame.removed == (1,)


@settings(max_examples=20, deadline=None)
@given(angle=st.floats(0.0, 2.0 * np.pi), gap=st.floats(0.020, 0.026))
def test_split_keeps_the_id_on_the_nearest_piece(angle: float, gap: float) -> None:
    surface = Surface()
    tracker = ContactTracker(surface, ContactConfig())
    axis = np.array([np.cos(angle), np.sin(angle)])
    # One blob of two overlapping tips, the first reaching further from the centroid.
    near, far = -0.3 * gap * axis, 0.6 * gap * axis
    joined = [(near + 0.25 * gap * axis, TIP, angle), (far - 0.25 * gap * axis, TIP, angle)]
    (parent,) = _frame(tracker, joined).contacts
    frame = _frame(tracker, [(near, TIP, angle), (far, TIP, angle)])
    assert len(frame) == 2 and frame.removed == ()
    pieces = sorted(frame, key=lambda c: float(np.hypot(*(c.centroid - parent.centroid))))
    assert pieces[0].id == parent.id
    assert pieces[0].status == "continuing" and pieces[0].sources == (parent.id,)
    assert pieces[1].id == parent.id + 1
    assert pieces[1].status == "new" and pieces[1].sources == (parent.id,)


def test_split_of_a_long_blob_whose_pieces_both_moved_far(tracker: ContactTracker) -> None:
    # A 12 cm long contact parts into its two ends, both beyond the match radius of
    # its centroid: the end nearer the old centroid keeps the id.
    (parent,) = _frame(tracker, [_finger(0.0, 0.0, axes=(0.06, 0.01))]).contacts
    frame = _frame(tracker, [_finger(-0.036, 0.0), _finger(0.045, 0.0)])
    assert frame.removed == ()
    kept, piece = frame[parent.id], frame[parent.id + 1]
    assert kept.centroid[0] < 0.0 < piece.centroid[0]
    assert kept.status == "continuing" and kept.sources == (parent.id,)
    assert piece.status == "new" and piece.sources == (parent.id,)


def test_piece_of_a_contact_that_also_moved_on(tracker: ContactTracker) -> None:
    # The parent's id goes to the piece within the match radius; a second piece whose
    # centroid lies in the parent's old outline is new, named after the parent.
    (parent,) = _frame(tracker, [_finger(0.0, 0.0, axes=(0.03, 0.01))]).contacts
    frame = _frame(tracker, [_finger(-0.012, 0.0), _finger(0.022, 0.0, axes=(0.005, 0.005))])
    assert frame[parent.id].centroid[0] < 0.0
    (piece,) = frame.new
    assert piece.sources == (parent.id,)


def test_reset_restarts_ids_and_frame_index(tracker: ContactTracker) -> None:
    _frame(tracker, [_finger(0.0, 0.0)])
    _frame(tracker, [_finger(0.1, 0.1)])
    tracker.reset()
    frame = _frame(tracker, [_finger(0.0, 0.0)])
    assert frame.index == 0 and frame.ids == (0,) and frame.removed == ()


def test_same_masks_give_identical_frames(surface: Surface) -> None:
    rng = np.random.default_rng(5)
    masks = []
    for t in range(4):
        fingers = [_finger(-0.1 + 0.005 * t, 0.02 * i, angle=0.1 * t) for i in range(3)]
        fingers.append(_finger(0.2, -0.1 + rng.uniform(0, 0.01)))
        masks.append(render_fingers(surface, fingers))
    runs = []
    for _ in range(2):
        tracker = ContactTracker(surface)
        runs.append([tracker.update(mask) for mask in masks])
    for a, b in zip(*runs, strict=True):
        assert a.ids == b.ids and a.removed == b.removed
        for ca, cb in zip(a, b, strict=True):
            assert np.array_equal(ca.contour, cb.contour)
            assert np.array_equal(ca.outline, cb.outline)


def test_continuing_contour_starts_where_the_last_one_did(tracker: ContactTracker) -> None:
    first = _frame(tracker, [_finger(0.0, 0.0, angle=0.4)])
    second = _frame(tracker, [_finger(0.004, 0.002, angle=0.4)])
    start = first.contacts[0].contour[0] + np.array([0.004, 0.002])
    assert np.hypot(*(second.contacts[0].contour[0] - start)) < 0.001


def _notched(surface: Surface, radius: float = 2.5) -> tuple[np.ndarray, np.ndarray]:
    """A fingertip's mask and the same with a dropout of ``radius`` pixels cut into
    its edge."""
    mask = render_fingers(surface, [_finger(0.0, 0.0)])
    notched = mask.copy()
    rows, cols = np.nonzero(mask)
    edge_row = round(float(rows.mean()))  # the right edge's middle
    edge_col = cols[rows == edge_row].max() + 1
    yy, xx = np.mgrid[: mask.shape[0], : mask.shape[1]]
    notched[(yy - edge_row) ** 2 + (xx - edge_col) ** 2 <= radius**2] = 0
    return mask, notched


def test_clean_ups_read_any_non_zero_pixel_as_touched(surface: Surface) -> None:
    _, notched = _notched(surface)
    config = ContactConfig(close_px=5, fill_px=2)
    areas = []
    for value in (1, 7, 255):
        tracker = ContactTracker(surface, config)
        image = notched.astype(np.uint8) * np.uint8(value)
        tracker.update(image)
        areas.append(tracker.update(image).contacts[0].area)
    assert areas[0] == areas[1] == areas[2]


def test_closing_mends_a_crack_but_not_a_bite(surface: Surface) -> None:
    # A crack narrower than the kernel is filled; a bite the kernel fits inside (a
    # dropout cut into the edge, as wide as it is deep) is not.
    mask = render_fingers(surface, [_finger(0.0, 0.0)])
    rows, cols = np.nonzero(mask)
    row = round(float(rows.mean()))
    edge = cols[rows == row].max()
    notched = mask.copy()
    notched[row, edge - 4 : edge + 1] = 0  # 1 pixel wide, 5 deep
    _, bitten = _notched(surface)
    closing = ContactTracker(surface, ContactConfig(close_px=5))
    assert closing.update(bitten).contacts[0].area == pytest.approx(
        ContactTracker(surface).update(bitten).contacts[0].area
    )
    whole = ContactTracker(surface).update(mask).contacts[0].area
    cut = ContactTracker(surface).update(notched).contacts[0].area
    closed = ContactTracker(surface, ContactConfig(close_px=5)).update(notched).contacts[0].area
    pixel = float(np.prod(surface.pixel_size))
    assert whole - cut > 2 * pixel  # the crack took pixels off the contact
    assert abs(closed - whole) < 0.5 * (whole - cut)


def test_fill_mends_a_flickering_dropout_but_not_a_lifted_finger(surface: Surface) -> None:
    mask, notched = _notched(surface)
    tracker = ContactTracker(surface, ContactConfig(fill_px=2))
    whole = tracker.update(mask).contacts[0].area
    assert tracker.update(notched).contacts[0].area == pytest.approx(whole)
    # The finger jumps 5 cm: nothing of where it was is kept (it is farther than
    # fill_px from the new contact).
    moved = render_fingers(surface, [_finger(0.05, 0.0)])
    frame = tracker.update(moved)
    assert len(frame) == 1
    assert frame.contacts[0].area == pytest.approx(
        ContactTracker(surface).update(moved).contacts[0].area
    )
    # The finger lifts: nothing of it is kept.
    assert len(tracker.update(np.zeros_like(mask))) == 0
    tracker.reset()  # forgets the last mask: a notched first frame stays notched
    cut = ContactTracker(surface).update(notched).contacts[0].area
    assert tracker.update(notched).contacts[0].area == pytest.approx(cut)
    # The finger lifts with a flipped pixel beside its edge: a speck does not keep
    # a piece of it either.
    rows, cols = np.nonzero(mask)
    speck = np.zeros_like(mask)
    speck[round(float(rows.mean())), cols.max() + 1] = 1
    tracker.update(mask)
    assert len(tracker.update(speck)) == 0


def test_the_vote_steadies_a_jittering_edge_and_mends_a_flickering_hole(
    surface: Surface,
) -> None:
    # A still fingertip seen through a pixel of edge jitter that changes every frame:
    # voted over three masks its centroid and area wobble less than as they come.
    from graspenv.surface.noise import SensorNoise

    mask = render_fingers(surface, [_finger(0.0, 0.0)])
    jitter = SensorNoise(jitter=1.0)
    rng = np.random.default_rng(0)
    masks = [jitter.apply(mask, rng) for _ in range(100)]
    spread = {}
    for votes in (1, 3):
        tracker = ContactTracker(surface, ContactConfig(vote_frames=votes))
        seen = [tracker.update(m).contacts[0] for m in masks][votes:]
        centroids = np.array([c.centroid for c in seen])
        spread[votes] = (
            float(np.linalg.norm(centroids.std(axis=0))),
            float(np.std([c.area for c in seen])),
        )
    assert spread[3][0] < 0.75 * spread[1][0]
    assert spread[3][1] < 0.75 * spread[1][1]
    # A dropout in one frame is outvoted by the two before it.
    whole, notched = _notched(surface)
    tracker = ContactTracker(surface, ContactConfig(vote_frames=3))
    area = [tracker.update(m).contacts[0].area for m in (whole, whole, notched)]
    assert area[2] == pytest.approx(area[0])
    assert ContactTracker(surface).update(notched).contacts[0].area < area[0]


def test_the_vote_keeps_a_new_touch_and_a_fast_finger_but_lags_a_lift(
    surface: Surface,
) -> None:
    tracker = ContactTracker(surface, ContactConfig(vote_frames=3))
    alone = ContactTracker(surface)
    one, two = _finger(-0.1, 0.0), _finger(0.1, 0.0)
    for fingers in ([one], [one], [one, two]):  # the second touches down
        frame = _frame(tracker, fingers)
    plain = _frame(alone, [one, two])
    assert len(frame) == 2
    assert [c.area for c in frame] == pytest.approx([c.area for c in plain])
    # A finger 5 cm from where it was (faster than its own width a frame) is seen
    # where it is, not erased.
    frame = _frame(tracker, [one, _finger(0.15, 0.0)])
    assert len(frame) == 2
    assert min(float(np.hypot(*(c.centroid - (0.15, 0.0)))) for c in frame) < 1e-3
    # A lift is outvoted for a frame: two of the last three masks still hold it.
    assert len(_frame(tracker, [one, _finger(0.15, 0.0)])) == 2
    assert len(_frame(tracker, [one])) == 2
    assert len(_frame(tracker, [one])) == 1
    tracker.reset()  # forgets the masks: the next frame is taken as it is
    assert len(_frame(tracker, [one, two])) == 2


@pytest.mark.parametrize("votes", [3, 5])
@pytest.mark.parametrize("widths", [0.1, 0.25, 0.4, 0.55, 0.7, 0.85, 1.0, 1.2])
def test_a_voted_finger_stays_one_contact_at_any_speed(
    surface: Surface, votes: int, widths: float
) -> None:
    # A fingertip sliding past a still one, by a share of its 16 mm width a frame:
    # the vote lags a slow finger a frame and takes a fast one as it is, and never
    # cuts it into slivers, erases it or joins where it was to it.
    tracker = ContactTracker(surface, ContactConfig(vote_frames=votes))
    plain = ContactTracker(surface)
    ids: set[int] = set()
    for k in range(12):
        fingers = [_finger(-0.1 + k * widths * 2 * TIP[0], 0.0), _finger(0.0, 0.03)]
        frame, seen = _frame(tracker, fingers), _frame(plain, fingers)
        assert len(frame) == 2, k
        ids |= set(frame.contact_ids.tolist())
        share = [c.area / s.area for c, s in zip(frame, seen, strict=True)]
        assert min(share) >= 0.5 and max(share) < 1.05, (k, share)
    assert len(ids) == 2


def test_a_pair_lifting_together_stays_a_frame_together_under_the_vote(
    surface: Surface,
) -> None:
    # Both fingertips lift at once, a flipped pixel beside one of them: the vote
    # keeps both for the frame it lags a lift, not one alone (which would push what
    # they held), and the speck is voted away.
    one, two = _finger(-0.05, 0.0), _finger(0.05, 0.0)
    mask = render_fingers(surface, [one, two])
    rows, cols = np.nonzero(render_fingers(surface, [one]))
    speck = np.zeros_like(mask)
    speck[round(float(rows.mean())), cols.max() + 2] = 1
    tracker = ContactTracker(surface, ContactConfig(vote_frames=3))
    for _ in range(3):
        tracker.update(mask)
    lagged = tracker.update(speck)
    assert len(lagged) == 2
    assert len(tracker.update(speck)) == 0  # the speck filter drops the speck
