"""The PyBullet scene: table, objects, particle pool and the per-frame control step.

:class:`PhysicsWorld` owns one PyBullet DIRECT client and is the only door to it:
numpy arrays in, numpy arrays out, object names instead of Bullet ids, particle ids
from :class:`~graspenv.physics.pool.ParticlePool`.

World frame: origin at the table centre, x right, y away from the viewer, z up from
the table top; SI units (m, kg, s, N, rad); quaternions are (x, y, z, w).

The world is composed of the pieces that do the work, each in its own module:
:mod:`~graspenv.physics.bodies` builds the table, floor and objects (and says which
Bullet settings are applied, and why); :class:`~graspenv.physics.pool.ParticlePool`
and :class:`~graspenv.physics.rigid.RigidBodies` hold the proxies;
:class:`~graspenv.physics.rays.RayCaster` casts the rays under points and
particles; :class:`~graspenv.physics.stepping.FrameStepper` runs a frame's
sub-steps and the pushes on objects; :mod:`~graspenv.physics.view` gives the bodies
their colours and the particles their cheap mesh, and draws the 3-D view;
:mod:`~graspenv.physics.reports` holds what the queries return. This module keeps
the one public class, the objects' states (read, and set by teleporting), where new
particles are put down (:meth:`PhysicsWorld.put_down`) and the per-frame particle
drive (:meth:`PhysicsWorld.step_frame`).

The time step is ``1 / (surface.fps · SceneConfig.sub_steps)``, sub-stepped in Python:
the particle force is recomputed before every ``stepSimulation``. Bullet's own
``numSubSteps`` would reapply the first sub-step's force on every internal step.
A frame in which an object's point or a particle would move more than
``physics.substep_travel`` a step gets more, shorter steps (up to
``physics.max_substeps``; :func:`~graspenv.physics.control.frame_substeps`).

One world serves many episodes: :meth:`reset` puts the same scene back (cheap, no
body is created), :meth:`rebuild` replaces it by another (``resetSimulation`` and
everything built again in a fresh world's order, so the results are a fresh
world's bit for bit). Disturbances (:meth:`apply_force`) and initial motions
(:meth:`set_object_state`) act on objects by name; :meth:`render` draws a 3-D view.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
from typing import TypedDict

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from graspenv.config import SceneConfig
from graspenv.geometry import SHAPE_CODES, footprint_depths, footprint_sides
from graspenv.physics.bodies import EDGE_RADIUS, build_scene, place_objects
from graspenv.physics.control import REST_TOLERANCE, ParticleDrive, SupportPlanes
from graspenv.physics.pool import ParticlePool
from graspenv.physics.rays import SUPPORT_CLEARANCE, RayCaster
from graspenv.physics.reports import (
    ContactReport,
    FootprintHits,
    ObjectStates,
    RayHits,
    read_contact_report,
)
from graspenv.physics.rigid import RigidBodies
from graspenv.physics.stepping import FrameStepper
from graspenv.physics.view import render_view
from graspenv.resources import Closeable

__all__ = [
    "EDGE_RADIUS",
    "ContactReport",
    "FootprintHits",
    "ObjectStateChange",
    "ObjectStates",
    "PhysicsWorld",
    "RayHits",
]


class ObjectStateChange(TypedDict, total=False):
    """The keywords of :meth:`PhysicsWorld.set_object_state`, for callers that pass
    them on (``Simulation.set_object_state``); each is described there."""

    position: ArrayLike | None
    yaw: float | None
    linear_velocity: ArrayLike | None
    angular_velocity: ArrayLike | None
    rolling: bool
    orientation: ArrayLike | None


class PhysicsWorld(Closeable):
    """A table, its objects and a pool of particle proxies in a PyBullet DIRECT client.

    Args:
        scene: the scene configuration; ``surface`` sets the table size and the frame
            rate, ``objects`` the objects, ``proxy`` the particles and ``physics`` the
            Bullet settings.

    Attributes:
        scene: the configuration it was built from (or last rebuilt to).
        pool: the particle bodies; ids from it go to :meth:`step_frame`.
        frame_dt: seconds per camera frame, ``1 / surface.fps``.
        substeps: physics steps per frame (a fast frame gets more, see
            :attr:`last_substeps`).
        substep_dt: seconds per physics step at ``substeps``.
        control_dt: Δt of the particle control law, seconds (``physics.control_time``,
            or the sub-step if that is longer).

    Example:
        >>> with PhysicsWorld(SceneConfig()) as world:  # doctest: +SKIP
        ...     ids = world.pool.acquire(2)
        ...     world.pool.place(ids, [[0.05, 0.0, 0.002], [0.06, 0.0, 0.002]])
        ...     world.step_frame(ids, [[0.04, 0.0], [0.05, 0.0]])
    """

    def __init__(self, scene: SceneConfig) -> None:
        self._client: int | None = pb.connect(pb.DIRECT)
        self._build(scene)

    def _build(self, scene: SceneConfig) -> None:
        """Build the whole scene into an empty client: every Bullet command in order.

        A fresh world and :meth:`rebuild` both come through here, so both send
        Bullet the same commands in the same order (and get the same body ids).
        """
        self.scene = scene
        self.frame_dt = 1.0 / scene.surface.fps
        # More where particles outweigh what a tall object feels (SceneConfig.sub_steps).
        physics = dataclasses.replace(scene.physics, substeps=scene.sub_steps)
        self.substeps = physics.substeps
        self.substep_dt = self.frame_dt / self.substeps
        # Below the sub-step the control law would be unstable.
        self.control_dt = max(scene.physics.control_time, self.substep_dt)
        self._bodies = build_scene(self.client, scene, self.substep_dt)
        self._object_bodies = self._bodies.objects
        self._rays = RayCaster(self.client, self._bodies, scene.proxy.particle_radius)
        # The particles' mass, press and force clamp, scaled to the lightest object.
        self._particle_proxy, self._particle_physics = scene.particle_settings
        self.pool = ParticlePool(self.client, self._particle_proxy, self._particle_physics)
        self.rigid_proxies = RigidBodies(self.client, self._particle_proxy, self._particle_physics)
        self._stepper = FrameStepper(self.client, self._bodies, self.pool, physics, self.substep_dt)
        self._states: ObjectStates | None = None
        self._states_step = -1
        self._place_objects()

    @property
    def bullet_seconds(self) -> float:
        """Wall seconds spent inside Bullet's ``stepSimulation`` by the last frame."""
        return self._stepper.bullet_seconds

    @property
    def last_substeps(self) -> int:
        """Physics steps the last frame took (``physics.substeps`` or more)."""
        return self._stepper.last_substeps

    # -- lifetime --------------------------------------------------------------------

    @property
    def client(self) -> int:
        """The PyBullet client id (for code inside ``graspenv.physics``)."""
        if self._client is None:
            raise RuntimeError("this PhysicsWorld is closed")
        return self._client

    def close(self) -> None:
        """Disconnect the PyBullet client; calling it again does nothing."""
        if self._client is not None:
            pb.disconnect(physicsClientId=self._client)
            self._client = None

    def __del__(self) -> None:
        # A forgotten world must not keep its client (and its memory) alive; at
        # interpreter exit pybullet may already be gone, which is fine.
        if getattr(self, "_client", None) is not None:
            with contextlib.suppress(Exception):
                self.close()

    def reset(self) -> None:
        """Restore the initial scene: objects back in place at rest, particles parked.

        No body is created or destroyed; the pool keeps its size and hands out the
        same ids again, so it is cheap. Body ids are unchanged, so the
        sorted pairs (``deterministicOverlappingPairs``) and the solver order are a
        fresh world's, and parked particles are asleep and collide with nothing;
        objects come back as in a fresh world (see :meth:`_place_objects`, which a
        fresh world runs too). Pending forces are dropped.

        The results after a reset match a fresh world's bit for bit in the cases
        tested (resting objects of any yaw; particles squeezing an unturned box),
        but not always: particles pushing a box with a non-zero yaw have been seen
        to differ in the last bits from the first frame on (cause not found; the
        object state itself is restored). Where bit-identity must be guaranteed,
        use :meth:`rebuild`, which empties Bullet and builds the scene anew.
        """
        self._stepper.drop_pending()
        self.pool.release_all()
        self.rigid_proxies.clear()
        self._place_objects()

    def _place_objects(self) -> None:
        """Put every object at its initial pose, at rest, with no contact history
        (:func:`~graspenv.physics.bodies.place_objects`, one physics step of the
        configured length, as in a fresh world)."""
        self._stepper.use_configured_step()
        place_objects(self.client, self.scene, self._object_bodies)
        self.pool.physics_steps += 1
        self._states = None

    def rebuild(self, scene: SceneConfig) -> None:
        """Replace the whole scene by another one, as if this world were new.

        Objects may differ in number, shape, size, mass and friction, and the
        surface, proxy and physics settings may change too. Bullet's world is emptied
        (``resetSimulation``) and everything is built again in the order
        :class:`PhysicsWorld` builds it, so body ids, broadphase pair order and every
        later result are bit-identical to those of ``PhysicsWorld(scene)`` given the
        same commands, by construction. It costs about as much as building the
        particle pool's first batch (``physics.pool_batch`` bodies); :meth:`reset`
        puts the same scene back for less, but without that guarantee.

        Every particle id and rigid proxy handle handed out before is invalid
        afterwards (:attr:`pool` and :attr:`rigid_proxies` are new objects), and
        pending forces are dropped.

        Args:
            scene: the new scene configuration.

        Raises:
            RuntimeError: the world is closed.
        """
        pb.resetSimulation(physicsClientId=self.client)
        self._build(scene)

    @property
    def num_bodies(self) -> int:
        """Number of Bullet bodies (table, floor, objects, pooled particles)."""
        # The client learns of batch-created bodies only from a sync (ParticlePool).
        pb.syncBodyInfo(physicsClientId=self.client)
        return int(pb.getNumBodies(physicsClientId=self.client))

    # -- objects ---------------------------------------------------------------------

    @property
    def object_names(self) -> tuple[str, ...]:
        """Names of the objects, in ``scene.objects`` order (their indices)."""
        return tuple(o.name for o in self.scene.objects)

    def object_index(self, name: str) -> int:
        """Index of an object in :attr:`object_names`.

        Raises:
            KeyError: no object has that name.
        """
        try:
            return self.object_names.index(name)
        except ValueError:
            raise KeyError(
                f"no object named {name!r}; objects are {list(self.object_names)}"
            ) from None

    def object_pose(self, name: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Pose of an object.

        Returns:
            (position, quaternion): centre of mass, metres, world frame, shape (3,);
            orientation as (x, y, z, w), shape (4,).
        """
        states = self.object_states()
        index = self.object_index(name)
        return states.position[index].copy(), states.quaternion[index].copy()

    def object_velocity(self, name: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Velocity of an object.

        Returns:
            (linear, angular): m/s and rad/s, world frame, shapes (3,) and (3,).
        """
        states = self.object_states()
        index = self.object_index(name)
        return states.linear[index].copy(), states.angular[index].copy()

    def object_states(self) -> ObjectStates:
        """Every object's pose and velocity now, read from Bullet once per physics step
        (and after :meth:`set_object_state`), so that the stages of a frame share one
        read. Read-only arrays, rows in :attr:`object_names` order."""
        step = self.pool.physics_steps
        if self._states is None or self._states_step != step:
            self._states = ObjectStates.read(self.client, self._object_bodies)
            self._states_step = step
        return self._states

    def apply_force(self, name: str, force: ArrayLike, height: float | None = None) -> None:
        """Push an object throughout the next camera frame, at its centre of mass or
        at a height.

        The force acts on every physics sub-step of the next :meth:`step_frame` or
        :meth:`step_bodies` call, i.e. for one camera frame (``frame_dt`` seconds),
        and is then forgotten: call it again before each frame for a lasting push.
        (Bullet clears external forces after every ``stepSimulation``, so the world
        keeps it and re-applies it before each of its own sub-steps.) Calls for the
        same object before one frame add up. :meth:`reset` and :meth:`rebuild` drop
        pending forces.

        Args:
            name: object name.
            force: newtons, world frame, shape (3,).
            height: the push's line of action passes through the point this far above
                the table (metres) over the object's centre: the force at the centre
                of mass plus the torque of that offset, taken at the object's pose now.
                ``None`` pushes at the centre of mass (no torque). A push at the height
                of the fingers' contacts cannot tip a squeezed object over them.

        Raises:
            KeyError: no object has that name.
            ValueError: the force is not three finite numbers, or the height is not
                finite.
        """
        index = self.object_index(name)
        push = np.asarray(force, dtype=float)
        if push.shape != (3,) or not np.all(np.isfinite(push)):
            raise ValueError(f"force for {name!r} must be 3 finite numbers (N), got {force!r}")
        self._stepper.push(index, push)
        if height is None:
            return
        if not math.isfinite(height):
            raise ValueError(f"height for {name!r} must be finite (metres), got {height!r}")
        arm = np.array([0.0, 0.0, float(height) - self.object_states().position[index, 2]])
        self._stepper.twist(index, np.cross(arm, push))

    def set_object_state(
        self,
        name: str,
        position: ArrayLike | None = None,
        yaw: float | None = None,
        linear_velocity: ArrayLike | None = None,
        angular_velocity: ArrayLike | None = None,
        *,
        rolling: bool = False,
        orientation: ArrayLike | None = None,
    ) -> None:
        """Move an object and/or set its velocity now (e.g. at the start of an episode).

        Whatever is ``None`` keeps its current value. The object is teleported: do it
        while no finger touches the object (contacts already pressing into it would
        push it out hard in the next step).

        Args:
            name: object name.
            position: centre of mass, metres, world frame, shape (3,); or (x, y),
                shape (2,), to rest it on the table (z = half its height).
            yaw: rotation about +z, radians; the object is stood upright with this
                yaw (any tilt is dropped).
            orientation: instead of ``yaw``, any orientation as a quaternion
                (x, y, z, w), normalised here, shape (4,) (a tipped object; give its
                ``position`` as (x, y, z), since (x, y) rests an upright one).
            linear_velocity: m/s, world frame, shape (3,).
            angular_velocity: rad/s, world frame, shape (3,).
            rolling: for a sphere on the table: set the angular velocity so that it
                rolls without slipping at its linear velocity (ω = ẑ × v / r, the
                given or current ``linear_velocity``); ``angular_velocity`` must then
                be ``None``. A sphere given only a linear velocity slides until table
                friction has spun it up, losing speed.

        Raises:
            KeyError: no object has that name.
            ValueError: a value has the wrong shape or is not finite, or ``rolling``
                is asked of something that is not a sphere or together with
                ``angular_velocity``.
        """
        index = self.object_index(name)
        body, config = self._object_bodies[index], self.scene.objects[index]
        # Check everything before changing anything: a bad value leaves the object be.
        given_position = (
            None if position is None else _finite(name, "position", position, ((2,), (3,)))
        )
        if yaw is not None and not math.isfinite(yaw):
            raise ValueError(f"yaw for {name!r} must be finite (radians), got {yaw!r}")
        given_orientation = (
            None if orientation is None else _finite(name, "orientation", orientation, ((4,),))
        )
        if given_orientation is not None:
            if yaw is not None:
                raise ValueError("pass either yaw or orientation, not both")
            length = float(np.linalg.norm(given_orientation))
            if length == 0.0:
                raise ValueError(f"orientation for {name!r} must be a non-zero quaternion")
            given_orientation /= length
        given_linear = (
            None
            if linear_velocity is None
            else _finite(name, "linear_velocity", linear_velocity, ((3,),))
        )
        given_angular = (
            None
            if angular_velocity is None
            else _finite(name, "angular_velocity", angular_velocity, ((3,),))
        )
        if rolling:
            if config.shape != "sphere":
                raise ValueError(f"rolling needs a sphere; {name!r} is a {config.shape}")
            if angular_velocity is not None:
                raise ValueError("pass either rolling=True or angular_velocity, not both")
        moves = position is not None or yaw is not None or given_orientation is not None
        if not moves and given_linear is None and given_angular is None and not rolling:
            return
        now_linear, now_angular = pb.getBaseVelocity(body, physicsClientId=self.client)
        linear = np.array(now_linear) if given_linear is None else given_linear
        angular = np.array(now_angular) if given_angular is None else given_angular
        if rolling:
            radius = config.size[0]
            # No slip where the sphere touches the table: v + ω × (−r ẑ) = 0.
            angular = np.array([-linear[1] / radius, linear[0] / radius, 0.0])
        if moves:
            now_position, quaternion = pb.getBasePositionAndOrientation(
                body, physicsClientId=self.client
            )
            xyz = np.array(now_position)
            if given_position is not None:
                xyz = given_position
                if xyz.shape == (2,):
                    xyz = np.append(xyz, config.height / 2)
            if yaw is not None:
                quaternion = pb.getQuaternionFromEuler((0.0, 0.0, float(yaw)))
            elif given_orientation is not None:
                quaternion = tuple(given_orientation.tolist())
            # This also zeroes the body's velocity, which is set again below.
            pb.resetBasePositionAndOrientation(
                body, xyz.tolist(), quaternion, physicsClientId=self.client
            )
        pb.resetBaseVelocity(body, linear.tolist(), angular.tolist(), physicsClientId=self.client)
        self._states = None

    # -- pictures --------------------------------------------------------------------

    def render(
        self,
        width: int,
        height: int,
        target: ArrayLike,
        distance: float,
        yaw_deg: float,
        pitch_deg: float,
        fov: float = 50.0,
    ) -> NDArray[np.uint8]:
        """A 3-D view of the table, the objects and the active particles.

        Software rendering (Bullet's TinyRenderer): headless, no GUI or EGL (its
        cost grows with the pooled particles). Parked
        particles lie beyond the far clipping plane and never show.

        Args:
            width: image width, pixels, >= 1.
            height: image height, pixels, >= 1.
            target: the point the camera looks at, metres, world frame, shape (3,).
            distance: camera distance from the target, metres, > 0.
            yaw_deg: camera yaw, degrees; 0 looks along +y from the viewer's side
                of the table (x to the right), 90 looks along -x.
            pitch_deg: degrees; negative looks down, -90 straight down.
            fov: vertical field of view, degrees, in (0, 180).

        Returns:
            RGB image, shape (height, width, 3), uint8, row 0 at the top.

        Raises:
            ValueError: a size, the distance or the field of view is out of range, or
                the target is not three numbers.
        """
        orbit = (distance, yaw_deg, pitch_deg)
        return render_view(self.client, (width, height), target, orbit, fov)

    # -- queries ---------------------------------------------------------------------

    def ray_heights(self, xy: ArrayLike) -> RayHits:
        """Cast vertical rays from above onto the table and whatever lies on it.

        Particles are transparent to these rays, so a new particle can be put on the
        object (or table) under its contour point: at z = height + particle radius.

        Args:
            xy: points, metres, world frame, shape (N, 2).

        Returns:
            Heights of the first surface hit and the object hit (-1: table).
        """
        return self._rays.heights(np.asarray(xy, dtype=float).reshape(-1, 2))

    def object_footprint(self, xy: ArrayLike, margin: float = 0.0) -> FootprintHits:
        """Find points that lie inside an object's footprint by more than a margin.

        The penetration limit (docs/design.md, section 2, step 7) uses this: a contact
        point deep inside an object's footprint goes on the object's top face, not
        against its side.
        Footprints follow the objects' current poses (a tipped box or a lying
        cylinder has the shadow it casts now).

        Args:
            xy: points, metres, world frame, shape (N, 2).
            margin: how far inside the footprint edge a point must be, metres.

        Returns:
            Object index, depth inside its footprint and the top height per point.
        """
        points = np.asarray(xy, dtype=float).reshape(-1, 2)
        owner, best = self.footprint_depth(points)
        shallow = best <= margin
        owner[shallow] = -1
        best[shallow] = -np.inf
        # Rays only where a footprint holds the point: this runs every frame.
        top = np.full(len(points), np.nan)
        inside = owner >= 0
        if inside.any():
            top[inside] = self.ray_heights(points[inside]).height
        return FootprintHits(owner, best, top)

    def footprint_depth(self, xy: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """How deep each point lies inside the nearest object footprint.

        Args:
            xy: points, metres, world frame, shape (N, 2).

        Returns:
            (object, depth): the index of the object with the largest depth (the
            footprint that holds the point deepest or, outside every footprint, the
            one it lies least far outside by this measure), -1 in a scene without
            objects; and the depth, metres, negative outside. Outside a box's
            footprint the depth is minus the distance beyond the farthest edge
            *line* the point lies outside of, which is never more than the true
            distance: a point is never nearer an object than its depth says (what
            culling needs to be safe). Shapes (N,).
        """
        return footprint_depths(*self._footprints(xy))

    def footprint_side(
        self, xy: ArrayLike, near: float
    ) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`footprint_depth`'s object and depth, and the table-plane outward
        normal of the nearest object's side at each point of ``xy`` (N, 2), metres (a
        box shadow's nearest edge, a disc's radius; a zero row with no side or farther
        than ``near`` metres outside every footprint), from one pass over the
        footprints (:func:`~graspenv.geometry.footprint_sides`)."""
        return footprint_sides(*self._footprints(xy), near)

    def _footprints(
        self, xy: ArrayLike
    ) -> tuple[
        NDArray[np.float64],
        NDArray[np.int64],
        NDArray[np.float64],
        NDArray[np.float64],
        NDArray[np.float64],
    ]:
        """The arguments the compiled footprint measures share: the points as a
        contiguous (N, 2) array, then every object's shape code, size, position
        and rotation."""
        points = np.ascontiguousarray(xy, dtype=float).reshape(-1, 2)
        states = self.object_states()
        bodies = self._bodies
        return points, bodies.shape_codes, bodies.sizes, states.position, states.rotation

    def contact_report(self, name: str) -> ContactReport:
        """Contacts on an object from the last physics sub-step.

        Args:
            name: object name.

        Returns:
            Contact points, normals (into the object) and forces, with which particle
            or object each contact is with.
        """
        body = self._object_bodies[self.object_index(name)]
        return read_contact_report(self.client, body, self.pool, self._bodies.object_of_body)

    # -- control ---------------------------------------------------------------------

    def step_frame(
        self,
        particles: ArrayLike,
        targets: ArrayLike,
        spin: ArrayLike | float = 0.0,
        dt: float | None = None,
    ) -> NDArray[np.float64]:
        """Advance one camera frame, driving every particle stack to its contour point.

        Each particle follows Wilson's law (:mod:`graspenv.physics.control`) through
        every sub-step of the frame. A bottom particle's friction acts only in the
        table plane, an upper one's in every direction (see
        :meth:`ParticlePool.set_upper`).

        Particles have infinite rotational inertia, so no contact can change their
        angular velocity: it is set here to ``spin`` about z. A rigid fingertip's
        surface turns with the finger; a sphere that does not turn drags a squeezed
        object's face along with its centre, one radius further out than the face,
        and overdrives a turn by radius / lever arm (about 6 % for 2 mm particles on a
        6 cm box). Pass the rotation rate of each contour (e.g. the hand's estimated
        rotation) to remove that error.

        Every active particle should be in ``particles`` every frame: one left out
        keeps its last velocity and target, and its next frame starts from there.

        Args:
            particles: particle ids, shape (K,) for single particles, or (K, L) for
                stacks of L particles per contour point, column 0 at the bottom.
            targets: contour points at the end of this frame, metres, world frame
                (x, y), shape (K, 2).
            spin: angular velocity about +z of the contour at each point, rad/s,
                shape (K,) or a scalar for all.
            dt: frame duration, seconds; defaults to ``1 / surface.fps``.

        Returns:
            Particle positions at the end of the frame, metres, world frame, shape
            ``particles.shape + (3,)``.
        """
        ids = np.asarray(particles, dtype=np.int64)
        if ids.ndim == 1:
            ids = ids[:, None]
        if ids.ndim != 2:
            raise ValueError(f"particles must have shape (K,) or (K, L), got {ids.shape}")
        k, layers = ids.shape
        goal_xy = np.asarray(targets, dtype=float)
        if goal_xy.shape != (k, 2):
            raise ValueError(f"targets must have shape ({k}, 2), got {goal_xy.shape}")
        spin_z = np.broadcast_to(np.asarray(spin, dtype=float), (k,))
        frame_dt = self.frame_dt if dt is None else float(dt)
        flat = ids.reshape(-1)
        if not self.pool.is_active(flat).all():
            raise ValueError(
                f"step_frame got parked or unknown particles: {flat[~self.pool.is_active(flat)]}"
            )
        if flat.size == 0:
            self._stepper.run(frame_dt, self._stepper.substeps_for(frame_dt, self.object_states))
            return np.zeros((*np.shape(particles), 3))

        goal = np.repeat(goal_xy, layers, axis=0)
        start = self.pool.last_targets(flat)
        bodies = self.pool.body_ids(flat).tolist()
        client = self.client
        get_position = pb.getBasePositionAndOrientation
        # Velocities: Bullet moves a body by h·v after its solve (pybullet splits
        # impulses only past 4 cm of penetration), so a particle's velocity is its
        # last displacement over h, exact to rounding; only the first sub-step
        # needs last frame's, which the pool keeps with the position it read then
        # (or placed the particle at). Two Bullet calls per particle fewer a frame.
        x, v, known = self.pool.cached_states(flat)
        for i in np.flatnonzero(~known).tolist():
            x[i] = get_position(bodies[i], client)[0]
            v[i] = pb.getBaseVelocity(bodies[i], client)[0]
        substeps = self._stepper.substeps_for(frame_dt, self.object_states, goal - start, v)
        h = frame_dt / substeps
        control_dt = self._control_dt(frame_dt)
        tangent_dt, normals = self._tangent_law(frame_dt, control_dt, goal)
        drive = ParticleDrive.for_frame(
            start,
            goal,
            layers,
            frame_dt,
            substeps,
            self._particle_proxy,
            self._particle_physics,
            top_press=self.scene.proxy.down_force,
            control_dt=control_dt,
            normals=normals,
            tangent_dt=tangent_dt,
        )
        angular = [(0.0, 0.0, w) for w in np.repeat(spin_z, layers).tolist()]
        self.pool.set_upper(flat, ~drive.is_bottom)
        n = len(bodies)
        set_velocity = pb.resetBaseVelocity
        chain = itertools.chain.from_iterable

        def read_positions() -> NDArray[np.float64]:
            # Positional arguments and fromiter: this is the hot loop.
            rows = [get_position(b, client)[0] for b in bodies]
            return np.fromiter(chain(rows), float, 3 * n).reshape(n, 3)

        # Where each bottom particle should rest: on the surface under it (rays from
        # the particle down ignore whatever is above it). One at table level cannot
        # be above its support and needs no ray.
        bottoms = x[drive.is_bottom]
        rest = SupportPlanes(
            np.full(len(bottoms), self.pool.radius), bottoms[:, :2], np.zeros((len(bottoms), 2))
        )
        raised = bottoms[:, 2] > self.pool.radius + REST_TOLERANCE
        if np.any(raised):
            height, slope = self._rays.support_planes(
                bottoms[raised], clearance=SUPPORT_CLEARANCE * self.pool.radius
            )
            rest.rest_z[raised] += height
            rest.slope[raised] = slope

        press = drive.presses(rest.rest_z)

        def drive_particles(substep: int) -> None:
            velocity = drive.velocities(substep, x, v, rest, press)
            for body, linear, spin_of in zip(bodies, velocity.tolist(), angular, strict=True):
                set_velocity(body, linear, spin_of, client)

        def observe() -> None:
            nonlocal x, v
            moved = read_positions()
            v = (moved - x) / h
            x = moved

        self._stepper.run(frame_dt, substeps, drive_particles, observe)
        self.pool.record_states(flat, x, v)
        self.pool.set_last_targets(flat, goal)
        return x.reshape(*np.shape(particles), 3)

    def step_bodies(self, handles: ArrayLike, goals: ArrayLike, dt: float | None = None) -> None:
        """Advance one camera frame, driving rigid proxy bodies to their goal poses.

        Args:
            handles: bodies from :attr:`rigid_proxies`, shape (B,).
            goals: (x, y, yaw) at the end of the frame, metres and radians, world
                frame, shape (B, 3).
            dt: frame duration, seconds; defaults to ``1 / surface.fps``.
        """
        frame_dt = self.frame_dt if dt is None else float(dt)
        substeps = self._stepper.substeps_for(frame_dt, self.object_states)
        h = frame_dt / substeps
        tau = max(self._control_dt(frame_dt), h)
        self._stepper.run(
            frame_dt, substeps, lambda _: self.rigid_proxies.drive(handles, goals, h, tau)
        )

    def _tangent_law(
        self, frame_dt: float, control_dt: float, goal: NDArray[np.float64]
    ) -> tuple[float | None, NDArray[np.float64] | None]:
        """The law's Δt along an object's side (``physics.stiff_tangent``) and the
        normal of the footprint side nearest each goal (inside a footprint, or
        within two particle radii outside one; zero rows elsewhere), or (None,
        None) where the law is the same along and across: the configured sub-step,
        where it is shorter than the law's Δt."""
        substep = frame_dt / self.substeps
        if not self.scene.physics.stiff_tangent or substep >= control_dt:
            return None, None
        return substep, self.footprint_side(goal[:, :2], 2.0 * self.pool.radius)[2]

    def _control_dt(self, frame_dt: float) -> float:
        """The control law's Δt for a frame of ``frame_dt`` seconds: the configured
        ``physics.control_time``, or the configured sub-step if that is longer."""
        return max(self.scene.physics.control_time, frame_dt / self.substeps)

    def balls(self) -> NDArray[np.bool_]:
        """Which objects are balls, whose footprint overhangs the table, shape (O,)."""
        return self._bodies.shape_codes == SHAPE_CODES["sphere"]

    def put_down(self, xy: ArrayLike, clear_sides: bool = True) -> NDArray[np.float64]:
        """Where a particle lowered onto each point goes: its centre, metres, (N, 3).

        It rests on the highest surface under its disc (rays from its centre and four
        points 0.9 radius around it), so a particle whose sphere would overlap a side
        goes on the top face rather than into the side, and one that fits under an
        overhang (beside a ball) rests on the table. A point outside every footprint
        but within two radii of a box's or an upright cylinder's side is moved out
        along the side's outward normal until its sphere clears it, onto the table:
        the disc's rays (Bullet's box meets one up to 0.6 mm past its side) put it
        on the top face, centre off it, and it rolled off and hung wedged on the
        side (docs/design.md, "Particles put down beside a side or a neighbour").
        No move by a ball, nor by a cylinder leaning by 1 µm (no side; given one,
        particles beside a rocked heavy cylinder's foot flung it: fuzz seed 9947).

        Args:
            xy: points, metres, world frame, shape (N, 2).
            clear_sides: move points beside a side out (if not, each rests where
                its disc's rays say, as the paper's instant proxies' do).
        """
        points = np.array(xy, dtype=float).reshape(-1, 2)
        radius = self.pool.radius
        near = np.zeros(0, np.intp)  # the points moved out beside a side
        if clear_sides:
            owner, depth, outward = self.footprint_side(points, 2.0 * radius)
            near = np.flatnonzero((owner >= 0) & (depth <= 0.0) & (depth > -2.0 * radius))
            near = near[~self.balls()[owner[near]]]
            outward = outward[near]
            sided = np.any(outward != 0.0, axis=1)
            near, outward = near[sided], outward[sided]
            points[near] += np.maximum(radius + depth[near], 0.0)[:, None] * outward
        rest = np.ones(len(points), bool)
        rest[near] = False
        bottom = np.empty(len(points))
        bottom[rest] = self._rest_heights(points[rest])
        bottom[near] = self.ray_heights(points[near]).height
        return np.column_stack([points, bottom + radius])

    def _rest_heights(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """The height of the highest surface under each particle's disc at ``points``
        (N, 2), metres; 0, the table, for one that fits under an overhang."""
        starts = np.column_stack([points, np.full(len(points), self._rays.top())])
        return self._rays.support_heights(starts, fit_under=True)


def _finite(
    name: str, what: str, value: ArrayLike, shapes: tuple[tuple[int, ...], ...]
) -> NDArray[np.float64]:
    """``value`` as a float array of one of ``shapes``, all finite, or a ValueError."""
    array = np.asarray(value, dtype=float)
    if array.shape not in shapes or not np.all(np.isfinite(array)):
        expected = " or ".join(str(s) for s in shapes)
        raise ValueError(f"{what} for {name!r} must be finite with shape {expected}, got {value!r}")
    return array.copy()
