"""Fixtures for the physics tests: headless PhysicsWorlds that are always closed."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest

from graspenv.config import SceneConfig, load_config
from graspenv.physics import PhysicsWorld


@pytest.fixture
def scene() -> SceneConfig:
    """The built-in default scene (one 6 cm box at the table centre)."""
    return load_config()


@pytest.fixture
def world(scene: SceneConfig) -> Iterator[PhysicsWorld]:
    """A headless world of the default scene, closed after the test."""
    with PhysicsWorld(scene) as w:
        yield w


@pytest.fixture
def make_world() -> Iterator[Callable[..., PhysicsWorld]]:
    """Build worlds from ``load_config(**overrides)``; all are closed after the test."""
    built: list[PhysicsWorld] = []

    def make(**overrides: object) -> PhysicsWorld:
        w = PhysicsWorld(load_config(**overrides))
        built.append(w)
        return w

    yield make
    for w in built:
        w.close()
