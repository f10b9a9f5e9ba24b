"""Physics: the only package that imports PyBullet.

:class:`PhysicsWorld` holds the table, the objects and a :class:`ParticlePool` of
sphere proxies. The proxies stage drives it once per camera frame:

1. touch-down: ``ids = world.pool.acquire(n)``; ``world.put_down(xy)`` gives where
   a particle lowered onto each new contour point comes to rest (on the surface
   under its disc, or on the table beside a side it would overlap; particles are
   transparent to its rays), and ``world.pool.place(ids, xyz)`` puts each particle
   there (stack layer l at ``l · proxy.stack_spacing`` above). ``world.object_footprint``
   tells which points lie deeper than ``proxy.penetration_margin`` inside an
   object's footprint (docs/design.md, section 2, step 7);
2. lift-off: ``world.pool.release(ids)``;
3. every frame: ``world.step_frame(ids, targets, spin)`` with every active particle
   (shape (K,) or (K, L) for stacks), its contour point (K, 2) and the contour's
   rotation rate about z; it returns the particles' positions after the frame.

Grasp metrics read ``world.contact_report(name)``.

Between episodes ``world.reset()`` puts the same scene back and
``world.rebuild(scene)`` replaces it (bit-identical to ``PhysicsWorld(scene)``).
``world.apply_force(name, force)`` pushes an object for the next frame,
``world.set_object_state(...)`` teleports or launches one, and
``world.render(...)`` draws a headless 3-D view (:mod:`graspenv.physics.view`).
"""

from __future__ import annotations

from graspenv.physics.pool import OBJECT_GROUP, PARTICLE_GROUP, STATIC_GROUP, ParticlePool
from graspenv.physics.world import (
    EDGE_RADIUS,
    ContactReport,
    FootprintHits,
    PhysicsWorld,
    RayHits,
)

__all__ = [
    "EDGE_RADIUS",
    "OBJECT_GROUP",
    "PARTICLE_GROUP",
    "STATIC_GROUP",
    "ContactReport",
    "FootprintHits",
    "ParticlePool",
    "PhysicsWorld",
    "RayHits",
]
