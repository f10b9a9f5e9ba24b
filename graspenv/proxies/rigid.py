"""Rigid proxies: one body per contact, what most touch software would do.

Each contact becomes one rigid prism with the convex footprint the contact had at
touch-down, driven to follow the contact's centroid and rotation. Its rotation is
the best rigid rotation between the previous contour, moved by the centroid's
displacement, and the points it matches in the current one; a round fingertip's
rotation is as invisible to it as to any mask-based method.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from graspenv.config import ProxyConfig
from graspenv.contacts.matching import correspond
from graspenv.contacts.tracking import ContactFrame
from graspenv.physics.world import PhysicsWorld
from graspenv.proxies.base import ProxyCommand, rigid_rotation

__all__ = ["RigidProxies"]


@dataclass
class _Body:
    handle: int
    points: NDArray[np.float64]
    centroid: NDArray[np.float64]
    yaw: float


class RigidProxies:
    """Contacts to one driven rigid body each.

    Args:
        world: the physics world that owns the bodies.
        proxy: matching settings (window, matcher, search).
    """

    def __init__(self, world: PhysicsWorld, proxy: ProxyConfig) -> None:
        self._world = world
        self._proxy = proxy
        self._bodies: dict[int, _Body] = {}

    def reset(self) -> None:
        self._bodies = {}

    def update(self, frame: ContactFrame, mask: NDArray[np.uint8]) -> ProxyCommand:
        """Bookkeeping for one frame; ``mask`` is not needed by this method."""
        del mask
        proxies = self._world.rigid_proxies
        present = set(frame.ids)
        for contact_id in list(self._bodies):
            if contact_id not in present:
                proxies.remove(self._bodies.pop(contact_id).handle)
        for contact in frame.contacts:
            body = self._bodies.get(contact.id)
            points = np.array(contact.contour)
            centroid = np.array(contact.centroid)
            if body is None or contact.status == "new":
                if body is not None:
                    proxies.remove(body.handle)
                handle = proxies.add(points - centroid, centroid)
                self._bodies[contact.id] = _Body(handle, points, centroid, 0.0)
                continue
            moved = body.points - body.centroid + centroid
            match = correspond(
                moved, points, self._proxy.window, self._proxy.matcher, self._proxy.search
            )
            body.yaw += rigid_rotation(moved, points[match.successor])
            body.points, body.centroid = points, centroid
        handles = np.array([b.handle for b in self._bodies.values()], np.int64)
        poses = np.array([[*b.centroid, b.yaw] for b in self._bodies.values()]).reshape(-1, 3)
        return ProxyCommand(
            np.zeros((0, 1), np.int64), np.zeros((0, 2)), np.zeros(0), handles, poses
        )
