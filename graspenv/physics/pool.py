"""A pool of particle bodies: sphere proxies created in batches and reused forever.

Creating a Bullet body costs about 0.4 ms even in batches, so particles are never
created or destroyed per camera frame: the pool creates sphere bodies in batches,
hands them out by id, and *parks* the released ones (no collisions, asleep, far from
the table) until they are needed again. Ids are pool indices (0, 1, 2, ...), not
Bullet body ids; the same calls in the same order hand out the same ids, which the
bit-for-bit determinism of the simulation depends on.

Particles are in collision group :data:`PARTICLE_GROUP` with mask
``OBJECT_GROUP | STATIC_GROUP``: they touch objects and the table, never one another.
Their rotational inertia is infinite, so no contact can turn them: a sphere that
contacts could spin takes the friction impulse by rolling and no friction reaches
the object. Their angular velocity is instead set by the control step (the spin of
their contour) and kept exactly.
"""

from __future__ import annotations

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from graspenv.config import PhysicsConfig, ProxyConfig
from graspenv.physics.meshes import mesh_visual_shape
from graspenv.physics.view import PARTICLE_RGBA, icosahedron

__all__ = ["OBJECT_GROUP", "PARTICLE_GROUP", "STATIC_GROUP", "ParticlePool"]

#: Collision group of dynamic objects (Bullet's own default for dynamic bodies).
OBJECT_GROUP = 1
#: Collision group of static bodies: the table and the floor (Bullet's default).
STATIC_GROUP = 2
#: Collision group of active particles; their mask is ``OBJECT_GROUP | STATIC_GROUP``.
PARTICLE_GROUP = 4
PARTICLE_MASK = OBJECT_GROUP | STATIC_GROUP

# Parked particles sit on a grid far from the table, 5 cm apart so that their
# bounding boxes never overlap (overlapping boxes would cost broadphase pair checks
# every step even with a zero collision mask).
_PARK_ORIGIN = (1000.0, 1000.0, 1000.0)
_PARK_SPACING = 0.05
_PARK_ROW = 64

# Bodies are created with this mass and given their real mass and infinite inertia
# right after. Bullet only refreshes a body's world inertia tensor when it integrates
# the body, so for its first awake step a particle still has the inertia it was
# created with; with the real 10 g that first contact spins it up, and the infinite
# inertia then keeps that spin forever (a conveyor belt under the object). Created
# heavy, the stale inertia is too large to spin anything.
_CREATION_MASS = 1.0e6

_IDENTITY = (0.0, 0.0, 0.0, 1.0)
_ZERO = (0.0, 0.0, 0.0)
# Friction scaling in the particle's own frame, whose z stays the world's z (a
# particle only ever spins about z). Planar friction keeps a millionth of its
# vertical part rather than none: Bullet scales a contact's friction direction by
# these factors without normalising it again, so on a vertical face where the
# particle slides only straight down (held still, pressed) the direction would be
# zero and the solver divides by it; the whole world turned NaN in the first frame
# (tests/physics/test_physics_control.py). A millionth of the friction along z
# cannot lift a particle or a face (a thousandth, also safe, doubled the turn's
# error in the one run measured).
_PLANAR_FRICTION = (1.0, 1.0, 1.0e-6)
_FULL_FRICTION = (1.0, 1.0, 1.0)


class ParticlePool:
    """Sphere bodies for particles, created in batches and parked when unused.

    Args:
        client: PyBullet physics client id that owns the bodies.
        proxy: particle radius, mass and friction.
        physics: CCD settings and the batch size (``physics.pool_batch``).
        capacity: number of bodies to create now (rounded up to whole batches);
            ``None`` creates one batch.

    Attributes:
        radius: particle sphere radius, metres.
        mass: particle mass, kilograms.
    """

    def __init__(
        self,
        client: int,
        proxy: ProxyConfig,
        physics: PhysicsConfig,
        capacity: int | None = None,
    ) -> None:
        self._client = client
        self._proxy = proxy
        self._physics = physics
        self.radius = proxy.particle_radius
        self.mass = proxy.particle_mass
        self._batch = physics.pool_batch
        self._shape = pb.createCollisionShape(
            pb.GEOM_SPHERE, radius=self.radius, physicsClientId=client
        )
        # Only seen in rendered views; the renderer draws parked particles too, so a
        # 20-triangle shape keeps a large pool from slowing every image.
        vertices, indices = icosahedron(self.radius)
        self._visual = mesh_visual_shape(client, vertices, indices, PARTICLE_RGBA)
        self._bodies = np.zeros(0, dtype=np.int64)
        self._active = np.zeros(0, dtype=bool)
        # Where each particle was told to be at the end of the previous frame, world
        # xy metres; the control step interpolates from it so particles move
        # smoothly through the frame rather than jumping in its first sub-step.
        self._last_target = np.zeros((0, 2))
        self._particle_of_body: dict[int, int] = {}
        # Position and velocity of each particle at the end of the frame it was last
        # stepped in (or where it was placed), metres and m/s, and the world's
        # physics step count then (-1: unknown). The control step uses them instead
        # of asking Bullet, two calls per particle fewer.
        self._velocity = np.zeros((0, 3))
        self._position = np.zeros((0, 3))
        self._velocity_step = np.zeros(0, dtype=np.int64)
        #: Physics steps taken by the world so far (kept by PhysicsWorld).
        self.physics_steps = 0
        # True where a particle's friction acts only in the table plane (see
        # set_upper); every particle starts as a bottom particle.
        self._planar = np.zeros(0, dtype=bool)
        self._grow(self._batch if capacity is None else max(capacity, 1))

    # -- sizes ---------------------------------------------------------------------

    @property
    def capacity(self) -> int:
        """Number of particle bodies that exist (active and parked)."""
        return int(self._bodies.size)

    @property
    def num_active(self) -> int:
        """Number of particles handed out and not yet released."""
        return int(np.count_nonzero(self._active))

    @property
    def active_ids(self) -> NDArray[np.int64]:
        """Ids of the active particles in increasing order, shape (K,)."""
        return np.flatnonzero(self._active).astype(np.int64)

    def body_ids(self, ids: ArrayLike) -> NDArray[np.int64]:
        """Bullet body ids of particles (for code inside ``graspenv.physics``).

        Args:
            ids: particle ids, any shape.

        Returns:
            Bullet body unique ids, same shape.
        """
        return self._bodies[np.asarray(ids, dtype=np.int64)]

    def is_active(self, ids: ArrayLike) -> NDArray[np.bool_]:
        """Whether particles are handed out (not parked).

        Args:
            ids: particle ids, any shape; ids outside the pool count as inactive.

        Returns:
            Booleans, same shape.
        """
        ids = np.asarray(ids, dtype=np.int64)
        inside = (ids >= 0) & (ids < self.capacity)
        return inside & self._active[np.where(inside, ids, 0)]

    def particle_of_body(self, body: int) -> int:
        """Particle id of a Bullet body id, -1 when the body is not a particle."""
        return self._particle_of_body.get(body, -1)

    # -- hand out and take back ------------------------------------------------------

    def acquire(self, n: int) -> NDArray[np.int64]:
        """Reserve ``n`` particles; they stay parked until :meth:`place` puts them down.

        The lowest free ids are handed out first, so the order is deterministic.
        The pool grows by whole batches when it runs out.

        Args:
            n: number of particles, >= 0.

        Returns:
            Particle ids, shape (n,), increasing.
        """
        if n < 0:
            raise ValueError(f"acquire(n) needs n >= 0, got {n}")
        free = np.flatnonzero(~self._active)
        if free.size < n:
            self._grow(n - free.size)
            free = np.flatnonzero(~self._active)
        ids = free[:n].astype(np.int64)
        self._active[ids] = True
        return ids

    def release(self, ids: ArrayLike) -> None:
        """Park particles: no collisions, zero velocity, asleep, far from the table.

        Args:
            ids: particle ids, shape (n,); releasing a parked particle is an error.
        """
        ids = self._check(ids)
        if ids.size == 0:
            return
        self._active[ids] = False
        self._park(ids)

    def release_all(self) -> None:
        """Park every active particle."""
        self.release(self.active_ids)

    def place(self, ids: ArrayLike, xyz: ArrayLike) -> None:
        """Put particles down at rest at given positions and make them collide.

        Args:
            ids: active particle ids, shape (n,).
            xyz: sphere centres, metres, world frame, shape (n, 3). A particle resting
                on a surface of height h is at z = h + radius.
        """
        ids = self._check(ids)
        xyz = np.asarray(xyz, dtype=float).reshape(ids.size, 3)
        c = self._client
        for body, position in zip(self._bodies[ids].tolist(), xyz.tolist(), strict=True):
            pb.resetBasePositionAndOrientation(body, position, _IDENTITY, physicsClientId=c)
            # Zero angular velocity too: with infinite inertia nothing else would.
            pb.resetBaseVelocity(body, _ZERO, _ZERO, physicsClientId=c)
            pb.setCollisionFilterGroupMask(
                body, -1, PARTICLE_GROUP, PARTICLE_MASK, physicsClientId=c
            )
            pb.changeDynamics(
                body,
                -1,
                activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING,
                physicsClientId=c,
            )
        self._last_target[ids] = xyz[:, :2]
        self._position[ids] = xyz
        self._velocity[ids] = 0.0
        self._velocity_step[ids] = self.physics_steps

    # -- state -----------------------------------------------------------------------

    def positions(self, ids: ArrayLike) -> NDArray[np.float64]:
        """Sphere centres of particles.

        Args:
            ids: particle ids, shape (n,).

        Returns:
            Positions, metres, world frame, shape (n, 3).
        """
        position, _, known = self.cached_states(ids)
        c = self._client
        get = pb.getBasePositionAndOrientation
        bodies = self._bodies[np.asarray(ids, dtype=np.int64).reshape(-1)]
        for i in np.flatnonzero(~known).tolist():
            position[i] = get(int(bodies[i]), physicsClientId=c)[0]
        return position

    def velocities(self, ids: ArrayLike) -> NDArray[np.float64]:
        """Linear velocities of particles (their spin is what the control step set).

        Args:
            ids: particle ids, shape (n,).

        Returns:
            Velocities, m/s, world frame, shape (n, 3).
        """
        c = self._client
        get = pb.getBaseVelocity
        bodies = self._bodies[np.asarray(ids, dtype=np.int64).reshape(-1)].tolist()
        return np.array([get(b, physicsClientId=c)[0] for b in bodies], dtype=float).reshape(-1, 3)

    def last_targets(self, ids: ArrayLike) -> NDArray[np.float64]:
        """Where particles were told to be at the end of the last frame.

        Args:
            ids: particle ids, shape (n,).

        Returns:
            Targets, metres, world frame (x, y), shape (n, 2).
        """
        return self._last_target[np.asarray(ids, dtype=np.int64).reshape(-1)].copy()

    def set_last_targets(self, ids: ArrayLike, xy: ArrayLike) -> None:
        """Record targets reached at the end of a frame (used by the control step).

        Args:
            ids: particle ids, shape (n,).
            xy: targets, metres, world frame, shape (n, 2).
        """
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        self._last_target[ids] = np.asarray(xy, dtype=float).reshape(ids.size, 2)

    def cached_states(
        self, ids: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
        """Positions and velocities recorded at the end of the last frame (or at
        :meth:`place`), if nothing stepped since, without asking Bullet: the positions
        are Bullet's own to the bit; the velocities are the last sub-step's
        displacement over its duration, Bullet's to rounding (see ``step_frame``).

        Args:
            ids: particle ids, shape (n,).

        Returns:
            (position, velocity, known): metres and m/s, world frame, shapes (n, 3),
            and whether each row is still current, shape (n,).
        """
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        known = self._velocity_step[ids] == self.physics_steps
        return self._position[ids], self._velocity[ids], known

    def record_states(self, ids: ArrayLike, position: ArrayLike, velocity: ArrayLike) -> None:
        """Record particle positions and velocities as current at ``physics_steps``.

        Args:
            ids: particle ids, shape (n,).
            position: metres, world frame, shape (n, 3).
            velocity: m/s, world frame, shape (n, 3).
        """
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        self._position[ids] = np.asarray(position, dtype=float).reshape(ids.size, 3)
        self._velocity[ids] = np.asarray(velocity, dtype=float).reshape(ids.size, 3)
        self._velocity_step[ids] = self.physics_steps

    def set_upper(self, ids: ArrayLike, upper: ArrayLike) -> None:
        """Give particles the friction of a bottom or an upper stack particle.

        A bottom particle stands for the fingertip on the table: its friction acts
        only in the table plane (a touch table cannot lift anything, and vertical
        friction on a squeezed face lets the particles and the face's bottom edge
        ratchet each other upwards until the object tips over). A particle higher in
        a stack is held at its height by the control law; it keeps full friction so
        that a stack can cradle a ball whose contacts lie below its equator. Only
        particles whose role changes cost a Bullet call.

        Args:
            ids: particle ids, shape (n,).
            upper: True for particles above the bottom of their stack, shape (n,).
        """
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        planar = ~np.broadcast_to(np.asarray(upper, dtype=bool), ids.shape)
        change = self._planar[ids] != planar
        c = self._client
        for slot, flat in zip(ids[change].tolist(), planar[change].tolist(), strict=True):
            pb.changeDynamics(
                int(self._bodies[slot]),
                -1,
                anisotropicFriction=_PLANAR_FRICTION if flat else _FULL_FRICTION,
                physicsClientId=c,
            )
            self._planar[slot] = flat

    # -- internals -------------------------------------------------------------------

    def _check(self, ids: ArrayLike) -> NDArray[np.int64]:
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        if ids.size == 0:
            return ids
        if ids.min() < 0 or ids.max() >= self.capacity:
            raise IndexError(f"particle ids out of range [0, {self.capacity}): {ids}")
        if not self._active[ids].all():
            raise ValueError(f"particles {ids[~self._active[ids]]} are not active")
        return ids

    def _grow(self, n: int) -> None:
        """Create whole batches of parked bodies, at least ``n`` new ones."""
        batches = -(-n // self._batch)
        for _ in range(batches):
            start = self.capacity
            slots = np.arange(start, start + self._batch)
            park = self._park_positions(slots)
            created = pb.createMultiBody(
                baseMass=_CREATION_MASS,
                baseCollisionShapeIndex=self._shape,
                baseVisualShapeIndex=self._visual,
                batchPositions=park.tolist(),
                useMaximalCoordinates=True,
                physicsClientId=self._client,
            )
            # A batch creation tells the client only about its last body; every call
            # the pool makes goes to the server by id and needs no more (a sync costs
            # 4-6 ms, most of a rebuild). PhysicsWorld.num_bodies syncs when asked.
            bodies = np.asarray(created, dtype=np.int64).reshape(-1)
            self._particle_of_body.update({b: start + i for i, b in enumerate(bodies.tolist())})
            for body in bodies.tolist():
                self._configure(body)
            self._bodies = np.concatenate([self._bodies, bodies])
            self._active = np.concatenate([self._active, np.zeros(bodies.size, dtype=bool)])
            self._planar = np.concatenate([self._planar, np.ones(bodies.size, dtype=bool)])
            self._velocity = np.concatenate([self._velocity, np.zeros((bodies.size, 3))])
            self._position = np.concatenate([self._position, park])
            self._velocity_step = np.concatenate(
                [self._velocity_step, np.full(bodies.size, -1, dtype=np.int64)]
            )
            self._last_target = np.concatenate([self._last_target, park[:, :2]])
            # Created parked (at rest on the park grid, asleep): only the collision
            # mask is left to clear.
            for body in bodies.tolist():
                pb.setCollisionFilterGroupMask(
                    body, -1, PARTICLE_GROUP, 0, physicsClientId=self._client
                )

    def _configure(self, body: int) -> None:
        """A new body's dynamics, in one call (PyBullet applies each setting on its
        own, whatever else the call sets): a parked particle's, asleep."""
        c = self._client
        proxy, physics = self._proxy, self._physics
        # mass= must come with localInertiaDiagonal: without it PyBullet sets the mass
        # of a maximal-coordinate body to zero and its positions become NaN.
        # A zero inertia diagonal is Bullet's "infinite inertia" (zero inverse).
        # Bullet also sets the CCD motion threshold to half the swept radius. The
        # sphere sits inside the particle (physics.ccd_sphere).
        swept = physics.ccd_sphere * proxy.particle_radius
        ccd = {"ccdSweptSphereRadius": swept} if physics.ccd else {}
        pb.changeDynamics(
            body,
            -1,
            mass=proxy.particle_mass,
            localInertiaDiagonal=_ZERO,
            lateralFriction=proxy.particle_friction,
            rollingFriction=0.0,
            spinningFriction=0.0,
            restitution=0.0,
            linearDamping=0.0,
            angularDamping=0.0,
            anisotropicFriction=_PLANAR_FRICTION,
            activationState=pb.ACTIVATION_STATE_SLEEP,
            physicsClientId=c,
            **ccd,
        )

    def _park_positions(self, ids: NDArray[np.int64]) -> NDArray[np.float64]:
        ids = np.asarray(ids)
        x0, y0, z0 = _PARK_ORIGIN
        return np.stack(
            [
                x0 + _PARK_SPACING * (ids % _PARK_ROW),
                y0 + _PARK_SPACING * (ids // _PARK_ROW),
                np.full(ids.shape, z0),
            ],
            axis=-1,
        ).astype(float)

    def _park(self, ids: NDArray[np.int64]) -> None:
        c = self._client
        park = self._park_positions(ids)
        for body, position in zip(self._bodies[ids].tolist(), park.tolist(), strict=True):
            pb.setCollisionFilterGroupMask(body, -1, PARTICLE_GROUP, 0, physicsClientId=c)
            pb.resetBasePositionAndOrientation(body, position, _IDENTITY, physicsClientId=c)
            pb.resetBaseVelocity(body, _ZERO, _ZERO, physicsClientId=c)
            # Asleep, a parked body is neither integrated nor pulled by gravity: it
            # stays put and costs about a quarter of an awake one per step.
            pb.changeDynamics(
                body, -1, activationState=pb.ACTIVATION_STATE_SLEEP, physicsClientId=c
            )
        self._last_target[ids] = park[:, :2]
        self._velocity_step[ids] = -1
