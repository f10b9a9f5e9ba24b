"""The PyBullet scene: table, objects, particle pool and the per-frame control step.

:class:`PhysicsWorld` owns one PyBullet DIRECT client and is the only door to it:
numpy arrays in, numpy arrays out, object names instead of Bullet ids, particle ids
from :class:`~graspenv.physics.pool.ParticlePool`.

World frame: origin at the table centre, x right, y away from the viewer, z up from
the table top; SI units (m, kg, s, N, rad); quaternions are (x, y, z, w).

Settings applied (from ``scene.physics`` unless stated), and why:

- time step ``1 / (surface.fps · physics.substeps)``, sub-stepped in Python: the
  particle force is recomputed before every ``stepSimulation``. Bullet's own
  ``numSubSteps`` would reapply the first sub-step's force on every internal step.
  A frame in which an object's point or a particle would move more than
  ``physics.substep_travel`` a step gets more, shorter steps (up to
  ``physics.max_substeps``; :func:`~graspenv.physics.control.frame_substeps`).
- ``deterministicOverlappingPairs``: Bullet sorts its broadphase pairs, so the
  solver order, and with it every bit of the result, depends only on the commands.
- ``numSolverIterations`` from ``physics.solver_iterations``; ``allowedCcdPenetration``
  from ``physics.allowed_ccd_penetration`` (at Bullet's default a fast 4 mm sphere
  tunnels through a thin wall even with CCD); ``contactBreakingThreshold`` from
  ``physics.contact_breaking_threshold`` (the 0.02 m default inflates every bounding
  box and slows ray casts five-fold).
- Linear and angular damping are zero for every body: air drag is negligible here
  and damping would bias slide distances.
- An upright cylinder stands on a thin square foot inscribed in its base
  (``_cylinder_collision_shape``), with a cylinder's inertia: alone, a Bullet
  cylinder sinks 2.4 mm into a slippery table.

One world serves many episodes: :meth:`reset` puts the same scene back (cheap, no
body is created), :meth:`rebuild` replaces it by another (``resetSimulation`` and
everything built again in a fresh world's order, so the results are a fresh
world's bit for bit). Disturbances (:meth:`apply_force`) and initial motions
(:meth:`set_object_state`) act on objects by name; :meth:`render` draws a 3-D view.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import TracebackType

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from graspenv.config import ObjectConfig, SceneConfig
from graspenv.geometry import SHAPE_CODES, footprint_depths
from graspenv.physics.control import REST_TOLERANCE, ParticleDrive, frame_substeps
from graspenv.physics.pool import (
    OBJECT_GROUP,
    PARTICLE_GROUP,
    STATIC_GROUP,
    ParticlePool,
)
from graspenv.physics.rigid import RigidBodies
from graspenv.physics.view import FLOOR_RGBA, TABLE_RGBA, object_rgba, render_rgb

__all__ = [
    "EDGE_RADIUS",
    "ContactReport",
    "FootprintHits",
    "ObjectStates",
    "PhysicsWorld",
    "RayHits",
]

#: Half the thickness of the foot under an upright cylinder, metres (its collision
#: shape, ``_cylinder_collision_shape``).
FOOT_HALF_THICKNESS = 0.001
#: How far Bullet rounds a box's and a cylinder's edges and corners, metres: its
#: collision margin (1 mm for shapes made by ``createCollisionShape``), embedded in
#: the half extents, so the faces are where the size says and the edges are
#: rounded by it (a sphere at a box's corner is 0.73 mm farther from it than from
#: the sharp corner; ``tests/physics/test_physics_world.py`` measures it).
EDGE_RADIUS = 0.001
#: Thickness of the table slab under z = 0, metres.
TABLE_THICKNESS = 0.05
#: Height of the floor's top below the table top, metres (a table is about this high).
FLOOR_DEPTH = 0.75
_FLOOR_HALF_SIZE = 2.0
_RAY_BATCH = 8192
#: A bottom particle rests on a surface that its rays meet at least this many radii
#: below its centre. A ray from 0.9 radius out of a particle pressed into an object's
#: side can start inside the object (a convex hull), and Bullet reports a hit at its
#: very start; counting that as a support raised the particle's resting height with
#: it, so nothing pulled it down and the squeeze walked it up the side (README,
#: "Accuracy across the grasp space": the slide's box tipped 9° and lost its grip).
#: A particle on a top face's edge meets the face 0.44 radius below its centre or
#: lower.
SUPPORT_CLEARANCE = 0.1
# Rays start this far above the highest point any object could reach while resting.
_RAY_CLEARANCE = 0.5

_OBJECT_MASK = OBJECT_GROUP | STATIC_GROUP | PARTICLE_GROUP
_STATIC_MASK = OBJECT_GROUP | PARTICLE_GROUP
_ZERO = (0.0, 0.0, 0.0)
# Where reset() moves objects (1 m apart) for one step so that all contacts drop.
_AWAY = 500.0


@dataclass(frozen=True)
class RayHits:
    """What vertical rays cast from above met first (particles are transparent).

    Attributes:
        height: z of the top surface under each point, metres; 0 on the bare table
            (and off its edge), shape (N,).
        object: index into ``PhysicsWorld.object_names`` of the object hit, -1 for
            the table, shape (N,).
    """

    height: NDArray[np.float64]
    object: NDArray[np.int64]


@dataclass(frozen=True)
class FootprintHits:
    """Which object's footprint (its shadow on the table) each point lies inside.

    Attributes:
        object: index of the object whose footprint holds the point deepest, -1 when
            no footprint holds it by more than the margin, shape (N,).
        depth: distance from the point in to the nearest footprint edge of that
            object, metres; -inf where ``object`` is -1, shape (N,).
        top: height of the top surface under the point (ray cast), metres, where
            ``object`` is not -1; NaN elsewhere (no ray is cast there), shape (N,).
    """

    object: NDArray[np.int64]
    depth: NDArray[np.float64]
    top: NDArray[np.float64]


@dataclass(frozen=True)
class ContactReport:
    """Contacts of one object after the last physics sub-step.

    One row per contact point; forces are those Bullet applied in the last sub-step.

    Attributes:
        particle: id of the particle in each contact, -1 when the other body is not a
            particle, shape (K,).
        other_object: index of the other object, -1 when it is a particle, the table
            or the floor, shape (K,).
        position: contact point on the object's surface, metres, world frame, (K, 3).
        normal: unit contact normal pointing into the object (the direction the
            contact pushes it), world frame, shape (K, 3).
        normal_force: normal force on the object, newtons, >= 0, shape (K,).
        friction: friction force on the object, newtons, world frame, shape (K, 3).
        distance: signed separation, metres (negative: penetration), shape (K,).
    """

    particle: NDArray[np.int64]
    other_object: NDArray[np.int64]
    position: NDArray[np.float64]
    normal: NDArray[np.float64]
    normal_force: NDArray[np.float64]
    friction: NDArray[np.float64]
    distance: NDArray[np.float64]

    @property
    def force(self) -> NDArray[np.float64]:
        """Total contact force on the object at each contact, newtons, shape (K, 3)."""
        return self.normal_force[:, None] * self.normal + self.friction

    def particle_normal_forces(self) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """Normal force on the object summed per particle.

        Returns:
            (ids, force): particle ids in increasing order, shape (P,), and the summed
            normal force each pushes on the object with, newtons, shape (P,).
        """
        mask = self.particle >= 0
        ids, inverse = np.unique(self.particle[mask], return_inverse=True)
        force = np.zeros(ids.size)
        np.add.at(force, inverse, self.normal_force[mask])
        return ids.astype(np.int64), force


@dataclass(frozen=True)
class ObjectStates:
    """Every object's state at one moment, rows in ``PhysicsWorld.object_names`` order.

    Attributes:
        position: centres of mass, metres, world frame, (O, 3).
        quaternion: orientations (x, y, z, w), (O, 4).
        rotation: the same as row-major 3 × 3 matrices (Bullet's), (O, 9).
        linear: velocities, m/s, world frame, (O, 3).
        angular: angular velocities, rad/s, world frame, (O, 3).
    """

    position: NDArray[np.float64]
    quaternion: NDArray[np.float64]
    rotation: NDArray[np.float64]
    linear: NDArray[np.float64]
    angular: NDArray[np.float64]

    @classmethod
    def read(cls, client: int, bodies: Sequence[int]) -> ObjectStates:
        """Two Bullet calls per body, and its rotation matrix."""
        count = len(bodies)
        position, quaternion = np.empty((count, 3)), np.empty((count, 4))
        rotation = np.empty((count, 9))
        linear, angular = np.empty((count, 3)), np.empty((count, 3))
        for i, body in enumerate(bodies):
            position[i], quaternion[i] = pb.getBasePositionAndOrientation(body, client)
            rotation[i] = pb.getMatrixFromQuaternion(quaternion[i].tolist())
            linear[i], angular[i] = pb.getBaseVelocity(body, client)
        for array in (position, quaternion, rotation, linear, angular):
            array.setflags(write=False)
        return cls(position, quaternion, rotation, linear, angular)


class PhysicsWorld:
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
        self.substeps = scene.physics.substeps
        self.substep_dt = self.frame_dt / self.substeps
        # Below the sub-step the control law would be unstable.
        self.control_dt = max(scene.physics.control_time, self.substep_dt)
        ring = 0.9 * scene.proxy.particle_radius
        self._disc_offsets = np.array(
            [
                [0.0, 0.0, 0.0],
                [ring, 0.0, 0.0],
                [-ring, 0.0, 0.0],
                [0.0, ring, 0.0],
                [0.0, -ring, 0.0],
            ]
        )
        self._object_bodies: list[int] = []
        self._body_to_object: dict[int, int] = {}
        self._table = -1
        self._floor = -1
        self._build_scene()
        # The particles' mass, press and force clamp, scaled for a light object.
        self._particle_proxy, self._particle_physics = scene.particle_settings
        self.pool = ParticlePool(self.client, self._particle_proxy, self._particle_physics)
        self.rigid_proxies = RigidBodies(self.client, self._particle_proxy, self._particle_physics)
        # Force on each object (by index) for every sub-step of the next frame, N.
        self._pending_force: dict[int, NDArray[np.float64]] = {}
        self._pending_torque: dict[int, NDArray[np.float64]] = {}
        self._states: ObjectStates | None = None
        self._states_step = -1
        self._place_objects()
        self.bullet_seconds = 0.0
        """Wall seconds spent inside Bullet's ``stepSimulation`` by the last frame."""
        self.last_substeps = self.substeps
        """Physics steps the last frame took (``physics.substeps`` or more)."""

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

    def __enter__(self) -> PhysicsWorld:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    def __del__(self) -> None:
        # A forgotten world must not keep its client (and its memory) alive; at
        # interpreter exit pybullet may already be gone, which is fine.
        if getattr(self, "_client", None) is not None:
            with contextlib.suppress(Exception):
                self.close()

    def reset(self) -> None:
        """Restore the initial scene: objects back in place at rest, particles parked.

        No body is created or destroyed; the pool keeps its size and hands out the
        same ids again, so this costs about 0.05 ms. Body ids are unchanged, so the
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
        self._pending_force, self._pending_torque = {}, {}
        self.pool.release_all()
        self.rigid_proxies.clear()
        self._place_objects()

    def _place_objects(self) -> None:
        """Put every object at its initial pose, at rest, with no contact history.

        Objects are first moved apart with their initial orientations and stepped
        once, which drops every contact manifold and broadphase pair (and Bullet's
        warm-start impulses with them), then put back. The step also leaves each
        object's world inertia tensor as its integration computes it for that
        orientation: Bullet updates the tensor only when it integrates a body (a pose
        reset does not), and its rotation matrix after a step differs from a new
        body's in the last bits for any yaw but 0. A fresh world runs this too, so
        a reset one carries the very same tensor: without that, a yawed box after a
        reset drifted from a fresh world's by about 1e-8 m/s within six frames.
        """
        client = self.client
        for i, (config, body) in enumerate(
            zip(self.scene.objects, self._object_bodies, strict=True)
        ):
            _, orientation = _initial_pose(config)
            pb.resetBasePositionAndOrientation(body, (_AWAY + i, _AWAY, _AWAY), orientation, client)
            pb.resetBaseVelocity(body, _ZERO, _ZERO, client)
        pb.stepSimulation(client)
        self.pool.physics_steps += 1
        for config, body in zip(self.scene.objects, self._object_bodies, strict=True):
            position, orientation = _initial_pose(config)
            pb.resetBasePositionAndOrientation(body, position, orientation, client)
            pb.resetBaseVelocity(body, _ZERO, _ZERO, client)
        self._states = None

    def rebuild(self, scene: SceneConfig) -> None:
        """Replace the whole scene by another one, as if this world were new.

        Objects may differ in number, shape, size, mass and friction, and the
        surface, proxy and physics settings may change too. Bullet's world is emptied
        (``resetSimulation``) and everything is built again in the order
        :class:`PhysicsWorld` builds it, so body ids, broadphase pair order and every
        later result are bit-identical to those of ``PhysicsWorld(scene)`` given the
        same commands, by construction. It costs about as much as building the
        particle pool's first batch (``physics.pool_batch`` bodies; 1–3 ms in all
        for the default 64 on this machine, with no body sync); :meth:`reset`
        puts the same scene back in 0.05 ms, but without that guarantee.

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
        pending = self._pending_force.get(index)
        self._pending_force[index] = push.copy() if pending is None else pending + push
        if height is None:
            return
        if not math.isfinite(height):
            raise ValueError(f"height for {name!r} must be finite (metres), got {height!r}")
        arm = np.array([0.0, 0.0, float(height) - self.object_states().position[index, 2]])
        torque = np.cross(arm, push)
        twist = self._pending_torque.get(index)
        self._pending_torque[index] = torque if twist is None else twist + torque

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
        config = self.scene.objects[index]
        body = self._object_bodies[index]
        client = self.client
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
        now_linear, now_angular = pb.getBaseVelocity(body, physicsClientId=client)
        linear = np.array(now_linear) if given_linear is None else given_linear
        angular = np.array(now_angular) if given_angular is None else given_angular
        if rolling:
            radius = config.size[0]
            # No slip where the sphere touches the table: v + ω × (−r ẑ) = 0.
            angular = np.array([-linear[1] / radius, linear[0] / radius, 0.0])
        if moves:
            now_position, quaternion = pb.getBasePositionAndOrientation(
                body, physicsClientId=client
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
                body, xyz.tolist(), quaternion, physicsClientId=client
            )
        pb.resetBaseVelocity(body, linear.tolist(), angular.tolist(), physicsClientId=client)
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

        Software rendering (Bullet's TinyRenderer): headless, no GUI or EGL; about
        10–20 ms for 320 × 240 and 85 ms for 640 × 480 here, plus a few ms per
        thousand pooled particles. Parked particles lie beyond the far clipping
        plane and never show.

        Args:
            width: image width, pixels.
            height: image height, pixels.
            target: the point the camera looks at, metres, world frame, shape (3,).
            distance: camera distance from the target, metres.
            yaw_deg: camera yaw, degrees; 0 looks along +y from the viewer's side
                of the table (x to the right), 90 looks along -x.
            pitch_deg: degrees; negative looks down, -90 straight down.
            fov: vertical field of view, degrees.

        Returns:
            RGB image, shape (height, width, 3), uint8.
        """
        return render_rgb(self.client, width, height, target, distance, yaw_deg, pitch_deg, fov)

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
        points = np.asarray(xy, dtype=float).reshape(-1, 2)
        n = points.shape[0]
        height = np.zeros(n)
        hit_object = np.full(n, -1, dtype=np.int64)
        if n == 0:
            return RayHits(height, hit_object)
        top = self._ray_top()
        starts = np.column_stack([points, np.full(n, top)])
        # Ending just under the table top keeps rays short (fewer broadphase visits).
        ends = np.column_stack([points, np.full(n, -1e-3)])
        for lo in range(0, n, _RAY_BATCH):
            hits = pb.rayTestBatch(
                starts[lo : lo + _RAY_BATCH].tolist(),
                ends[lo : lo + _RAY_BATCH].tolist(),
                collisionFilterMask=OBJECT_GROUP | STATIC_GROUP,
                physicsClientId=self.client,
            )
            for i, hit in enumerate(hits, start=lo):
                body = hit[0]
                if body < 0 or body == self._table:
                    continue
                height[i] = hit[3][2]
                hit_object[i] = self._body_to_object.get(body, -1)
        return RayHits(height, hit_object)

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
        points = np.ascontiguousarray(xy, dtype=float).reshape(-1, 2)
        states = self.object_states()
        return footprint_depths(
            points, self._shape_codes, self._sizes, states.position, states.rotation
        )

    def contact_report(self, name: str) -> ContactReport:
        """Contacts on an object from the last physics sub-step.

        Args:
            name: object name.

        Returns:
            Contact points, normals (into the object) and forces, with which particle
            or object each contact is with.
        """
        body = self._object_bodies[self.object_index(name)]
        points = pb.getContactPoints(bodyA=body, physicsClientId=self.client)
        k = len(points)
        particle = np.full(k, -1, dtype=np.int64)
        other = np.full(k, -1, dtype=np.int64)
        position = np.zeros((k, 3))
        normal = np.zeros((k, 3))
        normal_force = np.zeros(k)
        friction = np.zeros((k, 3))
        distance = np.zeros(k)
        for i, cp in enumerate(points):
            body_b = cp[2]
            particle[i] = self.pool.particle_of_body(body_b)
            other[i] = self._body_to_object.get(body_b, -1)
            position[i] = cp[5]
            # Bullet's normal is on B pointing towards A (the object): into it.
            normal[i] = cp[7]
            normal_force[i] = cp[9]
            friction[i] = cp[10] * np.asarray(cp[11]) + cp[12] * np.asarray(cp[13])
            distance[i] = cp[8]
        return ContactReport(particle, other, position, normal, normal_force, friction, distance)

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
            self._substeps(frame_dt, self._frame_substeps(frame_dt))
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
        substeps = self._frame_substeps(frame_dt, goal - start, v)
        h = frame_dt / substeps
        drive = ParticleDrive.for_frame(
            start,
            goal,
            layers,
            frame_dt,
            substeps,
            self._particle_proxy,
            self._particle_physics,
            top_press=self.scene.proxy.down_force,
            control_dt=self._control_dt(frame_dt),
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
        bottom_z = x[drive.is_bottom, 2]
        rest_z = np.full(bottom_z.shape, self.pool.radius)
        raised = bottom_z > self.pool.radius + REST_TOLERANCE
        if np.any(raised):
            rest_z[raised] += self._support_heights(
                x[drive.is_bottom][raised], clearance=SUPPORT_CLEARANCE * self.pool.radius
            )

        press = drive.presses(rest_z)

        def drive_particles(substep: int) -> None:
            velocity = drive.velocities(substep, x, v, rest_z, press)
            for body, linear, spin_of in zip(bodies, velocity.tolist(), angular, strict=True):
                set_velocity(body, linear, spin_of, client)

        def observe() -> None:
            nonlocal x, v
            moved = read_positions()
            v = (moved - x) / h
            x = moved

        self._substeps(frame_dt, substeps, drive_particles, observe)
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
        substeps = self._frame_substeps(frame_dt)
        h = frame_dt / substeps
        tau = max(self._control_dt(frame_dt), h)
        self._substeps(
            frame_dt, substeps, lambda _: self.rigid_proxies.drive(handles, goals, h, tau)
        )

    def _control_dt(self, frame_dt: float) -> float:
        """The control law's Δt for a frame of ``frame_dt`` seconds: the configured
        ``physics.control_time``, or the configured sub-step if that is longer."""
        return max(self.scene.physics.control_time, frame_dt / self.substeps)

    def _frame_substeps(
        self,
        frame_dt: float,
        target_steps: NDArray[np.float64] | None = None,
        velocities: NDArray[np.float64] | None = None,
    ) -> int:
        """This frame's sub-steps (:func:`~graspenv.physics.control.frame_substeps`)
        from how far its particles go (each its target's step, metres, (n, 2), or
        its own speed, m/s, (n, 3), over the frame, whichever is more) and from the
        objects' speed and spin at the frame's start: a box's or cylinder's fastest
        point (the spin at its bounding radius), a ball's lowest point (a ball
        rolling on the table needs no short steps: the point it rests on is still)."""
        physics = self.scene.physics
        if physics.max_substeps <= self.substeps:
            return self.substeps  # a fixed count: nothing to measure
        travel = 0.0
        if target_steps is not None and velocities is not None:
            travel = math.sqrt(
                max(
                    float(np.max(np.sum(target_steps**2, axis=1))),
                    float(np.max(np.sum(velocities**2, axis=1))) * frame_dt**2,
                )
            )
        if self._object_bodies:
            states = self.object_states()
            spin = states.angular
            # A ball's lowest point moves at v + ω × (0, 0, −r).
            lowest = (
                states.linear
                + np.column_stack([-spin[:, 1], spin[:, 0], np.zeros(len(spin))])
                * self._bounding_radii[:, None]
            )
            speed = np.where(
                self._shape_codes == SHAPE_CODES["sphere"],
                np.sqrt(np.sum(lowest**2, axis=1)),
                np.sqrt(np.sum(states.linear**2, axis=1))
                + self._bounding_radii * np.sqrt(np.sum(spin**2, axis=1)),
            )
            travel = max(travel, float(np.max(speed)) * frame_dt)
        return frame_substeps(travel, physics)

    def _substeps(
        self,
        frame_dt: float,
        substeps: int,
        drive: Callable[[int], None] | None = None,
        observe: Callable[[], None] | None = None,
    ) -> None:
        """The frame's ``substeps`` physics sub-steps of ``frame_dt / substeps``
        seconds: for each s = 1..S, drive the proxies, push the objects, step Bullet,
        then observe. Pending forces are dropped afterwards; :attr:`bullet_seconds`
        gets the time in Bullet's step and :attr:`last_substeps` the count."""
        client = self.client
        h = frame_dt / substeps
        if h != self.substep_dt:
            pb.setTimeStep(h, physicsClientId=client)
        clock = time.perf_counter
        step = pb.stepSimulation
        bullet = 0.0
        self.last_substeps = substeps
        for s in range(1, substeps + 1):
            if drive is not None:
                drive(s)
            self._apply_pending_forces()
            tic = clock()
            step(client)
            bullet += clock() - tic
            self.pool.physics_steps += 1
            if observe is not None:
                observe()
        self._pending_force, self._pending_torque = {}, {}
        if h != self.substep_dt:
            pb.setTimeStep(self.substep_dt, physicsClientId=client)
        self.bullet_seconds = bullet

    def rest_heights(self, xy: ArrayLike) -> NDArray[np.float64]:
        """Where a particle lowered from above onto each point comes to rest.

        The height of the highest surface under the particle's disc (rays from its
        centre and four points 0.9 radius around it), so a particle whose centre is
        just outside an object's side but whose sphere would overlap it rests on the
        top face instead of being put into the side.

        Args:
            xy: particle centres, metres, world frame, shape (N, 2).

        Returns:
            Height of the supporting surface, metres (0: table), shape (N,).
        """
        points = np.asarray(xy, dtype=float).reshape(-1, 2)
        top = self._ray_top()
        return self._support_heights(np.column_stack([points, np.full(len(points), top)]))

    def _support_heights(
        self, points: NDArray[np.float64], clearance: float = 0.0
    ) -> NDArray[np.float64]:
        """Height of the highest surface below each particle's disc (0: table), (n,).

        Rays go down from the centre and from four points 0.9 radius around it, so
        a particle whose centre has just passed an edge still counts as resting on
        it (pulling it down there would drive it into the edge and kick the object).
        A surface met less than ``clearance`` below a ray's start is not a support
        (:data:`SUPPORT_CLEARANCE`).
        """
        n = points.shape[0]
        if n == 0:
            return np.zeros(0)
        starts = (points[:, None, :] + self._disc_offsets[None, :, :]).reshape(-1, 3)
        ends = starts.copy()
        ends[:, 2] = -1e-3
        height = np.zeros(starts.shape[0])
        for lo in range(0, starts.shape[0], _RAY_BATCH):
            hits = pb.rayTestBatch(
                starts[lo : lo + _RAY_BATCH].tolist(),
                ends[lo : lo + _RAY_BATCH].tolist(),
                collisionFilterMask=OBJECT_GROUP | STATIC_GROUP,
                physicsClientId=self.client,
            )
            for i, hit in enumerate(hits, start=lo):
                if hit[0] >= 0 and hit[0] != self._table and hit[3][2] <= starts[i, 2] - clearance:
                    height[i] = hit[3][2]
        return height.reshape(n, -1).max(axis=1)

    # -- building --------------------------------------------------------------------

    def _apply_pending_forces(self) -> None:
        """Apply this frame's object forces for the coming sub-step (Bullet forgets them)."""
        client = self.client
        for index in sorted(self._pending_force):
            body = self._object_bodies[index]
            # WORLD_FRAME takes the point in world coordinates: the centre of mass, so
            # the push adds no torque (checked on a tilted maximal-coordinate box).
            position, _ = pb.getBasePositionAndOrientation(body, physicsClientId=client)
            pb.applyExternalForce(
                body,
                -1,
                self._pending_force[index].tolist(),
                position,
                pb.WORLD_FRAME,
                physicsClientId=client,
            )
        for index in sorted(self._pending_torque):
            pb.applyExternalTorque(
                self._object_bodies[index],
                -1,
                self._pending_torque[index].tolist(),
                pb.WORLD_FRAME,
                physicsClientId=client,
            )

    def _build_scene(self) -> None:
        client = self.client
        physics = self.scene.physics
        pb.setGravity(0.0, 0.0, -physics.gravity, physicsClientId=client)
        pb.setTimeStep(self.substep_dt, physicsClientId=client)
        pb.setPhysicsEngineParameter(
            numSubSteps=0,
            numSolverIterations=physics.solver_iterations,
            deterministicOverlappingPairs=1,
            allowedCcdPenetration=physics.allowed_ccd_penetration,
            contactBreakingThreshold=physics.contact_breaking_threshold,
            contactERP=physics.contact_erp,
            physicsClientId=client,
        )
        width, depth = self.scene.surface.size
        self._table = self._static_box(
            (width / 2, depth / 2, TABLE_THICKNESS / 2),
            (0.0, 0.0, -TABLE_THICKNESS / 2),
            physics.table_friction,
            TABLE_RGBA,
        )
        # The floor only catches objects pushed off the table, so they come to rest
        # instead of falling (and speeding up) forever.
        self._floor = self._static_box(
            (_FLOOR_HALF_SIZE, _FLOOR_HALF_SIZE, TABLE_THICKNESS / 2),
            (0.0, 0.0, -FLOOR_DEPTH - TABLE_THICKNESS / 2),
            physics.table_friction,
            FLOOR_RGBA,
        )
        self._object_bodies = [
            self._create_object(o, object_rgba(i)) for i, o in enumerate(self.scene.objects)
        ]
        self._body_to_object = {b: i for i, b in enumerate(self._object_bodies)}
        # The objects' shapes and sizes as the footprint kernel takes them.
        self._shape_codes = np.array([SHAPE_CODES[o.shape] for o in self.scene.objects], np.int64)
        self._sizes = np.zeros((len(self.scene.objects), 3))
        for i, o in enumerate(self.scene.objects):
            self._sizes[i, : len(o.size)] = o.size
        # The farthest point of each object from its centre, metres.
        self._bounding_radii = np.array([_bounding_radius(o) for o in self.scene.objects])

    def _static_box(
        self,
        half_extents: tuple[float, float, float],
        position: tuple[float, float, float],
        friction: float,
        rgba: tuple[float, float, float, float],
    ) -> int:
        client = self.client
        shape = pb.createCollisionShape(
            pb.GEOM_BOX, halfExtents=half_extents, physicsClientId=client
        )
        visual = pb.createVisualShape(
            pb.GEOM_BOX, halfExtents=half_extents, rgbaColor=rgba, physicsClientId=client
        )
        body = int(
            pb.createMultiBody(
                baseMass=0.0,
                baseCollisionShapeIndex=shape,
                baseVisualShapeIndex=visual,
                basePosition=position,
                useMaximalCoordinates=True,
                physicsClientId=client,
            )
        )
        pb.changeDynamics(
            body,
            -1,
            lateralFriction=friction,
            rollingFriction=0.0,
            spinningFriction=0.0,
            restitution=0.0,
            physicsClientId=client,
        )
        pb.setCollisionFilterGroupMask(body, -1, STATIC_GROUP, _STATIC_MASK, physicsClientId=client)
        return body

    def _create_object(self, config: ObjectConfig, rgba: tuple[float, float, float, float]) -> int:
        client = self.client
        if config.shape == "box":
            half_extents = [s / 2 for s in config.size]
            shape = pb.createCollisionShape(
                pb.GEOM_BOX, halfExtents=half_extents, physicsClientId=client
            )
            visual = pb.createVisualShape(
                pb.GEOM_BOX, halfExtents=half_extents, rgbaColor=rgba, physicsClientId=client
            )
        elif config.shape == "sphere":
            shape = pb.createCollisionShape(
                pb.GEOM_SPHERE, radius=config.size[0], physicsClientId=client
            )
            visual = pb.createVisualShape(
                pb.GEOM_SPHERE, radius=config.size[0], rgbaColor=rgba, physicsClientId=client
            )
        else:
            shape = _cylinder_collision_shape(client, *config.size)
            visual = pb.createVisualShape(
                pb.GEOM_CYLINDER,
                radius=config.size[0],
                length=config.size[1],
                rgbaColor=rgba,
                physicsClientId=client,
            )
        position, orientation = _initial_pose(config)
        body = int(
            pb.createMultiBody(
                baseMass=config.mass,
                baseCollisionShapeIndex=shape,
                baseVisualShapeIndex=visual,
                basePosition=position,
                baseOrientation=orientation,
                # physics.reduced_objects: a one-link multibody (config.py says why).
                useMaximalCoordinates=not self.scene.physics.reduced_objects,
                physicsClientId=client,
            )
        )
        pb.changeDynamics(
            body,
            -1,
            lateralFriction=config.friction,
            rollingFriction=config.rolling_friction,
            spinningFriction=config.spinning_friction,
            restitution=config.restitution,
            linearDamping=0.0,
            angularDamping=0.0,
            # An object asleep under a still hand would ignore weak pushes; objects
            # are few, keeping them awake is cheap.
            activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING,
            physicsClientId=client,
        )
        if config.shape == "cylinder":
            # A compound's inertia would be its bounding box's. (PyBullet sets a rigid
            # body's inertia with the mass it is given, so both go.)
            radius, height = config.size
            across = config.mass * (3 * radius**2 + height**2) / 12
            pb.changeDynamics(
                body,
                -1,
                mass=config.mass,
                localInertiaDiagonal=(across, across, config.mass * radius**2 / 2),
                physicsClientId=client,
            )
        pb.setCollisionFilterGroupMask(body, -1, OBJECT_GROUP, _OBJECT_MASK, physicsClientId=client)
        return body

    def _ray_top(self) -> float:
        tops = [0.0]
        for body in self._object_bodies:
            _, high = pb.getAABB(body, physicsClientId=self.client)
            tops.append(high[2])
        return max(tops) + _RAY_CLEARANCE


def _bounding_radius(config: ObjectConfig) -> float:
    """The distance from an object's centre to its farthest point, metres."""
    if config.shape == "box":
        return 0.5 * math.sqrt(sum(s * s for s in config.size))
    if config.shape == "sphere":
        return config.size[0]
    radius, height = config.size
    return math.hypot(radius, 0.5 * height)


def _cylinder_collision_shape(client: int, radius: float, height: float) -> int:
    """An upright cylinder standing on a foot: a thin square box inscribed in its base.

    Bullet meets a cylinder and a box (the table) with one contact point a step and
    keeps up to four while they hold still; on a slippery table the cylinder drifts,
    drops them and ends on a single rim point, 2.4 mm into the table (a 12 g one on
    a table of combined friction 0.01). The foot's square meets the table's box by
    Bullet's box-box algorithm, four corners every step on the rim, so the cylinder
    stands at its height on any table. The foot lies inside the cylinder: particles,
    rays and other objects meet the cylinder alone.
    """
    half_side = radius / math.sqrt(2.0)
    # At least Bullet's collision margin (1 mm), which a box's half extents embed.
    half_thickness = min(FOOT_HALF_THICKNESS, 0.25 * height)
    return int(
        pb.createCollisionShapeArray(
            # Bullet's cylinder axis is the body's z axis: the cylinder stands upright.
            shapeTypes=[pb.GEOM_CYLINDER, pb.GEOM_BOX],
            radii=[radius, 0.0],
            lengths=[height, 0.0],
            halfExtents=[[0.0, 0.0, 0.0], [half_side, half_side, half_thickness]],
            collisionFramePositions=[[0.0, 0.0, 0.0], [0.0, 0.0, half_thickness - height / 2]],
            physicsClientId=client,
        )
    )


def _initial_pose(config: ObjectConfig) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Resting pose of an object: centre (x, y, height / 2) metres, quaternion (x, y, z, w)."""
    x, y = config.position
    orientation = pb.getQuaternionFromEuler((0.0, 0.0, config.yaw))
    return (x, y, config.height / 2), tuple(orientation)


def _finite(
    name: str, what: str, value: ArrayLike, shapes: tuple[tuple[int, ...], ...]
) -> NDArray[np.float64]:
    """``value`` as a float array of one of ``shapes``, all finite, or a ValueError."""
    array = np.asarray(value, dtype=float)
    if array.shape not in shapes or not np.all(np.isfinite(array)):
        expected = " or ".join(str(s) for s in shapes)
        raise ValueError(f"{what} for {name!r} must be finite with shape {expected}, got {value!r}")
    return array.copy()
