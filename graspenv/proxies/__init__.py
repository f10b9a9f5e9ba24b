"""Proxy methods: tracked contours in, particle (or body) targets out."""

from __future__ import annotations

from graspenv.config import SceneConfig
from graspenv.physics.world import PhysicsWorld
from graspenv.proxies.base import ProxyCommand, ProxyMethod
from graspenv.proxies.instant import InstantProxies
from graspenv.proxies.persistent import PersistentProxies
from graspenv.proxies.rigid import RigidProxies
from graspenv.surface.geometry import Surface

__all__ = [
    "InstantProxies",
    "PersistentProxies",
    "ProxyCommand",
    "ProxyMethod",
    "RigidProxies",
    "make_proxies",
]


def make_proxies(world: PhysicsWorld, scene: SceneConfig, surface: Surface) -> ProxyMethod:
    """The proxy method ``scene.proxy.method`` names, bound to a world."""
    method = scene.proxy.method
    if method == "persistent":
        spacing = scene.contacts.contour_spacing(scene.proxy.particle_radius)
        return PersistentProxies(world, scene.proxy, spacing, surface.dt, scene.stack_layers)
    if method == "instant":
        return InstantProxies(world, scene.proxy, surface)
    return RigidProxies(world, scene.proxy)
