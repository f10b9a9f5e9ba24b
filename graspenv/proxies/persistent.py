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
   hand's turn. With ``proxy.predicted_resampling`` the current contour is resampled
   starting from the predicted first point, so points do not jitter along the
   contour and pull against each other. The windowed sum-of-squared-distances match
   (:func:`graspenv.contacts.matching.correspond_batch`: every continuing contact
   in one call) then gives each current point its predecessor, whose particle it
   reuses; current points without one get a new particle put down beside the first
   neighbouring point that is not new; previous points whose successor did not name
   them release theirs.
4. *New contact.* One particle (stack) per contour point, put down by ray casting on
   whatever is there (table or object top).
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
   pressing the side ever harder.

With ``track_hand_rotation`` and ``predicted_resampling`` both off this is the
paper's plain form: the raw previous contour matched against the tracker's contour
(with either on, the predicted points are matched).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from graspenv.config import ProxyConfig
from graspenv.contacts.matching import correspond_batch
from graspenv.contacts.resample import bounds_of, owners_of, resample_closed_batch
from graspenv.contacts.tracking import Contact, ContactFrame
from graspenv.geometry import rotate
from graspenv.physics.world import PhysicsWorld
from graspenv.proxies.base import ProxyCommand, rigid_rotation

__all__ = ["PersistentProxies"]


@dataclass
class _Track:
    """One contact's contour points and the particle stacks that follow them.

    Attributes:
        points: contour points of the last frame, metres, world frame, shape (N, 2).
        particles: pool ids, shape (N, L), column 0 at the bottom; a row of -1 for a
            culled point (no particle).
        centroid: the contact's centroid in the last frame, metres, shape (2,).
        travel: how far any of its points moved in the last frame at most, metres.
        born: which points got their particle in the last frame, shape (N,).
    """

    points: NDArray[np.float64]
    particles: NDArray[np.int64]
    centroid: NDArray[np.float64]
    travel: float = 0.0
    born: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, bool))


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
        self._dt = dt
        self._layers = layers
        self._cull = proxy.cull
        self._rise = proxy.stack_spacing * np.arange(self._layers)
        self._tracks: dict[int, _Track] = {}
        self.hand_turn = 0.0
        """The hand's estimated turn in the last frame, radians."""

    def reset(self) -> None:
        self._tracks = {}
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
        return {
            cid: track.particles[track.particles[:, 0] >= 0].reshape(-1)
            for cid, track in self._tracks.items()
        }

    def update(self, frame: ContactFrame, mask: NDArray[np.uint8]) -> ProxyCommand:
        """Bookkeeping for one frame; ``mask`` is not needed by this method."""
        del mask
        for contact_id in frame.removed:
            track = self._tracks.pop(contact_id, None)
            if track is not None:
                self._release(track.particles)

        continuing = [c for c in frame.continuing if c.id in self._tracks]
        turn = 0.0
        if self._proxy.track_hand_rotation and len(continuing) >= 2:
            before = np.array([self._tracks[c.id].centroid for c in continuing])
            after = np.array([c.centroid for c in continuing])
            turn = rigid_rotation(before, after)
        self.hand_turn = turn

        followed = self._follow([(self._tracks[c.id], c) for c in continuing], turn)
        tracks: dict[int, _Track] = {}
        spins: list[NDArray[np.float64]] = []
        for contact in frame.contacts:
            old = self._tracks.pop(contact.id, None)
            track = followed.get(contact.id)
            if track is not None:
                tracks[contact.id] = track
                spins.append(np.full(len(track.points), turn / self._dt))
            else:
                if old is not None:  # a reused id the tracker calls new: start afresh
                    self._release(old.particles)
                tracks[contact.id] = self._touch_down(contact)
                spins.append(np.zeros(len(tracks[contact.id].points)))
        for leftover in self._tracks.values():  # merged away without being listed
            self._release(leftover.particles)
        self._tracks = tracks

        if not tracks:
            empty = np.zeros((0, self._layers), np.int64)
            return ProxyCommand(empty, np.zeros((0, 2)), np.zeros(0))
        particles = np.concatenate([t.particles for t in tracks.values()])
        targets = np.concatenate([t.points for t in tracks.values()])
        spin = np.concatenate(spins)
        born = np.concatenate([t.born for t in tracks.values()])
        if self._cull or self._proxy.penetration_limit:
            owner, depth = self._world.footprint_depth(targets)
        if self._cull:
            travel = np.repeat(
                [t.travel for t in tracks.values()], [len(t.points) for t in tracks.values()]
            )
            self._cull_far(particles, targets, depth, travel, born)
            start = 0
            for track in tracks.values():  # the tracks keep the culling's changes
                track.particles = particles[start : start + len(track.points)]
                start += len(track.points)
            # The command gets the embodied rows as arrays of its own (the tracks
            # keep views of ``particles``).
            embodied = particles[:, 0] >= 0
            culled = int(np.count_nonzero(~embodied))
            particles, targets, spin = particles[embodied], targets[embodied], spin[embodied]
            born = born[embodied]
            owner, depth = owner[embodied], depth[embodied]
        else:
            culled = 0
        if self._proxy.penetration_limit:
            self._limit_penetration(particles, targets, owner, depth)
        return ProxyCommand(particles, targets, spin, culled=culled, born=born)

    # -- stages ------------------------------------------------------------------------

    def _follow(self, pairs: list[tuple[_Track, Contact]], turn: float) -> dict[int, _Track]:
        """Continue every continuing contact's track at once (step 3 of the module
        docstring): one resampling and one matching call for all of them."""
        if not pairs:
            return {}
        proxy, layers = self._proxy, self._layers
        before = [track for track, _ in pairs]
        contacts = [contact for _, contact in pairs]
        previous_bounds = bounds_of([len(t.points) for t in before])
        points = np.concatenate([t.points for t in before])
        centroid_before = np.array([t.centroid for t in before])
        centroid_after = np.array([c.centroid for c in contacts])
        if proxy.track_hand_rotation or proxy.predicted_resampling:
            # Where last frame's points should be now: carried by their contact's
            # centroid and turned by the hand's turn (0 when that estimate is off).
            sizes = np.diff(previous_bounds)
            predicted = rotate(points - np.repeat(centroid_before, sizes, axis=0), turn)
            predicted += np.repeat(centroid_after, sizes, axis=0)
        else:
            predicted = points
        if proxy.predicted_resampling:
            outlines = np.concatenate([c.outline for c in contacts])
            current, current_bounds = resample_closed_batch(
                outlines,
                bounds_of([len(c.outline) for c in contacts]),
                self._spacing,
                predicted[previous_bounds[:-1]],
            )
        else:
            current = np.concatenate([c.contour for c in contacts])
            current_bounds = bounds_of([len(c.contour) for c in contacts])
        match = correspond_batch(
            predicted,
            previous_bounds,
            current,
            current_bounds,
            proxy.window,
            proxy.matcher,
            proxy.search,
        )

        pool = self._world.pool
        previous_particles = np.concatenate([t.particles for t in before])
        self._release(previous_particles[~match.kept])
        particles = np.empty((len(current), layers), np.int64)
        reused = match.predecessor >= 0
        particles[reused] = previous_particles[match.predecessor[reused]]
        fresh = np.flatnonzero(~reused)
        born = np.zeros(len(current), bool)
        if fresh.size:
            anchors = match.anchor[fresh]
            beside = fresh[anchors >= 0]
            if beside.size:
                anchor_particles = particles[anchors[anchors >= 0]]
                # A culled anchor has no particle to start beside: the point stays
                # culled until the culling gives it one.
                placed = anchor_particles[:, 0] >= 0
                ids = pool.acquire(int(placed.sum()) * layers).reshape(-1, layers)
                pool.place(ids.reshape(-1), pool.positions(anchor_particles[placed].reshape(-1)))
                particles[beside[placed]] = ids
                particles[beside[~placed]] = -1
                born[beside[placed]] = True
            lost = fresh[anchors < 0]  # in contacts where nothing was kept
            if lost.size and self._cull:  # the culling puts down what is near
                particles[lost] = -1
            elif lost.size:  # put those contours down afresh
                ids = pool.acquire(lost.size * layers).reshape(lost.size, -1)
                self._put_down(ids, current[lost])
                particles[lost] = ids
                born[lost] = True
        # The farthest any point of a contact moved: its centroid's step plus the
        # turn's arc at its farthest point.
        owner, _ = owners_of(current_bounds)
        offset = current - centroid_after[owner]
        reach = np.maximum.reduceat(np.hypot(offset[:, 0], offset[:, 1]), current_bounds[:-1])
        step = centroid_after - centroid_before
        travel = np.hypot(step[:, 0], step[:, 1]) + abs(turn) * reach
        followed = {}
        for i, contact in enumerate(contacts):
            lo, hi = current_bounds[i], current_bounds[i + 1]
            followed[contact.id] = _Track(
                current[lo:hi],
                particles[lo:hi],
                contact.centroid.copy(),
                float(travel[i]),
                born[lo:hi],
            )
        return followed

    def _touch_down(self, contact: Contact) -> _Track:
        points = np.array(contact.contour)
        if self._cull:  # the culling puts down the points that are near an object
            culled = np.full((len(points), self._layers), -1)
            return _Track(points, culled, contact.centroid.copy(), born=np.zeros(len(points), bool))
        ids = self._world.pool.acquire(len(points) * self._layers).reshape(len(points), -1)
        self._put_down(ids, points)
        return _Track(points, ids, contact.centroid.copy(), born=np.ones(len(points), bool))

    def _release(self, particles: NDArray[np.int64]) -> None:
        """Give back the particles of some rows of a track (culled rows have none)."""
        ids = particles.reshape(-1)
        self._world.pool.release(ids[ids >= 0])

    def _cull_far(
        self,
        particles: NDArray[np.int64],
        points: NDArray[np.float64],
        depth: NDArray[np.float64],
        travel: NDArray[np.float64],
        born: NDArray[np.bool_],
    ) -> None:
        """Give particles to points near an object and take them from far ones, in place.

        Args:
            particles: (K, L) pool ids, -1 rows for culled points; updated.
            points: the contour points, metres, (K, 2).
            depth: each point's depth in the nearest footprint, metres (negative
                outside), (K,).
            travel: how far each point's contact moved in this frame at most, (K,).
            born: which points got their particle this frame, (K,); updated.
        """
        world, margin = self._world, self._proxy.cull_margin
        speeds = [np.hypot(*world.object_velocity(name)[0][:2]) for name in world.object_names]
        object_step = float(max(speeds, default=0.0)) * self._dt
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

    def _put_down(self, ids: NDArray[np.int64], points: NDArray[np.float64]) -> None:
        """Place stacks on whatever lies under their points' discs (rays from above)."""
        bottom = self._world.rest_heights(points) + self._world.pool.radius
        self._world.pool.place(ids.reshape(-1), self._stack_positions(points, bottom))

    def _stack_positions(
        self, points: NDArray[np.float64], bottom: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Sphere centres of stacks on points (metres, (K, 2)) with bottoms at z."""
        k = len(points)
        xy = np.repeat(points, self._layers, axis=0)
        z = (bottom[:, None] + self._rise[None, :]).reshape(-1)
        return np.column_stack([xy, z]).reshape(k * self._layers, 3)

    def _limit_penetration(
        self,
        particles: NDArray[np.int64],
        targets: NDArray[np.float64],
        owner: NDArray[np.int64],
        depth: NDArray[np.float64],
    ) -> None:
        world = self._world
        deep = np.flatnonzero((owner >= 0) & (depth > self._proxy.penetration_margin))
        if deep.size == 0:
            return
        bottom_ids = particles[deep, 0]
        z = world.pool.positions(bottom_ids)[:, 2]
        top = world.ray_heights(targets[deep]).height + world.pool.radius
        # A particle already on the top face stays where the physics put it.
        below = z < top - world.pool.radius
        if not np.any(below):
            return
        rows = deep[below]
        world.pool.place(
            particles[rows].reshape(-1), self._stack_positions(targets[rows], top[below])
        )
