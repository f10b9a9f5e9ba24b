"""Grasp-stability metrics: the planar Ferrari–Canny epsilon, force closure, slip,
tilt, grip force and penetration, on hand-built contacts (no physics)."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from graspenv.tasks import quality
from graspenv.tasks.metrics import (
    GraspMetrics,
    coulomb_slip_force,
    ferrari_canny,
    grasp_metrics,
    planar_slip,
    rigid_velocity_at,
    tilt_angle,
)

ORIGIN = np.zeros(2)
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])
AT_REST = np.zeros(3)


def ring(count: int, radius: float = 1.0, phase: float = 0.0) -> NDArray[np.float64]:
    """``count`` points evenly around a circle about the origin, shape (count, 2)."""
    angle = phase + 2.0 * math.pi * np.arange(count) / count
    return radius * np.column_stack([np.cos(angle), np.sin(angle)])


def turned(vectors: NDArray[np.float64], angle: float | NDArray[np.float64]) -> NDArray[np.float64]:
    """Each row turned counter-clockwise by its angle, radians."""
    c, s = np.cos(angle), np.sin(angle)
    return np.column_stack(
        [c * vectors[:, 0] - s * vectors[:, 1], s * vectors[:, 0] + c * vectors[:, 1]]
    )


# -- an independent reference: the hull's facets by brute force --------------------------


def reference_wrenches(
    points: NDArray[np.float64],
    normals: NDArray[np.float64],
    mu: float,
    centre: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Cone-edge wrenches (f_x, f_y, τ/ρ), ρ the farthest contact, written out plainly."""
    rho = max(float(np.linalg.norm(p - centre)) for p in points)
    rows = []
    for p, n in zip(points, normals, strict=True):
        n = n / np.linalg.norm(n)
        t = np.array([-n[1], n[0]])
        for sign in (-1.0, 1.0):
            f = n + sign * mu * t
            r = p - centre
            rows.append([f[0], f[1], (r[0] * f[1] - r[1] * f[0]) / rho])
    return np.array(rows)


def reference_epsilon(wrenches: NDArray[np.float64], tol: float = 1e-9) -> float:
    """Smallest distance from the origin to a supporting plane through three wrenches;
    0 when the origin is not strictly inside (or the set is flat)."""
    if np.linalg.matrix_rank(wrenches - wrenches.mean(axis=0), tol=tol) < 3:
        return 0.0
    best = math.inf
    for i, j, k in itertools.combinations(range(len(wrenches)), 3):
        normal = np.cross(wrenches[j] - wrenches[i], wrenches[k] - wrenches[i])
        length = float(np.linalg.norm(normal))
        if length < tol:
            continue
        normal /= length
        offset = float(normal @ wrenches[i])
        side = wrenches @ normal - offset
        if side.max() <= tol:
            best = min(best, offset)
        elif side.min() >= -tol:
            best = min(best, -offset)
    return best if best > tol else 0.0


def fibonacci_directions(count: int) -> NDArray[np.float64]:
    """Nearly uniform unit vectors on the sphere, shape (count, 3)."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    phi = math.pi * (1.0 + 5.0**0.5) * i
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


DIRECTIONS = fibonacci_directions(20_000)
# Every unit vector is within this angle of a sample (generous: the lattice's covering
# radius at 20 000 points is about 0.02).
DIRECTION_GAP = 0.05


@st.composite
def grasps(
    draw: st.DrawFn,
) -> tuple[NDArray[np.float64], NDArray[np.float64], float, NDArray[np.float64]]:
    """2–6 contacts around a centre, normals up to ~70° off the radial, any mu."""
    count = draw(st.integers(2, 6))
    unit = st.floats(0.0, 1.0, allow_nan=False)
    angle = np.array([draw(unit) for _ in range(count)]) * 2.0 * math.pi
    radius = 0.5 + np.array([draw(unit) for _ in range(count)])
    skew = (np.array([draw(unit) for _ in range(count)]) - 0.5) * 2.4
    if draw(st.booleans()):
        skew[:] = 0.0  # normals through the centre: the frictionless case is flat
    centre = np.array([draw(unit), draw(unit)]) - 0.5
    radial = np.column_stack([np.cos(angle), np.sin(angle)])
    points = centre + radius[:, None] * radial
    normals = turned(-radial, skew)
    mu = draw(st.sampled_from([0.0, 0.05, 0.3, 0.7, 1.5]))
    return points, normals, mu, centre


# -- Ferrari–Canny: closed forms ----------------------------------------------------------


@pytest.mark.parametrize("mu", [0.1, 0.5, 1.0, 2.0])
def test_two_antipodal_contacts_with_friction_are_planar_force_closure(mu: float) -> None:
    # A 6 cm box squeezed across its middle. In the plane the two tangential friction
    # forces make a couple, so the pair resists torque about z: the wrenches
    # (∓1, ±μ, ±μ)-style form a tetrahedron whose centroid is the origin. Scaling y and
    # z by 1/μ makes it regular, and each face lies at μ / sqrt(μ² + 2).
    a = 0.03
    centre = np.array([0.1, -0.2])
    points = centre + np.array([[a, 0.0], [-a, 0.0]])
    normals = np.array([[-1.0, 0.0], [1.0, 0.0]])
    epsilon = ferrari_canny(points, normals, mu, centre)
    assert epsilon == pytest.approx(mu / math.sqrt(mu * mu + 2.0), rel=1e-9)
    # An explicit ρ stretches the torque axis by a/ρ: 1/sqrt(1 + 1/μ² + ρ²/(μa)²).
    rho = 0.1
    expected = 1.0 / math.sqrt(1.0 + 1.0 / mu**2 + (rho / (mu * a)) ** 2)
    assert ferrari_canny(points, normals, mu, centre, torque_scale=rho) == pytest.approx(
        expected, rel=1e-9
    )


def test_two_antipodal_frictionless_contacts_are_not_force_closure() -> None:
    points = np.array([[0.03, 0.0], [-0.03, 0.0]])
    normals = np.array([[-1.0, 0.0], [1.0, 0.0]])
    assert ferrari_canny(points, normals, 0.0, ORIGIN) == 0.0


@pytest.mark.parametrize(("mu", "closed"), [(0.5, False), (0.75, False), (0.85, True), (1.5, True)])
def test_two_contacts_close_only_when_their_line_lies_in_both_cones(
    mu: float, closed: bool
) -> None:
    # Nguyen's two-finger condition: the line between the contacts is atan(0.8) = 38.7°
    # from both normals, so closure needs atan(μ) > 38.7°, i.e. μ > 0.8.
    points = np.array([[1.0, 0.8], [-1.0, -0.8]])
    normals = np.array([[-1.0, 0.0], [1.0, 0.0]])
    assert (ferrari_canny(points, normals, mu, ORIGIN) > 0.0) is closed


def test_four_contacts_at_right_angles_with_unit_friction_span_a_cube() -> None:
    # Contact k on the unit disc with normal −p_k and μ = 1 has cone edges −p_k ± t_k and
    # torques ±1 (ρ = 1): the eight wrenches are the corners of the cube [-1, 1]³, whose
    # faces are at distance 1.
    points = ring(4, radius=0.04)
    assert ferrari_canny(points, -points, 1.0, ORIGIN) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("count", [3, 4, 5])
@pytest.mark.parametrize("mu", [0.05, 0.4, 1.0])
def test_three_or_more_contacts_around_a_disc_with_friction_are_closure(
    count: int, mu: float
) -> None:
    points = ring(count, radius=0.05, phase=0.3)
    epsilon = ferrari_canny(points, -points, mu, ORIGIN)
    assert epsilon > 0.01
    assert epsilon == pytest.approx(
        reference_epsilon(reference_wrenches(points, -points, mu, ORIGIN)), abs=1e-9
    )


@pytest.mark.parametrize("count", [2, 3, 4, 7])
def test_frictionless_contacts_on_a_circle_cannot_resist_torque(count: int) -> None:
    # Every normal passes through the centre: no wrench has torque, the hull is flat.
    points = ring(count, radius=0.05, phase=0.1)
    assert ferrari_canny(points, -points, 0.0, ORIGIN) == 0.0


def test_frictionless_pinwheel_contacts_are_closure() -> None:
    # Normals skewed both ways off the radial give torques of both signs without
    # friction: six contacts alternately +0.4 and −0.4 rad off the centre.
    points = ring(6, radius=0.05)
    normals = turned(-points, np.array([0.4, -0.4] * 3))
    epsilon = ferrari_canny(points, normals, 0.0, ORIGIN)
    assert epsilon > 0.0
    assert epsilon == pytest.approx(
        reference_epsilon(reference_wrenches(points, normals, 0.0, ORIGIN)), abs=1e-9
    )


def test_an_object_free_to_leave_on_one_side_is_not_closure() -> None:
    # Frictionless pushes from ±x and from above (+y side, pushing −y, off-centre both
    # ways): every wrench has f_y <= 0, so the origin is on the hull's boundary and the
    # object can be pulled away in +y without resistance.
    points = np.array([[1.0, 0.0], [-1.0, 0.0], [0.5, 1.0], [-0.5, 1.0]])
    normals = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, -1.0]])
    assert ferrari_canny(points, normals, 0.0, ORIGIN) == 0.0
    # One more push from below closes it.
    closed = ferrari_canny(
        np.vstack([points, [0.0, -1.0]]), np.vstack([normals, [0.0, 1.0]]), 0.0, ORIGIN
    )
    assert closed > 0.0


def test_fewer_than_two_contacts_are_never_closure() -> None:
    assert ferrari_canny(np.zeros((0, 2)), np.zeros((0, 2)), 1.0, ORIGIN) == 0.0
    assert ferrari_canny([[0.03, 0.0]], [[-1.0, 0.0]], 1.0, ORIGIN) == 0.0


def test_epsilon_grows_with_friction() -> None:
    points = ring(3, radius=0.05, phase=0.2)
    values = [ferrari_canny(points, -points, mu, ORIGIN) for mu in (0.0, 0.1, 0.3, 0.6, 1.0)]
    assert values[0] == 0.0
    assert all(b > a for a, b in itertools.pairwise(values))


def test_epsilon_does_not_depend_on_contact_order_or_position_or_heading() -> None:
    rng = np.random.default_rng(7)
    points = ring(5, radius=0.04, phase=0.5) + rng.normal(0.0, 0.005, (5, 2))
    normals = turned(-points, rng.uniform(-0.5, 0.5, 5))
    base = ferrari_canny(points, normals, 0.4, ORIGIN)
    assert base > 0.0
    order = rng.permutation(5)
    assert ferrari_canny(points[order], normals[order], 0.4, ORIGIN) == pytest.approx(
        base, abs=1e-12
    )
    shift = np.array([0.21, -0.13])
    assert ferrari_canny(points + shift, normals, 0.4, shift) == pytest.approx(base, abs=1e-12)
    angle = 1.1
    assert ferrari_canny(
        turned(points, angle), turned(normals, angle), 0.4, ORIGIN
    ) == pytest.approx(base, abs=1e-12)


def test_more_cone_samples_leave_epsilon_unchanged() -> None:
    # In the plane the two edges span the cone and wrenches are linear in the force.
    points = ring(4, radius=0.05, phase=0.3)
    normals = turned(-points, np.array([0.2, -0.1, 0.3, 0.0]))
    two = ferrari_canny(points, normals, 0.3, ORIGIN)
    assert two > 0.0
    for edges in (3, 5, 8):
        wrenches = quality._primitive_wrenches(points, normals, 0.3, ORIGIN, None, edges)
        assert wrenches is not None
        assert quality._epsilon_of_wrenches(wrenches) == pytest.approx(two, abs=1e-12)


def test_many_contacts_match_the_brute_force_facets(monkeypatch: pytest.MonkeyPatch) -> None:
    # The incremental hull alone must be right: its exhaustive fallback is switched off.
    def no_fallback(*_: object) -> None:
        raise AssertionError("the incremental hull failed its check")

    monkeypatch.setattr(quality, "_facet_normals_by_enumeration", no_fallback)
    rng = np.random.default_rng(3)
    angle = rng.uniform(0.0, 2.0 * math.pi, 25)
    radial = np.column_stack([np.cos(angle), np.sin(angle)])
    points = 0.05 * radial
    normals = turned(-radial, rng.uniform(-0.6, 0.6, 25))
    expected = reference_epsilon(reference_wrenches(points, normals, 0.3, ORIGIN))
    assert expected > 0.0
    assert ferrari_canny(points, normals, 0.3, ORIGIN) == pytest.approx(expected, abs=1e-9)


def test_the_exhaustive_fallback_agrees_with_the_hull() -> None:
    # The fallback only runs if floating point breaks the incremental hull; check it
    # directly so it is right when it does.
    points = ring(5, radius=0.05, phase=0.4)
    normals = turned(-points, np.array([0.3, -0.2, 0.1, 0.0, -0.4]))
    wrenches = reference_wrenches(points, normals, 0.5, ORIGIN)
    facets = quality._facet_normals_by_enumeration(wrenches, 1e-9)
    assert facets is not None
    fallback = float(np.min(np.max(wrenches @ facets.T, axis=0)))
    assert fallback == pytest.approx(ferrari_canny(points, normals, 0.5, ORIGIN), abs=1e-12)
    assert quality._facet_normals_by_enumeration(wrenches[:, [0, 1, 0]], 1e-9) is None


def test_bad_inputs_are_rejected_with_the_value() -> None:
    points = ring(3)
    with pytest.raises(ValueError, match="mu"):
        ferrari_canny(points, -points, -0.1, ORIGIN)
    with pytest.raises(ValueError, match="non-zero"):
        ferrari_canny(points, np.zeros((3, 2)), 0.5, ORIGIN)
    with pytest.raises(ValueError, match=r"\(K, 2\)"):
        ferrari_canny(points, -points[:2], 0.5, ORIGIN)
    with pytest.raises(ValueError, match="torque_scale"):
        ferrari_canny(points, -points, 0.5, ORIGIN, torque_scale=0.0)
    with pytest.raises(ValueError, match="cone_edges"):
        quality._primitive_wrenches(points, -points, 0.5, ORIGIN, None, cone_edges=1)


# -- Ferrari–Canny: properties --------------------------------------------------------------


@settings(max_examples=120, deadline=None)
@given(grasps())
def test_epsilon_is_the_exact_inscribed_radius_and_zero_iff_no_closure(
    grasp: tuple[NDArray[np.float64], NDArray[np.float64], float, NDArray[np.float64]],
) -> None:
    points, normals, mu, centre = grasp
    epsilon = ferrari_canny(points, normals, mu, centre)
    assert epsilon >= 0.0

    wrenches = reference_wrenches(points, normals, mu, centre)
    assert epsilon == pytest.approx(reference_epsilon(wrenches), abs=1e-8)
    # Independently: the support function min over unit d of max_i w_i·d equals the
    # inscribed radius when the origin is inside; a sampled d misses the minimum by at
    # most |w|max × the gap between samples.
    sampled = float(np.min(np.max(wrenches @ DIRECTIONS.T, axis=0)))
    slack = float(np.max(np.linalg.norm(wrenches, axis=1))) * DIRECTION_GAP
    if epsilon > 0.0:
        assert epsilon - 1e-9 <= sampled <= epsilon + slack
    else:
        assert sampled <= slack


@settings(max_examples=60, deadline=None)
@given(grasps(), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_epsilon_never_falls_as_friction_rises(
    grasp: tuple[NDArray[np.float64], NDArray[np.float64], float, NDArray[np.float64]],
    low: float,
    extra: float,
) -> None:
    points, normals, _, centre = grasp
    assert (
        ferrari_canny(points, normals, low + extra, centre)
        >= ferrari_canny(points, normals, low, centre) - 1e-9
    )


# -- slip, tilt, Coulomb ----------------------------------------------------------------------


def test_rigid_velocity_fit_recovers_a_twist_exactly() -> None:
    points = np.array([[0.03, 0.01], [-0.03, 0.02], [0.0, -0.04]])
    v, omega, pivot = np.array([0.1, -0.05]), 2.0, np.array([0.01, 0.0])
    d = points - pivot
    velocities = v + omega * np.column_stack([-d[:, 1], d[:, 0]])
    query = np.array([0.2, 0.3])
    q = query - pivot
    expected = v + omega * np.array([-q[1], q[0]])
    np.testing.assert_allclose(rigid_velocity_at(points, velocities, query), expected, atol=1e-12)


def test_slip_is_zero_when_the_object_moves_rigidly_with_the_fingers() -> None:
    centre = np.array([0.1, 0.2])
    fingers = centre + np.array([[0.03, 0.0], [0.03, 0.01], [-0.03, 0.0], [-0.03, -0.01]])
    v, omega = np.array([0.05, 0.02]), 1.5  # translate and turn about the centre
    d = fingers - centre
    finger_velocity = v + omega * np.column_stack([-d[:, 1], d[:, 0]])
    assert planar_slip(centre, v, fingers, finger_velocity) == pytest.approx(0.0, abs=1e-12)
    # Turning about another point moves the centre too; still rigid, still no slip.
    pivot = np.array([0.0, 0.0])
    d = fingers - pivot
    finger_velocity = v + omega * np.column_stack([-d[:, 1], d[:, 0]])
    c = centre - pivot
    object_velocity = np.append(v + omega * np.array([-c[1], c[0]]), 0.3)  # z is ignored
    assert planar_slip(centre, object_velocity, fingers, finger_velocity) == pytest.approx(
        0.0, abs=1e-12
    )


def test_slip_is_the_fingers_speed_when_the_object_stays_put() -> None:
    fingers = np.array([[0.03, 0.0], [-0.03, 0.0], [0.0, 0.03]])
    u = np.array([0.04, -0.03])
    assert planar_slip(ORIGIN, np.zeros(2), fingers, np.tile(u, (3, 1))) == pytest.approx(0.05)
    # Without fingers the slip is the object's own planar speed.
    assert planar_slip(
        ORIGIN, [0.3, 0.4, 9.0], np.zeros((0, 2)), np.zeros((0, 2))
    ) == pytest.approx(0.5)


def test_tilt_is_the_angle_of_the_body_z_axis_from_vertical() -> None:
    half = math.radians(10.0) / 2.0
    about_x = [math.sin(half), 0.0, 0.0, math.cos(half)]
    assert tilt_angle(about_x) == pytest.approx(math.radians(10.0), abs=1e-12)
    yaw = [0.0, 0.0, math.sin(0.6), math.cos(0.6)]
    assert tilt_angle(yaw) == pytest.approx(0.0, abs=1e-12)
    # Yaw then a 30° tip about y, from an unnormalised quaternion.
    tip = np.array([0.0, math.sin(math.radians(15.0)), 0.0, math.cos(math.radians(15.0))])
    combined = _quaternion_product(np.array(yaw), tip) * 3.0
    assert tilt_angle(combined) == pytest.approx(math.radians(30.0), abs=1e-12)
    assert tilt_angle([1.0, 0.0, 0.0, 0.0]) == pytest.approx(math.pi, abs=1e-12)


def _quaternion_product(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Hamilton product of (x, y, z, w) quaternions."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ]
    )


def test_coulomb_slip_force_is_twice_mu_times_each_fingers_push() -> None:
    assert coulomb_slip_force(10.0, 0.5) == pytest.approx(10.0)
    assert coulomb_slip_force(4.0, 0.25) == pytest.approx(2.0)
    with pytest.raises(ValueError, match="grip_force"):
        coulomb_slip_force(-1.0, 0.5)


# -- grasp_metrics on a hand-built contact report -------------------------------------------


@dataclasses.dataclass(frozen=True)
class Report:
    """A contact report with only the attributes grasp_metrics reads
    (:class:`graspenv.tasks.metrics.ContactArrays`)."""

    particle: NDArray[np.int64]
    position: NDArray[np.float64]
    normal: NDArray[np.float64]
    normal_force: NDArray[np.float64]
    distance: NDArray[np.float64]


def report(
    rows: list[tuple[int, tuple[float, float, float], tuple[float, float, float], float, float]],
) -> Report:
    """Rows of (particle, position, normal into the object, normal force, distance)."""
    k = len(rows)
    return Report(
        particle=np.array([r[0] for r in rows], dtype=np.int64),
        position=np.array([r[1] for r in rows], dtype=float).reshape(k, 3),
        normal=np.array([r[2] for r in rows], dtype=float).reshape(k, 3),
        normal_force=np.array([r[3] for r in rows], dtype=float),
        distance=np.array([r[4] for r in rows], dtype=float),
    )


# A 6 cm box at (0.1, 0.2) squeezed by two particles a side, plus the table under it.
SQUEEZE = [
    (0, (0.13, 0.21, 0.01), (-1.0, 0.0, 0.0), 3.0, -0.0004),
    (1, (0.13, 0.19, 0.01), (-1.0, 0.0, 0.0), 2.0, -0.0002),
    (2, (0.07, 0.21, 0.01), (1.0, 0.0, 0.0), 2.5, -0.0003),
    (3, (0.07, 0.19, 0.01), (1.0, 0.0, 0.0), 2.5, -0.0001),
    (-1, (0.10, 0.20, 0.0), (0.0, 0.0, 1.0), 40.0, -0.002),
]
BOX_CENTRE = np.array([0.1, 0.2, 0.03])


def test_grip_force_and_contacts_count_only_particles() -> None:
    m = grasp_metrics(
        report(SQUEEZE), BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((4, 3)), 0.25
    )
    assert m.grip_force == pytest.approx(10.0)  # not the table's 40 N
    assert m.n_contacts == 4
    assert m.penetration == pytest.approx(0.0004)  # not the table's 2 mm
    assert m.slip == 0.0 and m.tilt == 0.0


def test_a_squeezed_box_is_in_force_closure_with_the_merged_contacts_epsilon() -> None:
    m = grasp_metrics(
        report(SQUEEZE), BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((4, 2)), 0.25
    )
    points = np.array([r[1][:2] for r in SQUEEZE[:4]])
    normals = np.array([r[2][:2] for r in SQUEEZE[:4]])
    expected = ferrari_canny(points, normals, 0.25, BOX_CENTRE[:2])
    assert m.force_closure and m.epsilon == pytest.approx(expected, abs=1e-12)
    assert m.epsilon > 0.1
    frictionless = grasp_metrics(
        report(SQUEEZE), BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((4, 2)), 0.0
    )
    assert not frictionless.force_closure and frictionless.epsilon == 0.0


def test_a_particle_touching_at_several_points_is_one_contact() -> None:
    # Two particles across the box (epsilon then depends on where each one is). Particle
    # 0 touches at two points whose force-weighted mean is its point in SQUEEZE,
    # (0.13, 0.21): 1 N at y = 0.215 and 2 N at y = 0.2075 (the plain mean is off by
    # 1.25 mm, which would change epsilon by about 15 %).
    split = [
        (0, (0.13, 0.215, 0.01), (-1.0, 0.0, 0.0), 1.0, -0.0004),
        (0, (0.13, 0.2075, 0.01), (-1.0, 0.0, 0.0), 2.0, -0.0001),
        SQUEEZE[3],
    ]
    whole = [SQUEEZE[0], SQUEEZE[3]]
    m = grasp_metrics(report(split), BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((3, 2)), 0.5)
    expected = grasp_metrics(
        report(whole), BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((2, 2)), 0.5
    )
    assert m.n_contacts == 2
    assert m.force_closure
    assert m.epsilon == pytest.approx(expected.epsilon, abs=1e-12)
    assert m.grip_force == pytest.approx(expected.grip_force)


def test_particles_pressing_from_above_or_apart_do_not_count_for_closure() -> None:
    on_top = (7, (0.1, 0.2, 0.06), (0.0, 0.0, -1.0), 5.0, -0.0001)
    apart = (8, (0.1, 0.23, 0.01), (0.0, -1.0, 0.0), 0.0, 0.001)  # reported, not touching
    rows = [*SQUEEZE, on_top, apart]
    m = grasp_metrics(report(rows), BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((6, 2)), 0.25)
    base = grasp_metrics(
        report(SQUEEZE), BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((4, 2)), 0.25
    )
    assert m.n_contacts == 5  # the one on top touches; the one apart does not
    assert m.grip_force == pytest.approx(15.0)
    assert m.epsilon == pytest.approx(base.epsilon, abs=1e-12)


def test_grasp_slip_is_zero_for_a_rigid_carry_and_full_for_fingers_sliding_past() -> None:
    v, omega = np.array([0.05, -0.02]), 0.8
    d = np.array([r[1][:2] for r in SQUEEZE[:4]]) - BOX_CENTRE[:2]
    fingers = v + omega * np.column_stack([-d[:, 1], d[:, 0]])
    carried = grasp_metrics(
        report(SQUEEZE), BOX_CENTRE, IDENTITY, np.append(v, 0.0), [0.0, 0.0, omega], fingers, 0.25
    )
    assert carried.slip == pytest.approx(0.0, abs=1e-12)
    # The same rows given per report row (the table's velocity is never read).
    per_row = np.vstack([fingers, [9.0, 9.0]])
    again = grasp_metrics(
        report(SQUEEZE), BOX_CENTRE, IDENTITY, np.append(v, 0.0), AT_REST, per_row, 0.25
    )
    assert again.slip == pytest.approx(0.0, abs=1e-12)
    left_behind = grasp_metrics(
        report(SQUEEZE), BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.tile([0.03, 0.04], (4, 1)), 0.25
    )
    assert left_behind.slip == pytest.approx(0.05)


def test_with_no_particle_contact_slip_is_the_objects_planar_speed() -> None:
    table_only = report([SQUEEZE[-1]])
    m = grasp_metrics(
        table_only, BOX_CENTRE, IDENTITY, [0.3, -0.4, 0.2], AT_REST, np.zeros((0, 3)), 0.5
    )
    assert m.slip == pytest.approx(0.5)
    assert (m.grip_force, m.n_contacts, m.force_closure, m.epsilon, m.penetration) == (
        0.0,
        0,
        False,
        0.0,
        0.0,
    )


def test_grasp_tilt_reads_the_object_quaternion() -> None:
    half = math.radians(10.0) / 2.0
    q = [math.sin(half), 0.0, 0.0, math.cos(half)]
    m = grasp_metrics(report(SQUEEZE), BOX_CENTRE, q, AT_REST, AT_REST, np.zeros((4, 2)), 0.25)
    assert m.tilt == pytest.approx(math.radians(10.0), abs=1e-12)


def test_velocities_that_do_not_match_the_report_are_rejected() -> None:
    with pytest.raises(ValueError, match="particle_velocities"):
        grasp_metrics(
            report(SQUEEZE), BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((3, 2)), 0.25
        )


def test_a_physics_contact_report_is_accepted_as_is() -> None:
    from graspenv.physics import ContactReport

    r = report(SQUEEZE)
    k = len(SQUEEZE)
    real = ContactReport(
        **dataclasses.asdict(r),
        other_object=np.full(k, -1, dtype=np.int64),
        friction=np.zeros((k, 3)),
    )
    m = grasp_metrics(real, BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((4, 2)), 0.25)
    assert m == grasp_metrics(r, BOX_CENTRE, IDENTITY, AT_REST, AT_REST, np.zeros((4, 2)), 0.25)


def test_metrics_are_frozen_and_empty_means_no_grasp() -> None:
    empty = GraspMetrics.empty()
    assert (empty.n_contacts, empty.force_closure, empty.epsilon, empty.slip) == (
        0,
        False,
        0.0,
        0.0,
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        empty.slip = 1.0  # type: ignore[misc]
