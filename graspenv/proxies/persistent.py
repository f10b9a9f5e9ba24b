"""Persistent particle proxies (Wilson, ITS 2009).

Every contour point of every contact owns a particle (or a stack of them) that lives
as long as the point can be followed from frame to frame, so a squeezing finger keeps
pushing the same bodies into an object and friction builds up as it would under a
real fingertip. One camera frame:

1. *Lift-off.* Particles of removed contacts go back to the pool.
2. *Hand rotation* (``proxy.track_hand_rotation``). The rotation of the best rigid
   motion of all continuing contacts' centroids is the hand's turn this frame. A
   round fingertip's own rotation cannot be seen in the mask; without this estimate
   its points would counter-rotate against a turning object and roll on it.
3. *Continuing contact.* The previous points are predicted: moved by the contact's
   centroid displacement and, with the estimate on, turned about the centroid by the
   hand's turn. With ``proxy.predicted_resampling`` the current contour is made
   from the predicted points: with ``proxy.follow_points`` (the default) each moves
   onto the new outline along the contour's normal (gaps filled at the spacing,
   crowded points dropped: :func:`graspenv.contacts.resample.follow_kernel`), so the points move as
   the contact moved and stay put on a still one; without it the outline is
   resampled evenly from the predicted first point, and the points slide along a
   round tip's outline as its pixelated perimeter changes. The windowed
   sum-of-squared-distances match (:func:`graspenv.contacts.matching.correspond_batch`:
   every continuing contact in one call) then gives each current point its
   predecessor, whose particle it reuses; current points without one get a new
   particle put down beside the nearest neighbouring point that is not new (its
   particle moved by the new point's offset from that point, less any part of the
   offset into the side it presses; not moved off a top face), or, farther than
   :data:`FAR_FROM_ANCHOR` contour spacings (or particle diameters) from that
   point's particle (the other half of a merged contact), or where it would overlap
   a box's or a cylinder's footprint by more than :data:`MOST_OVERLAP` of its
   radius, on whatever lies under the point itself, as a new contact's are;
   previous points whose successor did not name them release theirs.
4. *New contact.* One particle (stack) per contour point, put down by ray casting on
   whatever is there (table or object top); a point just outside an object's side
   goes on the table beside it, clear of the side.
5. *Culling* (``proxy.cull``). A point that cannot touch an object before the next
   frame (farther from every object's footprint than the particle radius, twice its
   contact's travel this frame, the fastest object's travel in a frame and
   ``proxy.cull_margin``) has no particle: it stays a plain contour point, matched
   like the others, and gets a particle (put down by ray casting) as it comes near.
   Beyond that reach plus the margin again a point gives its particle back. A finger
   squeezing a box keeps particles only on the side facing it; a hand hovering over
   an empty part of the table costs no physics at all.
6. *Penetration limit* (``proxy.penetration_limit``). A particle whose point lies
   deeper than ``proxy.penetration_margin`` inside an object's footprint while the
   particle is below the object's top is lifted onto the top face, instead of
   pressing the side ever harder. The depth is the point's from the footprint's
   nearest side or, if deeper, from the side the particle is at (there a particle
   radius more is allowed): a finger sliding into a box along an edge stays within
   the margin of that edge while its particles, stopped at the face it entered by,
   would fall ever farther behind.

7. *Side hold* (``proxy.hold_time``, an option off in every preset; docs/accuracy.md, "The
   side hold"). All of a contact's targets are shifted by one offset along the side
   its particles press, the integral of how far they stood behind the hand along
   it, over the hold time: a fingertip is rigid, so under a steady load along the
   side its particles stay where the hand puts them instead of giving by the load
   over the law's stiffness (:mod:`graspenv.proxies.side_hold`). What each frame
   adds is the part of the shortfalls that one rigid motion of each object
   explains, fitted to all the particles pressing it, so that the contacts on one
   object cannot wind up against each other. A contact that presses no side lets
   its hold go at the same rate. Particles put down this frame start at their
   points and reach the shifted targets in the frame.
8. *Shared side load* (``proxy.share_side_load``). A fingertip's particles pressing
   one object's side share its load along the side by how deep they press, as one
   rigid contact: their targets' summed offset along the side is kept and dealt
   out by depth, so all reach their friction limit together instead of the least
   pressed slipping first (:func:`~graspenv.proxies.side_hold.shared_side_load`).

With ``track_hand_rotation`` and ``predicted_resampling`` both off this is the
paper's plain form: the raw previous contour matched against the tracker's contour
(with either on, the predicted points are matched).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from graspenv.config import ProxyConfig
from graspenv.contacts.matching import correspond_batch
from graspenv.contacts.resample import follow_kernel, gather, gather_rows, resample_kernel
from graspenv.contacts.tracking import ContactFrame, ContactSet
from graspenv.geometry import Polylines, bounds_of, not_into, reach_from
from graspenv.jit import njit
from graspenv.physics.control import REST_TOLERANCE
from graspenv.physics.world import PhysicsWorld
from graspenv.proxies.base import ProxyCommand, rotation_kernel
from graspenv.proxies.side_hold import Sides, beside, holds_after, pressing, shared_targets

__all__ = ["PersistentProxies"]

#: A new contour point farther than this many contour spacings (or particle
#: diameters, whichever is more) from the particle of the point it would start
#: beside is put down where it is instead: the other half of a merged contact, not a
#: contour that grew by a point. At 2 mm spacing, two spacings put points of a
#: sliding grip's leading edge down too (the slide's error 0.27 -> 0.88 mm).
FAR_FROM_ANCHOR = 2.0

#: A particle put down beside its anchor's on the table may overlap a box's or a
#: cylinder's footprint by at most this share of its radius (a squeezing anchor's
#: own press is hundredths of a millimetre); beyond it the point is put down where
#: it is. A leaning cylinder's footprint is its shadow's hull, wider than its foot:
#: there a point beside the overhang may be put down afresh needlessly, under it.
MOST_OVERLAP = 0.25


class _Smoothed(NamedTuple):
    """The alpha-beta filter of each contact's centroid (``proxy.smoothing``,
    :func:`_alpha_beta`).

    Attributes:
        centroids: the filtered centroids, metres, shape (T, 2) (the centroids
            themselves unless ``proxy.smoothing`` is on).
        drift: the filtered centroid velocities, metres a frame, (T, 2); NaN in a
            contact's first frame.
    """

    centroids: NDArray[np.float64]
    drift: NDArray[np.float64]


class _Tracks(NamedTuple):
    """Every tracked contact's contour points and the particle stacks that follow
    them, laid end to end in ascending contact id.

    Attributes:
        ids: contact ids, ascending, shape (T,).
        contours: each track's contour points of the last frame, metres, world frame,
            (P, 2) in all.
        particles: pool ids, shape (P, L), column 0 at the bottom, rows as in
            ``contours``; a row of -1 for a culled point (no particle).
        born: which points got their particle in the last frame, shape (P,).
        centroids: each contact's centroid in the last frame, metres, shape (T, 2).
        travel: how far any point of each contact moved in the last frame at most,
            metres, shape (T,).
        smoothed: each contact's filtered centroid.
        hold: each contact's side hold, the shift of its targets along the side
            its particles press, metres, world frame, (T, 2) (zero without
            ``proxy.hold_time``).
    """

    ids: NDArray[np.int64]
    contours: Polylines
    particles: NDArray[np.int64]
    born: NDArray[np.bool_]
    centroids: NDArray[np.float64]
    travel: NDArray[np.float64]
    smoothed: _Smoothed
    hold: NDArray[np.float64]

    @classmethod
    def empty(cls, layers: int) -> _Tracks:
        points = np.zeros((0, 2))
        return cls(
            np.zeros(0, np.int64), Polylines(points, np.zeros(1, np.intp)),
            np.zeros((0, layers), np.int64), np.zeros(0, bool), points, np.zeros(0),
            _Smoothed(points, points), points,
        )  # fmt: skip


class PersistentProxies:
    """Contours to persistent particle stacks.

    Args:
        world: the physics world whose particle pool and ray casts are used.
        proxy: particle and matching settings.
        spacing: contour spacing, metres, for resampling continuing contours.
        dt: seconds per camera frame (turns the hand's turn into a rotation rate).
        layers: particles per contour point (:attr:`SceneConfig.stack_layers`).
    """

    def __init__(
        self,
        world: PhysicsWorld,
        proxy: ProxyConfig,
        spacing: float,
        dt: float,
        layers: int,
    ) -> None:
        self._world = world
        self._proxy = proxy
        self._spacing = spacing
        # Farther than this from its anchor's particle, a new point is put down
        # where it is (FAR_FROM_ANCHOR).
        self._far = FAR_FROM_ANCHOR * max(spacing, 2.0 * world.pool.radius)
        self._dt = dt
        self._layers = layers
        self._cull = proxy.cull
        self._rise = proxy.stack_spacing * np.arange(self._layers)
        self._tracks = _Tracks.empty(layers)
        self.hand_turn = 0.0
        """The hand's estimated turn in the last frame, radians."""
        # The share of the particles' shortfall along a side the hold takes up a
        # frame (proxy.hold_time; 0: off).
        self._hold_gain = min(1.0, dt / proxy.hold_time) if proxy.hold_time > 0 else 0.0
        # The longest a hold may be: a grip gives at most its friction times its
        # particles' offset (the squeeze, up to the penetration margin) before it
        # slips, no more than this with an object's friction of up to 1.
        self._hold_most = proxy.particle_friction * proxy.penetration_margin
        self._share = proxy.share_side_load
        # Each object's friction against a particle (Bullet's product), for the share.
        self._side_friction = proxy.particle_friction * np.array(
            [o.friction for o in world.scene.objects]
        )

    def reset(self) -> None:
        self._tracks = _Tracks.empty(self._layers)
        self.hand_turn = 0.0

    def particle_contacts(self) -> dict[int, NDArray[np.int64]]:
        """Which particles belong to which contact after the last frame.

        For per-finger measurements: match the ``particle`` column of
        :meth:`~graspenv.physics.world.PhysicsWorld.contact_report` against these.

        Returns:
            Contact id → its particle ids (every stack layer: points in contour
            order, the layers of each point bottom first; culled points have none),
            shape (N·L,); contacts in the order of the last frame. Copies: safe to
            keep.
        """
        tracks = self._tracks
        result = {}
        bounds = tracks.contours.bounds
        for t, contact_id in enumerate(tracks.ids.tolist()):
            particles = tracks.particles[bounds[t] : bounds[t + 1]]
            result[contact_id] = particles[particles[:, 0] >= 0].reshape(-1)
        return result

    def update(self, frame: ContactFrame, mask: NDArray[np.uint8]) -> ProxyCommand:
        """Bookkeeping for one frame; ``mask`` is not needed by this method."""
        del mask
        proxy, layers, before = self._proxy, self._layers, self._tracks
        if len(before.ids) == 0 and len(frame) == 0:  # nothing on the table
            return ProxyCommand(np.zeros((0, layers), np.int64), np.zeros((0, 2)), np.zeros(0))
        now = frame.contact_set
        plan = _plan_follow(
            before,
            now,
            proxy.track_hand_rotation,
            proxy.predicted_resampling,
            proxy.follow_points,
            self._spacing,
        )
        # Every track no contact continues gives its particles back: lift-offs,
        # merges, reused ids.
        self._release(before.particles[plan.ended_rows])
        self.hand_turn = plan.motion.turn
        followed = self._follow(before, plan)
        tracks = self._touch_down(now, plan.follows, followed)
        self._tracks = tracks
        if len(tracks.particles) == 0:
            empty = np.zeros((0, layers), np.int64)
            return ProxyCommand(empty, np.zeros((0, 2)), np.zeros(0))

        sizes = np.diff(tracks.contours.bounds)
        spin = np.repeat(np.where(plan.follows, plan.motion.turn / self._dt, 0.0), sizes)
        particles, targets, born = tracks.particles, tracks.contours.points, tracks.born
        sided = proxy.penetration_limit or self._hold_gain > 0.0 or self._share
        if self._cull or sided:
            owner, depth = self._world.footprint_depth(targets)
        culled = 0
        if self._cull:
            # In place: the tracks keep the culling's changes.
            self._cull_far(tracks, depth, np.repeat(tracks.travel, sizes))
            embodied = particles[:, 0] >= 0
            culled = len(embodied) - int(np.count_nonzero(embodied))
            # The command gets the embodied rows as arrays of its own.
            particles, targets, spin = particles[embodied], targets[embodied], spin[embodied]
            born = born[embodied]
            owner, depth = owner[embodied], depth[embodied]
        else:
            particles, targets, born = particles.copy(), targets.copy(), born.copy()
        if sided:
            sides = pressing(self._world, particles, owner, depth)
        lifted = np.zeros(0, np.intp)
        if proxy.penetration_limit:
            lifted = self._limit_penetration(particles, targets, depth, sides)
        track_of = np.repeat(np.arange(len(tracks.ids)), sizes)
        if self._cull:
            track_of = track_of[embodied]
        if self._hold_gain > 0.0 or self._share:
            pressed = beside(self._world, sides, owner, lifted)
        if self._hold_gain > 0.0:
            # In place, as the culling: the tracks keep the new hold.
            tracks.hold[:] = holds_after(
                self._world, tracks.hold, self._hold_gain, self._hold_most,
                track_of, particles, born, owner, sides, pressed,
            )  # fmt: skip
            targets = targets + tracks.hold[track_of]
        if self._share:
            targets = shared_targets(self._side_friction, targets, track_of, owner, sides, pressed)
        return ProxyCommand(particles, targets, spin, culled=culled, born=born)

    # -- stages ------------------------------------------------------------------------

    def _follow(self, before: _Tracks, plan: _Plan) -> _Tracks:
        """Continue every continuing contact's track at once (step 3 of the module
        docstring): the plan's one resampling, one matching call for all of them,
        then the particles each current point inherits, starts beside a neighbour
        or is put down with.

        Returns:
            The continued tracks, in frame order.
        """
        proxy, layers = self._proxy, self._layers
        if plan.contacts.size == 0:
            return _Tracks.empty(layers)
        match = correspond_batch(
            *plan.predicted, *plan.current, proxy.window, proxy.matcher, proxy.search
        )
        pool = self._world.pool
        previous_particles = before.particles[plan.previous_rows]
        self._release(previous_particles[~match.kept])
        particles, beside, anchors, lost = _inherit(
            previous_particles, match.predecessor, match.anchor
        )
        current = plan.current.points
        born = np.zeros(len(current), bool)
        if beside.size:
            # A new point far from its anchor's particle (a merged contact's other
            # half) is put down where it is, as a touch-down would be; started beside
            # the anchor it raced along the contour and dragged what it rubbed. The
            # distance is to the particle, not to the anchor point: at a merge the
            # anchors are points the matching gave to kept particles across the
            # merged contour, near the new points but far from their own particles
            # (measured from the points, the fix changed nothing). A sliding grip's
            # particles lag their points, hence the reach of two spacings or two
            # particle diameters (the grid and the bench's default scenes were
            # unchanged by it).
            start = pool.positions(particles[anchors].reshape(-1)).reshape(-1, layers, 3)
            near = np.hypot(*(current[beside] - start[:, 0, :2]).T) <= self._far
            lost = np.concatenate([lost, beside[~near]])
            beside, anchors, start = beside[near], anchors[near], start[near]
            # Beside the anchor's particle, as far from it as the new point is from
            # the anchor's point, less any part of that into the side the anchor's
            # particle presses. Started on it, a new particle stood a spacing from
            # its point, held there by friction on a squeezed side for tens of
            # frames; dropout holes put such points down every few frames, always
            # on the same side of their neighbours, and that turned the object
            # (docs/design.md, "Particles put down beside a side or a neighbour").
            # The whole offset put particles into the object. An anchor on a top
            # face keeps its new neighbour on it: moved, that could step off the
            # face's edge into the air beside the side.
            on_table = np.flatnonzero(start[:, 0, 2] < pool.radius + REST_TOLERANCE)
            offset = current[beside[on_table]] - current[anchors[on_table]]
            outward = self._world.footprint_side(start[on_table, 0, :2], 2.0 * pool.radius)[2]
            start[on_table, :, :2] += not_into(offset, outward)[:, None, :]
            # Nor into an object: beside a cylinder that leans (no side to keep the
            # offset out of) a new particle started with its centre inside a spun
            # 1.62 kg one, which it threw 77 mm up (fuzz seed 9947). Those points
            # are put down where they are instead, as a touch-down's are.
            fresh = np.zeros(len(beside), bool)
            fresh[on_table] = self._overlapping(start[on_table, 0, :2])
            lost = np.concatenate([lost, beside[fresh]])
            beside, anchors, start = beside[~fresh], anchors[~fresh], start[~fresh]
        if beside.size:
            ids = pool.acquire(beside.size * layers).reshape(-1, layers)
            pool.place(ids.reshape(-1), start.reshape(-1, 3))
            particles[beside] = ids
            born[beside] = True
        # Points in contacts where nothing was kept, and new points far from their
        # anchor's particle or that would start in an object beside it: the culling
        # puts down what is near, or else they are put down afresh.
        if lost.size and not self._cull:
            ids = pool.acquire(lost.size * layers).reshape(lost.size, -1)
            self._put_down(ids, current[lost])
            particles[lost] = ids
            born[lost] = True
        centroids = plan.motion.after
        points, smoothed = current, _Smoothed(centroids, np.zeros_like(centroids))
        if proxy.smoothing < 1.0:
            rows = plan.track_rows
            was = before.smoothed.centroids[rows]
            smoothed = _Smoothed(
                *_alpha_beta(
                    was,
                    before.smoothed.drift[rows],
                    centroids,
                    proxy.smoothing,
                    proxy.smoothing_gate,
                )
            )
            motion = _Motion(was, smoothed.centroids, rotation_kernel(was, smoothed.centroids))
            previous = Polylines(before.contours.points[plan.previous_rows], plan.predicted.bounds)
            points = _smooth_points(previous, motion, current, match.predecessor, proxy.smoothing)
        return _Tracks(
            plan.ids, Polylines(points, plan.current.bounds), particles, born, centroids,
            plan.travel, smoothed, before.hold[plan.track_rows],
        )  # fmt: skip

    def _touch_down(
        self, now: ContactSet, follows: NDArray[np.bool_], followed: _Tracks
    ) -> _Tracks:
        """All of the frame's tracks, in ascending id: the ``followed`` ones and a
        new one for every contact of the frame (``now``) that follows none (step 4),
        put down by ray casting unless the culling will do it."""
        new = np.flatnonzero(~follows)
        if new.size == 0:
            return followed
        points, bounds = gather(now.contours.points, now.contours.bounds, new)
        new_centroids = now.centroids[new]
        if self._cull:  # the culling puts down the points that are near an object
            particles = np.full((len(points), self._layers), -1, np.int64)
            born = np.zeros(len(points), bool)
        else:
            particles = self._world.pool.acquire(len(points) * self._layers)
            particles = particles.reshape(len(points), -1)
            self._put_down(particles, points)
            born = np.ones(len(points), bool)
        new_drift = np.full((new.size, 2), np.nan)
        new_hold = np.zeros((new.size, 2))
        if followed.ids.size == 0:
            return _Tracks(
                now.ids[new], Polylines(points, bounds), particles, born,
                new_centroids.copy(), np.zeros(new.size), _Smoothed(new_centroids, new_drift),
                new_hold,
            )  # fmt: skip
        # Both kinds together, then in the frame's (ascending id) order.
        sizes = np.concatenate([np.diff(followed.contours.bounds), np.diff(bounds)])
        order = np.argsort(np.concatenate([np.flatnonzero(follows), new]), kind="stable")
        rows, tracks_bounds = gather_rows(bounds_of(sizes), order)
        smoothed = followed.smoothed
        return _Tracks(
            now.ids.copy(),
            Polylines(np.concatenate([followed.contours.points, points])[rows], tracks_bounds),
            np.concatenate([followed.particles, particles])[rows],
            np.concatenate([followed.born, born])[rows],
            now.centroids.copy(),
            np.concatenate([followed.travel, np.zeros(new.size)])[order],
            _Smoothed(
                np.concatenate([smoothed.centroids, new_centroids])[order],
                np.concatenate([smoothed.drift, new_drift])[order],
            ),
            np.concatenate([followed.hold, new_hold])[order],
        )

    def _release(self, particles: NDArray[np.int64]) -> None:
        """Give back the particles of some rows of a track (culled rows have none)."""
        ids = particles.reshape(-1)
        self._world.pool.release(ids[ids >= 0])

    def _cull_far(
        self, tracks: _Tracks, depth: NDArray[np.float64], travel: NDArray[np.float64]
    ) -> None:
        """Give particles to the tracks' points near an object and take them from far
        ones, in place (their ``particles`` and ``born``).

        Args:
            tracks: this frame's tracks, K points.
            depth: each point's depth in the nearest footprint, metres (negative
                outside), (K,).
            travel: how far each point's contact moved in this frame at most, (K,).
        """
        particles, points, born = tracks.particles, tracks.contours.points, tracks.born
        world, margin = self._world, self._proxy.cull_margin
        linear = world.object_states().linear
        speeds = np.hypot(linear[:, 0], linear[:, 1])
        object_step = float(speeds.max(initial=0.0)) * self._dt
        reach = world.pool.radius + margin + 2.0 * travel + object_step
        bodiless = particles[:, 0] < 0
        near = np.flatnonzero(bodiless & (depth > -reach))
        far = np.flatnonzero(~bodiless & (depth < -(reach + margin)))
        if far.size:
            self._release(particles[far])
            particles[far] = -1
        if near.size:
            ids = world.pool.acquire(near.size * self._layers).reshape(near.size, -1)
            self._put_down(ids, points[near])
            particles[near] = ids
            born[near] = True

    def _overlapping(self, xy: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Which table-level particle centres (metres, world frame, (K, 2)) overlap a
        box's or a cylinder's footprint by more than :data:`MOST_OVERLAP` of their
        radius (a ball's overhang leaves room under it; a point deeper in a ball's
        disc than in a box it also lies in counts as the ball's)."""
        world = self._world
        owner, depth = world.footprint_depth(xy)
        # False wherever there is no object (owner -1, depth -inf).
        deep = depth > -(1.0 - MOST_OVERLAP) * world.pool.radius
        deep[deep] = ~world.balls()[owner[deep]]
        return deep

    def _put_down(self, ids: NDArray[np.int64], points: NDArray[np.float64]) -> None:
        """Place stacks where particles lowered onto their points come to rest
        (:meth:`~graspenv.physics.world.PhysicsWorld.put_down`)."""
        spots = self._world.put_down(points)
        self._world.pool.place(ids.reshape(-1), self._stack_positions(spots[:, :2], spots[:, 2]))

    def _stack_positions(
        self, points: NDArray[np.float64], bottom: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Sphere centres of stacks on points (metres, (K, 2)) whose lowest sphere's
        centre is at z ``bottom``."""
        k = len(points)
        xy = np.repeat(points, self._layers, axis=0)
        z = (bottom[:, None] + self._rise[None, :]).reshape(-1)
        return np.column_stack([xy, z]).reshape(k * self._layers, 3)

    def _limit_penetration(
        self,
        particles: NDArray[np.int64],
        targets: NDArray[np.float64],
        depth: NDArray[np.float64],
        sides: Sides,
    ) -> NDArray[np.intp]:
        """Lift onto the top face each particle (stack) whose point lies deeper than
        the margin inside an object's footprint while the particle is below the top
        (step 6 of the module docstring).

        Args:
            particles: particle ids, (K, L) stacks, bottom first.
            targets: the contour points, metres, world frame, (K, 2).
            depth: each point's depth in the footprint that holds it deepest, metres,
                negative outside, (K,).
            sides: the rows inside a footprint (:func:`~graspenv.proxies.side_hold.pressing`).

        Returns:
            The rows lifted.
        """
        world = self._world
        margin, radius = self._proxy.penetration_margin, world.pool.radius
        inside, at, normal = sides.rows, sides.at, sides.normal
        nothing = np.zeros(0, np.intp)
        if inside.size == 0:
            return nothing
        # A point may lie near a side other than the one its particle presses: a
        # finger sliding into a box along an edge keeps its points within the margin
        # of the edge's side while its particles, stopped at the face it entered by,
        # fall ever farther behind (seed 2575 of the long fuzz, at `fast`). Measured
        # from the side the particle is at, that point is deep too. The side is the
        # nearest footprint's side within two radii of the particle (none at a
        # disc's centre or by a leaning cylinder: there only the nearest side counts).
        # This measure allows a radius more than the margin: a particle pushed round
        # a small cylinder lies up to 1.5 mm farther behind its point than the point's
        # depth (7.5 mm on a 6 mm squeeze of a 3 cm cylinder), and lifting it lost
        # the grip (tests/proxies/test_penetration.py).
        behind = np.abs(np.einsum("ij,ij->i", at[:, :2] - targets[inside], normal)) - radius
        deep = (depth[inside] > margin) | (behind > margin + radius)
        if not np.any(deep):
            return nothing
        top = world.ray_heights(targets[inside[deep]]).height + radius
        # A particle already on the top face stays where the physics put it.
        below = at[deep, 2] < top - radius
        if not np.any(below):
            return nothing
        rows = inside[deep][below]
        world.pool.place(
            particles[rows].reshape(-1), self._stack_positions(targets[rows], top[below])
        )
        return rows


class _Motion(NamedTuple):
    """How each of several contacts moved rigidly in a frame: turned by ``turn``
    about its centroid ``before[k]`` and carried to ``after[k]`` (compiled code).

    Attributes:
        before: the centroids before, metres, world frame, shape (F, 2).
        after: the centroids after, metres, shape (F, 2).
        turn: the turn, the same for every contact, radians.
    """

    before: NDArray[np.float64]
    after: NDArray[np.float64]
    turn: float


class _Plan(NamedTuple):
    """What a frame's continuing contacts need, from :func:`_plan_follow` (which
    builds it in compiled code).

    Attributes:
        follows: which contacts of the frame continue a track, shape (C,).
        ended_rows: rows of the tracks no contact continues, (E,).
        contacts: the following contacts (frame indices), (F,).
        ids: their ids, (F,).
        track_rows: the tracks they continue, (F,).
        motion: how they moved since the last frame: their centroids then and now
            (metres, (F, 2)) and the hand's turn (radians).
        previous_rows: the rows of their tracks' last points, (P,).
        predicted: where those points should be now, metres, one set per contact.
        current: the current contours (where the predicted points land, resampled
            from the predicted first points, or the tracker's), metres, one set per
            contact.
        travel: how far any point of each moved this frame at most, metres, (F,).
    """

    follows: NDArray[np.bool_]
    ended_rows: NDArray[np.intp]
    contacts: NDArray[np.intp]
    ids: NDArray[np.int64]
    track_rows: NDArray[np.intp]
    motion: _Motion
    previous_rows: NDArray[np.intp]
    predicted: Polylines
    current: Polylines
    travel: NDArray[np.float64]


@njit
def _plan_follow(
    before: _Tracks,
    frame: ContactSet,
    track_hand_rotation: bool,
    predicted_resampling: bool,
    follow_points: bool,
    spacing: float,
) -> _Plan:
    """Steps 2 and 3 of the module docstring up to the matching, from the tracks of
    the last frame (``before``) to the contacts of this one (``frame``)."""
    track_ids, track_bounds = before.ids, before.contours.bounds
    ids = frame.ids
    count = len(ids)
    # Which track each contact continues: the same id, not new this frame.
    follows = np.zeros(count, np.bool_)
    track = np.full(count, -1, np.intp)
    ended = np.ones(len(track_ids), np.bool_)
    for c in range(count):
        t = np.searchsorted(track_ids, ids[c])
        if not frame.is_new[c] and t < len(track_ids) and track_ids[t] == ids[c]:
            follows[c] = True
            track[c] = t
            ended[t] = False
    contacts = np.flatnonzero(follows)
    continued = track[contacts]
    ended_rows, _ = gather_rows(track_bounds, np.flatnonzero(ended))
    previous_rows, previous_bounds = gather_rows(track_bounds, continued)
    after = frame.centroids[contacts]
    motion = _Motion(before.centroids[continued], after, 0.0)
    if track_hand_rotation and len(contacts) >= 2:
        motion = _Motion(motion.before, after, rotation_kernel(motion.before, after))
    # Where last frame's points should be now: carried by their contact's centroid and
    # turned by the hand's turn (0 when that estimate is off).
    predicted = Polylines(before.contours.points[previous_rows], previous_bounds)
    if track_hand_rotation or predicted_resampling:
        predicted = Polylines(_carry(predicted, motion), previous_bounds)
    if predicted_resampling:
        outlines = Polylines(*gather(frame.outlines.points, frame.outlines.bounds, contacts))
        if follow_points:
            current = follow_kernel(outlines, spacing, predicted)
        else:
            current = resample_kernel(outlines, spacing, predicted.points[previous_bounds[:-1]])
    else:
        contours, contour_bounds = gather(frame.contours.points, frame.contours.bounds, contacts)
        current = Polylines(contours, contour_bounds)
    # The farthest any point of a contact moved: its centroid's step plus the turn's
    # arc at its farthest point.
    reach = reach_from(after, current)
    travel = np.empty(len(contacts))
    for k in range(len(contacts)):
        step = np.hypot(after[k, 0] - motion.before[k, 0], after[k, 1] - motion.before[k, 1])
        travel[k] = step + abs(motion.turn) * reach[k]
    return _Plan(
        follows, ended_rows, contacts, ids[contacts], continued, motion, previous_rows,
        predicted, current, travel,
    )  # fmt: skip


@njit
def _inherit(
    previous: NDArray[np.int64], predecessor: NDArray[np.intp], anchor: NDArray[np.intp]
) -> tuple[NDArray[np.int64], NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
    """The particle stacks current points inherit (step 3 of the module docstring).

    Returns:
        (particles, beside, anchors, lost): each current point's predecessor's stack,
        or -1 rows, (Q, L); the new points that start beside an anchor that has a
        particle, and those anchors (a culled anchor has none to start beside: its
        point stays culled until the culling gives it one); and the new points in
        contacts where nothing was kept.
    """
    particles = np.full((len(predecessor), previous.shape[1]), -1, np.int64)
    beside = np.zeros(len(predecessor), np.bool_)
    lost = np.zeros(len(predecessor), np.bool_)
    for j in range(len(predecessor)):
        if predecessor[j] >= 0:
            particles[j] = previous[predecessor[j]]
    for j in range(len(predecessor)):
        if predecessor[j] >= 0:
            continue
        if anchor[j] < 0:
            lost[j] = True
        elif particles[anchor[j], 0] >= 0:
            beside[j] = True
    rows = np.flatnonzero(beside)
    return particles, rows, anchor[rows], np.flatnonzero(lost)


@njit
def _alpha_beta(
    position: NDArray[np.float64],
    velocity: NDArray[np.float64],
    measured: NDArray[np.float64],
    alpha: float,
    gate: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """One step of an alpha-beta filter on each row (``proxy.smoothing``).

    A row is predicted a frame's step ahead at its velocity and moved the share
    ``alpha`` of the way to its measurement; the velocity takes ``beta = alpha² /
    (2 - alpha)`` of the surprise (Benedict and Bordner's pairing). A motion at
    constant velocity is followed without lag, and the measurement's frame-to-frame
    noise is damped. A row seen for the second time (velocity NaN) or surprised by
    more than ``gate`` metres (a strike, a sudden start) takes its measurement as it
    is, and the step that got it there as its velocity.
    """
    beta = alpha * alpha / (2.0 - alpha)
    smoothed = np.empty_like(measured)
    rate = np.empty_like(measured)
    for k in range(len(measured)):
        px = position[k, 0] + velocity[k, 0]
        py = position[k, 1] + velocity[k, 1]
        sx, sy = measured[k, 0] - px, measured[k, 1] - py
        if not np.isfinite(px + py) or np.hypot(sx, sy) > gate:
            smoothed[k] = measured[k]
            rate[k, 0] = measured[k, 0] - position[k, 0]
            rate[k, 1] = measured[k, 1] - position[k, 1]
            continue
        smoothed[k, 0] = px + alpha * sx
        smoothed[k, 1] = py + alpha * sy
        rate[k, 0] = velocity[k, 0] + beta * sx
        rate[k, 1] = velocity[k, 1] + beta * sy
    return smoothed, rate


@njit
def _carry(points: Polylines, motion: _Motion) -> NDArray[np.float64]:
    """Each contact's points (set k of ``points``) moved rigidly with it (``motion``)."""
    carried = np.empty_like(points.points)
    cos, sin = np.cos(motion.turn), np.sin(motion.turn)
    before, after = motion.before, motion.after
    for k in range(len(points.bounds) - 1):
        for i in range(points.bounds[k], points.bounds[k + 1]):
            x = points.points[i, 0] - before[k, 0]
            y = points.points[i, 1] - before[k, 1]
            carried[i, 0] = (x * cos - y * sin) + after[k, 0]
            carried[i, 1] = (x * sin + y * cos) + after[k, 1]
    return carried


@njit
def _smooth_points(
    previous: Polylines,
    motion: _Motion,
    measured: NDArray[np.float64],
    predecessor: NDArray[np.intp],
    alpha: float,
) -> NDArray[np.float64]:
    """Each followed point carried rigidly by its contact's smoothed motion, then
    moved the share ``alpha`` of the way to where it is measured: the contact's shape
    follows the contour slowly, its motion at once. New points stay where they are
    measured."""
    carried = _carry(previous, motion)
    points = measured.copy()
    for j in range(len(predecessor)):
        p = predecessor[j]
        if p >= 0:
            points[j, 0] = carried[p, 0] + alpha * (measured[j, 0] - carried[p, 0])
            points[j, 1] = carried[p, 1] + alpha * (measured[j, 1] - carried[p, 1])
    return points
