"""Instant particle proxies (Wilson et al., UIST 2008): the baseline that cannot grasp.

Every frame, every strong-gradient pixel of the mask (subsampled by
``proxy.instant_stride``) becomes a particle, put down from above where the pixel is
now (on an object's top if its sphere would overlap the object) and moved through
the frame with the image motion (dense optical flow) that brought it there; all of
them are replaced in the next frame. Nothing persists, so a particle that ends up
inside an object's footprint is put down on its top next frame instead of squeezing
its side: fingers can push objects but cannot hold them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from graspenv.config import ProxyConfig
from graspenv.contacts.edges import backward_flow, edge_pixels
from graspenv.contacts.tracking import ContactFrame
from graspenv.physics.world import PhysicsWorld
from graspenv.proxies.base import ProxyCommand
from graspenv.surface.geometry import Surface

__all__ = ["InstantProxies"]


class InstantProxies:
    """Mask edges to particles that live for one frame.

    Args:
        world: the physics world whose pool and ray casts are used.
        proxy: ``instant_stride`` and the stack settings.
        surface: the pixel ↔ world transform.
    """

    def __init__(self, world: PhysicsWorld, proxy: ProxyConfig, surface: Surface) -> None:
        self._world = world
        self._proxy = proxy
        self._surface = surface
        self._previous: NDArray[np.uint8] | None = None
        self._particles = np.zeros(0, np.int64)

    def reset(self) -> None:
        self._previous = None
        self._particles = np.zeros(0, np.int64)

    def update(self, frame: ContactFrame, mask: NDArray[np.uint8]) -> ProxyCommand:
        """Replace every particle; ``frame`` is not needed by this method."""
        del frame
        pool = self._world.pool
        pool.release(self._particles)
        pixels = edge_pixels(mask, self._proxy.instant_stride)
        previous = self._previous if self._previous is not None else mask
        self._previous = mask.copy()
        if len(pixels) == 0:
            self._particles = np.zeros(0, np.int64)
            return ProxyCommand(np.zeros((0, 1), np.int64), np.zeros((0, 2)), np.zeros(0))
        now = self._surface.pixel_to_world(pixels)
        before = self._surface.pixel_to_world(backward_flow(previous, mask, pixels))
        # Each particle keeps the pixel's image velocity for one frame.
        targets = 2.0 * now - before
        ids = pool.acquire(len(pixels))
        # Where the pixel is, on the object's top wherever the disc's rays meet it.
        # Moved out to clear a side instead (as the persistent proxies put a new
        # point down), the particles just outside a squeezed side gripped it and
        # the canonical turn ended 7.8° short instead of 43°; the paper's baseline
        # cannot hold a turn (README, "The paper's interactions, measured").
        pool.place(ids, self._world.put_down(now, clear_sides=False))
        self._particles = ids
        return ProxyCommand(ids[:, None], targets, np.zeros(len(ids)))
