"""A fingertip's load along an object's side: its share among the particles
(``proxy.share_side_load``; step 8 of :mod:`graspenv.proxies.persistent`), and the
side hold (``proxy.hold_time``; step 7).

A rigid fingertip's contact has one normal force and one friction force, so it slips
when the load along the side reaches μ times the normal force. Under the contact
law each particle presses with k·d for a depth d and pulls along the side with k·e
for an offset e along it, one stiffness k: particles stuck to one side carry the
same e, the least pressed reach their limit (e = μ·d) first and slide while the
rest hold, and the grip creeps in partial slip (docs/accuracy.md, "A fingertip shares its side
load"). :func:`shared_side_load` shares each fingertip's load by depth instead.

The side hold: a fingertip is rigid: under a steady load along an object's side its particles
should stay where the hand puts them, not give by the load over the contact law's
stiffness. Each frame the particles pressing a side are compared with where the
hand put them; the part of their shortfalls along the sides that one rigid motion
of each object explains is integrated into a per-contact offset of the targets
(docs/accuracy.md, "The side hold"; docs/design.md, section 3b).

The pure laws (:func:`side_hold`, :func:`rigid_part`, :func:`shared_side_load`)
come first; then the frame's side stages the persistent proxies call, which read
the world: which particles press a side (:func:`pressing`, :func:`beside`), each
contact's hold after a frame (:func:`holds_after`) and the targets with their load
shared (:func:`shared_targets`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from graspenv.geometry import less_along
from graspenv.jit import njit
from graspenv.physics.control import REST_TOLERANCE
from graspenv.physics.world import PhysicsWorld

__all__ = [
    "WRAPPED_NORMAL",
    "Sides",
    "beside",
    "holds_after",
    "pressing",
    "rigid_part",
    "shared_side_load",
    "shared_targets",
    "side_hold",
]

#: The side hold counts a contact only where its particles' side normals add up to
#: at least this share of their number (an arc of up to about 150° either side of
#: its middle): beyond that it wraps round the object and has no one side to hold
#: along (:func:`side_hold`).
WRAPPED_NORMAL = 0.25


def side_hold(
    hold: NDArray[np.float64],
    gain: float,
    contact: NDArray[np.intp],
    shortfall: NDArray[np.float64],
    outward: NDArray[np.float64],
    body: NDArray[np.intp],
    arm: NDArray[np.float64],
    most: float = math.inf,
) -> NDArray[np.float64]:
    """Each contact's side hold after a frame: the hold plus ``gain`` times its
    particles' mean shortfall along their sides as one rigid motion of each object
    explains it (:func:`rigid_part`), less the part of that along the contact's
    mean outward normal; a contact with no particle on a side lets its hold go by
    the same share.

    The squeeze is the law's own and stays out of it twice over: each particle's
    shortfall along its own side's normal is dropped, and so is what is left along
    the contact's mean normal (particles stuck round a curve stand short along the
    squeeze, which each one's side sees partly along it); what is removed along the
    mean normal includes the hold's own part there (it is kept in the world frame,
    and a turning contact's hold turns partly onto its normal). A particle with no
    side normal (by a leaning cylinder) has no side to hold along and does not
    count, nor does a contact whose particles' normals nearly cancel (one that wraps
    round an object has no one side). The fit to a rigid motion keeps the contacts
    on one object from winding up against each other in what the object cannot do
    (two fingers on one flat face holding apart, a stretch along it; on a round side
    a shift across the contacts is seen along it, and most of such a stretch
    stays). A hold is at
    most ``most`` long: a particle kept from its point along the side by something
    other than friction (another object) would otherwise push it ever farther.

    Args:
        hold: each contact's hold, metres, world frame, (T, 2).
        gain: the frame over the hold time, at most 1.
        contact: the contact of each particle pressing a side, (N,).
        shortfall: where the hand put it less where it is, metres, world frame,
            (N, 2).
        outward: the side's unit normal there, pointing away from the object's
            centre (the wrap test needs that), (N, 2), or a zero row.
        body: the object whose side it presses, (N,).
        arm: its point on that side less the object's centre, metres, world frame,
            (N, 2).
        most: the longest a hold may be, metres.

    Returns:
        The new holds, metres, (T, 2).
    """
    count = len(hold)
    after = hold * (1.0 - gain)
    sided = np.any(outward != 0.0, axis=1)
    counts = np.bincount(contact[sided], minlength=count)
    normal = np.zeros((count, 2))
    np.add.at(normal, contact[sided], outward[sided])
    length = np.hypot(normal[:, 0], normal[:, 1])
    pressed = (counts > 0) & (length >= WRAPPED_NORMAL * counts)
    if not np.any(pressed):
        return after
    use = sided & pressed[contact]
    contact = contact[use]
    along = rigid_part(body[use], arm[use], shortfall[use], outward[use])
    lag = np.zeros((count, 2))
    np.add.at(lag, contact, along)
    lag /= np.maximum(counts, 1)[:, None]
    normal /= np.maximum(length, 1e-12)[:, None]
    held = less_along(hold + gain * lag, normal)
    held *= np.minimum(1.0, most / np.maximum(np.hypot(held[:, 0], held[:, 1]), 1e-12))[:, None]
    after[pressed] = held[pressed]
    return after


def rigid_part(
    body: NDArray[np.intp],
    arm: NDArray[np.float64],
    shortfall: NDArray[np.float64],
    outward: NDArray[np.float64],
) -> NDArray[np.float64]:
    """The part of the particles' shortfalls along their sides that one rigid motion
    of each object (a shift in the table plane and a turn about its centre) explains:
    the least-squares fit of each object's shortfalls, each seen along its own side.

    Each side sees a shift through its tangent and a turn as the tangent's share of
    the arm's perpendicular. The fitted values are the projection of the shortfalls
    onto the motions the sides can see, unique where the motion itself is not (a
    single flat face cannot tell a shift along it from a turn); that is their mean
    along one flat face, whose arms (to points on the face) all reach it alike. On a
    round side a shift across the contacts is seen along the side too, so two
    contacts on a cylinder pulled apart along it keep most of their shortfalls.

    Args:
        body: each particle's object, (N,).
        arm: its point on the side less that object's centre, metres, world frame,
            (N, 2).
        shortfall: where the hand put it less where it is, metres, world frame,
            (N, 2); only its part along the side counts.
        outward: its side's unit outward normal, (N, 2).

    Returns:
        The fitted shortfalls along the sides, metres, world frame, (N, 2).
    """
    tangent = np.column_stack([-outward[:, 1], outward[:, 0]])
    objects, body = np.unique(body, return_inverse=True)
    # The turn's column in units of each object's arms, so that a relative cut of
    # the normal matrix's eigenvalues treats a shift and a turn alike.
    reach = np.zeros(len(objects))
    np.add.at(reach, body, np.einsum("ij,ij->i", arm, arm))
    reach = np.sqrt(reach / np.bincount(body)) + 1e-12
    turn = (tangent[:, 1] * arm[:, 0] - tangent[:, 0] * arm[:, 1]) / reach[body]
    seen = np.column_stack([tangent, turn])  # each row: how the side sees (dx, dy, turn)
    size = np.einsum("ij,ij->i", shortfall, tangent)
    normal_matrix = np.zeros((len(objects), 3, 3))
    np.add.at(normal_matrix, body, seen[:, :, None] * seen[:, None, :])
    moment = np.zeros((len(objects), 3))
    np.add.at(moment, body, seen * size[:, None])
    motion = np.einsum(
        "oij,oj->oi", np.linalg.pinv(normal_matrix, rcond=1e-9, hermitian=True), moment
    )
    fitted = np.einsum("ij,ij->i", seen, motion[body])
    return fitted[:, None] * tangent


def shared_side_load(
    reach: NDArray[np.float64],
    outward: NDArray[np.float64],
    group: NDArray[np.int64],
    friction: NDArray[np.float64],
) -> NDArray[np.float64]:
    """The shifts of particles' targets along their sides that share each group's
    load along the side by depth, as a rigid fingertip's contact does.

    A group is one fingertip's particles on one object's side. Each particle's target
    lies ``reach`` from it: its part along the particle's own side normal, the
    depth d (inward), sets how hard it presses, its part e along the side how hard
    it pulls along it. Within a group the particles that press (d > 0) keep the
    sum of their e, but each gets the share d / Σd of it: the group's load along the
    side is unchanged, and every particle is at the same share of its friction
    limit, so they slip together when the load reaches μ·Σd. What a squeeze alone
    puts along the particles round a curved side, opposite either side of the
    middle, cancels. Left as they are: a particle whose own offset from its
    group's mean is more than its friction holds (it slides back towards its point
    on its own), a group whose normals nearly cancel (wrapped round an object,
    :data:`WRAPPED_NORMAL`), and one whose load is at or beyond its friction limit,
    which slides, each particle on its own.

    Args:
        reach: each particle's target less where it is, metres, world frame, (N, 2).
        outward: its side's unit outward normal, (N, 2), no zero row.
        group: each particle's group, any integers, (N,).
        friction: its friction coefficient against the side (Bullet's product of
            the two), (N,).

    Returns:
        The shift of each target along its side, metres, world frame, (N, 2).

    Raises:
        ValueError: the arrays' shapes do not agree.
    """
    if not (reach.shape == outward.shape and reach.shape[1:] == (2,)):
        raise ValueError(f"reach and outward must be (N, 2), got {reach.shape}, {outward.shape}")
    if not (group.shape == friction.shape == reach.shape[:1]):
        raise ValueError(f"group and friction must be ({len(reach)},)")
    if group.size and int(group.max()) - int(group.min()) > 4 * group.size:
        group = np.unique(group, return_inverse=True)[1]  # the kernel indexes by range
    return _share_by_depth(
        np.ascontiguousarray(reach, np.float64),
        np.ascontiguousarray(outward, np.float64),
        np.ascontiguousarray(group, np.int64),
        np.ascontiguousarray(friction, np.float64),
    )


@njit
def _share_by_depth(
    reach: NDArray[np.float64],
    outward: NDArray[np.float64],
    group: NDArray[np.int64],
    friction: NDArray[np.float64],
) -> NDArray[np.float64]:
    """:func:`shared_side_load`, compiled: passes over the particles in order,
    summing per group as numpy's ``bincount`` does (the numpy form it replaced is
    the oracle in tests/proxies/reference.py). Groups are indexed from the smallest
    number among the pressing particles, so their range must be small (contact
    index × objects + object in the frame's use; :func:`shared_side_load` renumbers a
    wide one). :data:`WRAPPED_NORMAL` is read as a constant when it compiles."""
    n = reach.shape[0]
    shift = np.zeros((n, 2))
    along = np.empty(n)
    deep = np.empty(n)
    pressers, first, last = 0, 0, 0
    for i in range(n):
        along[i] = reach[i, 0] * -outward[i, 1] + reach[i, 1] * outward[i, 0]
        deep[i] = -(reach[i, 0] * outward[i, 0] + reach[i, 1] * outward[i, 1])
        if deep[i] > 0.0:
            if pressers == 0 or group[i] < first:
                first = group[i]
            if pressers == 0 or group[i] > last:
                last = group[i]
            pressers += 1
    if pressers == 0:
        return shift
    size = last - first + 1
    # The pressing particles' mean offset along the side, per group: one further
    # from it than its own friction holds is not stuck with the rest and slides
    # back towards its point as before (else particles could drift along a held
    # side, ever further from their points, and bunch).
    total = np.zeros(size)
    count = np.zeros(size, np.int64)
    for i in range(n):
        if deep[i] > 0.0:
            total[group[i] - first] += along[i]
            count[group[i] - first] += 1
    stuck = np.zeros(n, np.bool_)
    normal = np.zeros((size, 2))
    load = np.zeros(size)
    depth = np.zeros(size)
    limit = np.zeros(size)
    stuck_count = np.zeros(size, np.int64)
    for i in range(n):
        if deep[i] > 0.0:
            g = group[i] - first
            if abs(along[i] - total[g] / count[g]) <= friction[i] * deep[i]:
                stuck[i] = True
                stuck_count[g] += 1
                normal[g, 0] += outward[i, 0]
                normal[g, 1] += outward[i, 1]
                load[g] += along[i]
                depth[g] += deep[i]
                limit[g] += friction[i] * deep[i]
    for i in range(n):
        if stuck[i]:
            g = group[i] - first
            share = 0.0  # a stuck particle's shift is share × tangent, signed zeros too
            one_side = np.hypot(normal[g, 0], normal[g, 1]) >= WRAPPED_NORMAL * stuck_count[g]
            if one_side and abs(load[g]) < limit[g]:
                share = deep[i] * load[g] / depth[g] - along[i]
            shift[i, 0] = share * -outward[i, 1]
            shift[i, 1] = share * outward[i, 0]
    return shift


class Sides(NamedTuple):
    """The rows of a frame whose points lie inside an object's footprint.

    Attributes:
        rows: their indices, (N,).
        at: where their bottom particles are, metres, world frame, (N, 3).
        normal: the table-plane outward normal of the nearest object's side at each
            particle within two particle radii, or a zero row, (N, 2).
        nearest, off: the object nearest each particle and how deep the particle's
            centre lies in its footprint, metres, negative outside, (N,) each.
    """

    rows: NDArray[np.intp]
    at: NDArray[np.float64]
    normal: NDArray[np.float64]
    nearest: NDArray[np.int64]
    off: NDArray[np.float64]


def pressing(
    world: PhysicsWorld,
    particles: NDArray[np.int64],
    owner: NDArray[np.int64],
    depth: NDArray[np.float64],
) -> Sides:
    """The rows whose points lie inside an object's footprint, where their bottom
    particles are and the side each is by (what the penetration limit and the
    side hold both need, read once).

    Args:
        particles: particle ids, (K, L) stacks, bottom first.
        owner, depth: the object whose footprint holds each point deepest and that
            depth from its nearest side, metres, negative outside; (K,) each
            (:meth:`~graspenv.physics.world.PhysicsWorld.footprint_depth`).
    """
    rows = np.flatnonzero((owner >= 0) & (depth > 0.0))
    at = world.pool.positions(particles[rows, 0])
    # The nearest footprint's side within two radii of the particle (none at a
    # disc's centre or by a leaning cylinder).
    nearest, off, normal = world.footprint_side(at[:, :2], 2.0 * world.pool.radius)
    return Sides(rows, at, normal, nearest, off)


def holds_after(
    world: PhysicsWorld,
    hold: NDArray[np.float64],
    gain: float,
    most: float,
    track_of: NDArray[np.intp],
    particles: NDArray[np.int64],
    born: NDArray[np.bool_],
    owner: NDArray[np.int64],
    sides: Sides,
    pressed: NDArray[np.bool_],
) -> NDArray[np.float64]:
    """Each contact's side hold after this frame (step 7 of :mod:`graspenv.proxies.persistent`).

    A particle counts if its point lies inside an object's footprint, it was
    not put down this frame, it stands on the table (not on a top face) and
    that object is the one nearest it, whose side gives its outward normal
    (:func:`side_hold` leaves out those with none).
    Its shortfall is where the hand put it last frame (its last target less its
    contact's hold then) less where it is; a particle a merged contact
    inherited was held with its old contact's hold, which for that one frame
    counts as shortfall (and, through the fit, in the other contacts on the
    same object).

    Args:
        world: the world the particles are in.
        hold: each contact's hold before this frame, metres, world frame, (T, 2).
        gain, most: as :func:`side_hold`.
        track_of: each row's contact, (K,).
        particles, born: the rows' particle stacks (K, L) and which were put
            down this frame.
        owner: the object whose footprint holds each point deepest, (K,).
        sides: the rows inside a footprint (:func:`pressing`).
        pressed: which of them press a side (:func:`beside`).

    Returns:
        The new holds, metres, world frame, (T, 2).
    """
    pool = world.pool
    rows, at, outward, _, off = sides
    keep = ~born[rows] & pressed
    rows, at, outward, off = rows[keep], at[keep, :2], outward[keep], off[keep]
    contact = track_of[rows]
    shortfall = pool.last_targets(particles[rows, 0]) - hold[contact] - at
    body = owner[rows]
    arm = at - world.object_states().position[body, :2]
    # The arm to the particle's point on the side, not to its centre: particles
    # on one face press in to depths a few micrometres apart, and seen from
    # their centres the face would tell a turn from a shift along it.
    arm += off[:, None] * outward
    return side_hold(hold, gain, contact, shortfall, outward, body, arm, most)


def beside(
    world: PhysicsWorld, sides: Sides, owner: NDArray[np.int64], lifted: NDArray[np.intp]
) -> NDArray[np.bool_]:
    """Which of ``sides``' rows press the side of the object their point lies in:
    the particle stands on the table (not on a top face, nor lifted there this
    frame) and that object is the one nearest it (with two objects close
    together it may not be)."""
    on_table = sides.at[:, 2] < world.pool.radius + REST_TOLERANCE
    if lifted.size:  # mostly empty, and numpy's isin costs microseconds even so
        on_table &= ~np.isin(sides.rows, lifted)
    return on_table & (sides.nearest == owner[sides.rows])


def shared_targets(
    friction: NDArray[np.float64],
    targets: NDArray[np.float64],
    track_of: NDArray[np.intp],
    owner: NDArray[np.int64],
    sides: Sides,
    pressed: NDArray[np.bool_],
) -> NDArray[np.float64]:
    """``targets`` with each contact's load along each object's side shared by its
    particles' depths (step 8 of :mod:`graspenv.proxies.persistent`), where they press a side
    (``pressed``, :func:`beside`); ``friction`` is each object's against a particle
    (Bullet's product of the two). Its arguments come from the frame's steps before
    it (:func:`pressing`, :func:`beside`) and are not checked again."""
    return _shared_rows(
        targets, sides.rows, sides.at, sides.normal, pressed, track_of, owner, friction
    )


@njit
def _shared_rows(
    targets: NDArray[np.float64],
    rows: NDArray[np.intp],
    at: NDArray[np.float64],
    normal: NDArray[np.float64],
    pressed: NDArray[np.bool_],
    track_of: NDArray[np.intp],
    owner: NDArray[np.int64],
    friction: NDArray[np.float64],
) -> NDArray[np.float64]:
    """:func:`shared_targets` in one compiled call: the pressing rows with a side
    normal gathered, their load shared (:func:`_share_by_depth`), the shifts added
    to a copy of ``targets``; ``friction`` is each object's against a particle."""
    kept = np.flatnonzero(pressed & ((normal[:, 0] != 0.0) | (normal[:, 1] != 0.0)))
    m = kept.size
    reach = np.empty((m, 2))
    group = np.empty(m, np.int64)
    against = np.empty(m)
    for j in range(m):
        row = rows[kept[j]]
        body = owner[row]
        reach[j, 0] = targets[row, 0] - at[kept[j], 0]
        reach[j, 1] = targets[row, 1] - at[kept[j], 1]
        group[j] = track_of[row] * friction.size + body
        against[j] = friction[body]
    shift = _share_by_depth(reach, normal[kept], group, against)
    shared = targets.copy()
    for j in range(m):
        shared[rows[kept[j]], 0] += shift[j, 0]
        shared[rows[kept[j]], 1] += shift[j, 1]
    return shared
