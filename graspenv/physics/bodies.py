"""Building the scene's bodies: Bullet's settings, the table, the floor and the objects.

:func:`build_scene` sends Bullet every command of a new scene in a fixed order (a
fresh world and ``PhysicsWorld.rebuild`` both come through it, so both get the same
body ids) and returns the :class:`SceneBodies`: the Bullet ids and the objects'
shapes as the footprint kernel takes them. :func:`place_objects` puts the objects at
their initial poses with no contact history. The particles are built by
:class:`~graspenv.physics.pool.ParticlePool`, not here.

Settings applied (from ``scene.physics``), and why:

- ``deterministicOverlappingPairs``: Bullet sorts its broadphase pairs, so the
  solver order, and with it every bit of the result, depends only on the commands.
- ``numSolverIterations`` from ``physics.solver_iterations``; ``allowedCcdPenetration``
  from ``physics.allowed_ccd_penetration`` (at Bullet's default a fast 4 mm sphere
  tunnels through a thin wall even with CCD); ``contactBreakingThreshold`` such
  that a particle's contacts form ``physics.contact_breaking_threshold`` before it
  touches (:func:`bullet_breaking_threshold`: Bullet scales the threshold by the
  smaller shape's size).
- Linear and angular damping are zero for every body: air drag is negligible here
  and damping would bias slide distances.
- An upright cylinder stands on a thin square foot inscribed in its base
  (:func:`cylinder_collision_shape`), with a cylinder's inertia: alone, a Bullet
  cylinder sinks 2.4 mm into a slippery table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pybullet as pb
from numpy.typing import NDArray

from graspenv.config import ObjectConfig, SceneConfig
from graspenv.geometry import SHAPE_CODES, bounding_radius
from graspenv.physics.pool import OBJECT_GROUP, PARTICLE_GROUP, STATIC_GROUP
from graspenv.physics.view import FLOOR_RGBA, TABLE_RGBA, object_rgba

__all__ = [
    "EDGE_RADIUS",
    "FLOOR_DEPTH",
    "FOOT_HALF_THICKNESS",
    "TABLE_THICKNESS",
    "SceneBodies",
    "build_scene",
    "bullet_breaking_threshold",
    "cylinder_collision_shape",
    "initial_pose",
    "place_objects",
]

#: Half the thickness of the foot under an upright cylinder, metres (its collision
#: shape, :func:`cylinder_collision_shape`).
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

_OBJECT_MASK = OBJECT_GROUP | STATIC_GROUP | PARTICLE_GROUP
_STATIC_MASK = OBJECT_GROUP | PARTICLE_GROUP
_ZERO = (0.0, 0.0, 0.0)
# Where place_objects() moves objects (1 m apart) for one step so that all contacts drop.
_AWAY = 500.0


@dataclass(frozen=True)
class SceneBodies:
    """The Bullet bodies of a scene (particles aside) and the objects' shapes.

    Attributes:
        table: body id of the table slab.
        floor: body id of the floor under the table.
        objects: body id of each object, in ``scene.objects`` order.
        object_of_body: object index of each object body id.
        shape_codes: each object's :data:`~graspenv.geometry.SHAPE_CODES` code, (O,).
        sizes: each object's ``size``, zero-padded, metres, (O, 3).
        bounding_radii: the farthest point of each object from its centre, metres,
            (O,) (:func:`~graspenv.geometry.bounding_radius`).
    """

    table: int
    floor: int
    objects: list[int]
    object_of_body: dict[int, int]
    shape_codes: NDArray[np.int64]
    sizes: NDArray[np.float64]
    bounding_radii: NDArray[np.float64]


def bullet_breaking_threshold(distance: float, particle_radius: float) -> float:
    """The ``contactBreakingThreshold`` to give PyBullet for a particle's contacts to
    form ``distance`` metres before it touches.

    PyBullet's dispatcher scales the threshold by the smaller shape of each pair: a
    pair's contacts form within the threshold times that shape's bounding-sphere
    radius, which Bullet takes from the shape's box (√3·r for a sphere of radius r).
    Given 1 mm as it is, a 2 mm particle's contacts formed only 3.5 µm before it
    touched, so a particle closing faster than that in a sub-step met no contact
    and ended up to a sub-step's travel inside what it struck (the long fuzz's last
    violations; docs/design.md, section 3b). The same threshold scales a pair of
    larger shapes by the smaller's bounding radius (an object on the table: about
    13 mm for the default box at 1 mm), and Bullet's broadphase grows every
    bounding box by the threshold itself, in metres.
    ``tests/physics/test_physics_world.py`` measures where a particle's contacts form.
    """
    return distance / (math.sqrt(3.0) * particle_radius)


def build_scene(client: int, scene: SceneConfig, substep_dt: float) -> SceneBodies:
    """Set Bullet's parameters and build the table, the floor and every object.

    Args:
        client: an empty PyBullet client.
        scene: the scene configuration.
        substep_dt: the physics time step, seconds.
    """
    physics = scene.physics
    pb.setGravity(0.0, 0.0, -physics.gravity, physicsClientId=client)
    pb.setTimeStep(substep_dt, physicsClientId=client)
    pb.setPhysicsEngineParameter(
        numSubSteps=0,
        numSolverIterations=physics.solver_iterations,
        deterministicOverlappingPairs=1,
        allowedCcdPenetration=physics.allowed_ccd_penetration,
        contactBreakingThreshold=bullet_breaking_threshold(
            physics.contact_breaking_threshold, scene.proxy.particle_radius
        ),
        contactERP=physics.contact_erp,
        physicsClientId=client,
    )
    width, depth = scene.surface.size
    table = _static_box(
        client,
        (width / 2, depth / 2, TABLE_THICKNESS / 2),
        (0.0, 0.0, -TABLE_THICKNESS / 2),
        physics.table_friction,
        TABLE_RGBA,
    )
    # The floor only catches objects pushed off the table, so they come to rest
    # instead of falling (and speeding up) forever.
    floor = _static_box(
        client,
        (_FLOOR_HALF_SIZE, _FLOOR_HALF_SIZE, TABLE_THICKNESS / 2),
        (0.0, 0.0, -FLOOR_DEPTH - TABLE_THICKNESS / 2),
        physics.table_friction,
        FLOOR_RGBA,
    )
    objects = [
        _create_object(client, o, object_rgba(i), physics.reduced_objects)
        for i, o in enumerate(scene.objects)
    ]
    sizes = np.zeros((len(scene.objects), 3))
    for i, o in enumerate(scene.objects):
        sizes[i, : len(o.size)] = o.size
    return SceneBodies(
        table=table,
        floor=floor,
        objects=objects,
        object_of_body={b: i for i, b in enumerate(objects)},
        shape_codes=np.array([SHAPE_CODES[o.shape] for o in scene.objects], np.int64),
        sizes=sizes,
        bounding_radii=np.array([bounding_radius(o) for o in scene.objects]),
    )


def place_objects(client: int, scene: SceneConfig, objects: list[int]) -> None:
    """Put every object at its initial pose, at rest, with no contact history.

    Objects are first moved apart with their initial orientations and stepped once
    (one ``stepSimulation``, which the caller counts), which drops every contact
    manifold and broadphase pair (and Bullet's warm-start impulses with them), then
    put back. The step also leaves each object's world inertia tensor as its
    integration computes it for that orientation: Bullet updates the tensor only
    when it integrates a body (a pose reset does not), and its rotation matrix after
    a step differs from a new body's in the last bits for any yaw but 0. A fresh
    world runs this too, so a reset one carries the very same tensor: without that,
    a yawed box after a reset drifted from a fresh world's by about 1e-8 m/s within
    six frames.
    """
    for i, (config, body) in enumerate(zip(scene.objects, objects, strict=True)):
        _, orientation = initial_pose(config)
        pb.resetBasePositionAndOrientation(body, (_AWAY + i, _AWAY, _AWAY), orientation, client)
        pb.resetBaseVelocity(body, _ZERO, _ZERO, client)
    pb.stepSimulation(client)
    for config, body in zip(scene.objects, objects, strict=True):
        position, orientation = initial_pose(config)
        pb.resetBasePositionAndOrientation(body, position, orientation, client)
        pb.resetBaseVelocity(body, _ZERO, _ZERO, client)


def initial_pose(config: ObjectConfig) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Resting pose of an object: centre (x, y, height / 2) metres, quaternion (x, y, z, w)."""
    x, y = config.position
    orientation = pb.getQuaternionFromEuler((0.0, 0.0, config.yaw))
    return (x, y, config.height / 2), tuple(orientation)


def cylinder_collision_shape(client: int, radius: float, height: float) -> int:
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


def _static_box(
    client: int,
    half_extents: tuple[float, float, float],
    position: tuple[float, float, float],
    friction: float,
    rgba: tuple[float, float, float, float],
) -> int:
    shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half_extents, physicsClientId=client)
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


def _create_object(
    client: int,
    config: ObjectConfig,
    rgba: tuple[float, float, float, float],
    reduced: bool,
) -> int:
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
        shape = cylinder_collision_shape(client, *config.size)
        visual = pb.createVisualShape(
            pb.GEOM_CYLINDER,
            radius=config.size[0],
            length=config.size[1],
            rgbaColor=rgba,
            physicsClientId=client,
        )
    position, orientation = initial_pose(config)
    body = int(
        pb.createMultiBody(
            baseMass=config.mass,
            baseCollisionShapeIndex=shape,
            baseVisualShapeIndex=visual,
            basePosition=position,
            baseOrientation=orientation,
            # physics.reduced_objects: a one-link multibody (config.py says why).
            useMaximalCoordinates=not reduced,
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
        across, radius = config.level_inertia, config.size[0]
        pb.changeDynamics(
            body,
            -1,
            mass=config.mass,
            localInertiaDiagonal=(across, across, config.mass * radius**2 / 2),
            physicsClientId=client,
        )
    pb.setCollisionFilterGroupMask(body, -1, OBJECT_GROUP, _OBJECT_MASK, physicsClientId=client)
    return body
