"""A fingertip's load along an object's side, shared among its particles by depth
(``proxy.share_side_load``): one rigid contact, whose particles reach their friction
limit together."""

from __future__ import annotations

import numpy as np
import pytest

from graspenv.proxies.side_hold import WRAPPED_NORMAL, _shared_rows, shared_side_load

from . import reference

MU = 1.0


def _tangent(outward: np.ndarray) -> np.ndarray:
    return np.column_stack([-outward[:, 1], outward[:, 0]])


def _reach(outward: np.ndarray, depth: list[float], along: list[float]) -> np.ndarray:
    """Targets ``depth`` inside each side and ``along`` it from the particles."""
    return -np.array(depth)[:, None] * outward + np.array(along)[:, None] * _tangent(outward)


def _after(reach: np.ndarray, outward: np.ndarray, group: list[int] | None = None) -> np.ndarray:
    """Each target's offset along its side after sharing."""
    groups = np.zeros(len(reach), np.int64) if group is None else np.array(group)
    shifted = reach + shared_side_load(reach, outward, groups, np.full(len(reach), MU))
    return np.einsum("ij,ij->i", shifted, _tangent(outward))


def test_a_face_shares_its_load_by_depth_and_keeps_its_sum() -> None:
    outward = np.tile([1.0, 0.0], (3, 1))
    depth, along = [0.001, 0.002, 0.003], [0.0004, -0.0002, 0.0003]
    reach = _reach(outward, depth, along)
    shift = shared_side_load(reach, outward, np.zeros(3, np.int64), np.full(3, MU))
    # Along the side only: how hard each presses is left alone.
    np.testing.assert_allclose(np.einsum("ij,ij->i", shift, outward), 0.0, atol=1e-15)
    after = _after(reach, outward)
    np.testing.assert_allclose(after.sum(), sum(along), rtol=1e-12)
    np.testing.assert_allclose(after / np.array(depth), sum(along) / sum(depth), rtol=1e-12)


def test_a_squeeze_round_a_curve_puts_no_load_along_it() -> None:
    """Particles either side of the middle of a fingertip's arc on a cylinder, pulled
    along the side in opposite directions by the squeeze alone, stand at none."""
    angles = np.radians([-20.0, -10.0, 0.0, 10.0, 20.0])
    outward = np.column_stack([-np.cos(angles), np.sin(angles)])
    depth = [0.001, 0.0025, 0.003, 0.0025, 0.001]
    reach = _reach(outward, depth, [-0.0006, -0.0003, 0.0, 0.0003, 0.0006])
    np.testing.assert_allclose(_after(reach, outward), 0.0, atol=1e-15)


def test_a_sliding_contact_and_one_wrapped_round_an_object_are_left_alone() -> None:
    outward = np.tile([0.0, 1.0], (2, 1))
    depth = [0.001, 0.002]
    # Beyond the friction limit (μ·Σd = 3 mm): it slides, each particle on its own.
    sliding = _reach(outward, depth, [0.001, 0.0025])
    np.testing.assert_allclose(_after(sliding, outward), [0.001, 0.0025])
    # Just within it, shared.
    stuck = _reach(outward, depth, [0.001, 0.0019])
    np.testing.assert_allclose(_after(stuck, outward), [0.0029 / 3, 0.0058 / 3], rtol=1e-9)
    # Four sides of a small object facing every way: no one side to share along.
    around = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    wrapped = _reach(around, [0.001, 0.002, 0.001, 0.002], [0.0004, 0.0, -0.0001, 0.0002])
    np.testing.assert_allclose(_after(wrapped, around), [0.0004, 0.0, -0.0001, 0.0002])


def test_a_particle_that_does_not_press_keeps_its_target_and_takes_no_share() -> None:
    outward = np.tile([1.0, 0.0], (3, 1))
    reach = _reach(outward, [0.002, -0.0005, 0.002], [0.0003, 0.0009, -0.0001])
    np.testing.assert_allclose(_after(reach, outward), [0.0001, 0.0009, 0.0001], rtol=1e-9)


def test_groups_share_apart() -> None:
    outward = np.tile([1.0, 0.0], (4, 1))
    reach = _reach(outward, [0.001, 0.003, 0.002, 0.002], [0.0004, 0.0, 0.0002, -0.0002])
    np.testing.assert_allclose(
        _after(reach, outward, [0, 0, 7, 7]), [0.0001, 0.0003, 0.0, 0.0], atol=1e-15
    )


def test_a_particle_further_from_its_place_than_its_friction_holds_is_not_shared() -> None:
    """Its offset less the group's mean is beyond μ·d: it would slide back towards its
    point on its own, so it keeps its target and the others share theirs."""
    outward = np.tile([1.0, 0.0], (3, 1))
    reach = _reach(outward, [0.002, 0.002, 0.0005], [0.0002, 0.0, 0.0016])
    np.testing.assert_allclose(_after(reach, outward), [0.0001, 0.0001, 0.0016], rtol=1e-9)


def _same_bits(got: np.ndarray, expected: np.ndarray) -> None:
    """Equal to the bit, signed zeros too (``assert_array_equal`` takes -0.0 for 0.0)."""
    assert got.shape == expected.shape and got.dtype == expected.dtype
    np.testing.assert_array_equal(got.view(np.uint64), expected.view(np.uint64))


def _kernel_and_oracle(
    outward: list[list[float]], depth: list[float], along: list[float], friction: float = MU
) -> tuple[np.ndarray, np.ndarray]:
    """One group's shifts from the compiled form and from the numpy form."""
    normals = np.array(outward, dtype=float)
    reach = _reach(normals, depth, along)
    group, mu = np.zeros(len(depth), np.int64), np.full(len(depth), friction)
    return (
        shared_side_load(reach, normals, group, mu),
        reference.shared_side_load(reach, normals, group, mu, WRAPPED_NORMAL),
    )


def test_ties_at_each_rule_go_as_the_numpy_form_says() -> None:
    """Exactly representable cases on each rule's boundary, where random inputs never
    land: a particle whose offset from the group's mean equals its friction limit is
    stuck; a load equal to the group's limit slides; a particle at depth 0 does not
    press; normals that add up to exactly the wrapped share are one side."""
    face = [[1.0, 0.0]] * 2
    cases = {
        "offset at its limit, stuck": (face, [0.5, 0.5], [0.5, -0.5]),
        "load at the limit, slides": (face, [0.5, 0.25], [0.25, 0.5]),
        "depth 0, not pressing": (face, [0.5, 0.0], [0.125, 0.125]),
        "normals at the wrapped share": (
            [[1.0, 0.0]] * 3 + [[-1.0, 0.0], [0.0, 1.0], [0.0, 1.0], [0.0, -1.0], [0.0, -1.0]],
            [0.5] * 8,
            [0.25] + [0.0] * 7,
        ),
    }
    moved = {}
    for name, (outward, depth, along) in cases.items():
        got, expected = _kernel_and_oracle(outward, depth, along)
        _same_bits(got, expected)
        moved[name] = bool(np.any(got != 0.0))
    # Each tie decides whether anything moves, so flipping a rule's < and <= shows.
    assert moved == {
        "offset at its limit, stuck": True,
        "load at the limit, slides": False,
        "depth 0, not pressing": False,
        "normals at the wrapped share": True,
    }


def test_groups_far_apart_are_groups_as_any() -> None:
    """Group numbers need not be small: far apart they share as numbered 0 and 1."""
    outward = np.tile([1.0, 0.0], (4, 1))
    reach = _reach(outward, [0.001, 0.002, 0.001, 0.003], [0.0004, -0.0002, 0.0003, 0.0])
    mu = np.full(4, MU)
    near = shared_side_load(reach, outward, np.array([0, 0, 1, 1]), mu)
    far = np.array([-(2**62), -(2**62), 2**62, 2**62])
    _same_bits(shared_side_load(reach, outward, far, mu), near)


def test_the_compiled_sharing_matches_its_numpy_form() -> None:
    """On random contacts (one to four groups a frame, some beyond their friction
    limit, some wrapped round an object, some particles not pressing), bit for bit."""
    rng = np.random.default_rng(0)
    shared = 0
    for _ in range(400):
        n = int(rng.integers(0, 40))
        angle = rng.uniform(-np.pi, np.pi, n) * rng.choice([0.1, 1.0])
        outward = np.column_stack([np.cos(angle), np.sin(angle)])
        depth = rng.uniform(-0.001, 0.004, n)
        reach = _reach(outward, list(depth), list(rng.normal(0.0, 0.002, n)))
        group = rng.integers(0, 4, n) * 3 + rng.integers(0, 2, n)
        friction = rng.choice([0.3, 1.0, 2.0], n)
        shift = shared_side_load(reach, outward, group, friction)
        _same_bits(
            shift, reference.shared_side_load(reach, outward, group, friction, WRAPPED_NORMAL)
        )
        shared += int(np.count_nonzero(shift[:, 0]))
    assert shared > 1000  # the cases share, not only leave alone


def test_the_frames_compiled_gather_matches_its_numpy_form() -> None:
    """The frame's step (``shared_targets``): rows of contacts on two objects, some
    not pressing or with no side normal, gathered, shared and put back, bit for bit."""
    rng = np.random.default_rng(1)
    moved = 0
    for _ in range(200):
        k = int(rng.integers(0, 50))
        targets = rng.normal(0.0, 0.05, (k, 2))
        track_of = np.sort(rng.integers(0, 5, k)).astype(np.intp)
        owner = rng.integers(-1, 2, k).astype(np.int64)
        rows = np.flatnonzero(owner >= 0)
        angle = rng.uniform(-np.pi, np.pi, rows.size)
        normal = np.column_stack([np.cos(angle), np.sin(angle)])
        normal[rng.random(rows.size) < 0.1] = 0.0
        at = np.column_stack(
            [targets[rows] + rng.normal(0.0, 0.002, (rows.size, 2)), np.full(rows.size, 0.004)]
        )
        pressed = rng.random(rows.size) < 0.9
        friction = np.array([1.0, 0.6])
        frame = (targets, rows, at, normal, pressed, track_of, owner, friction)
        shared = _shared_rows(*frame)
        _same_bits(shared, reference.shared_rows(frame, WRAPPED_NORMAL))
        moved += int(np.count_nonzero(np.any(shared != targets, axis=1)))
    assert moved > 100  # the cases share, not only leave alone


def test_arrays_that_do_not_agree_are_refused() -> None:
    outward = np.tile([1.0, 0.0], (3, 1))
    with pytest.raises(ValueError, match="reach and outward"):
        shared_side_load(outward[:2], outward, np.zeros(3, np.int64), np.ones(3))
    with pytest.raises(ValueError, match="group and friction"):
        shared_side_load(outward, outward, np.zeros(2, np.int64), np.ones(3))
