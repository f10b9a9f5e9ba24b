"""Fixtures of the contact tests: the default table and contact settings."""

from __future__ import annotations

import pytest

from graspenv.config import ContactConfig
from graspenv.contacts import ContactTracker
from graspenv.surface.geometry import Surface


@pytest.fixture
def surface() -> Surface:
    """The default table: 0.61 × 0.46 m, 640 × 480 pixels, 60 Hz."""
    return Surface()


@pytest.fixture
def config() -> ContactConfig:
    return ContactConfig()


@pytest.fixture
def tracker(surface: Surface, config: ContactConfig) -> ContactTracker:
    return ContactTracker(surface, config)
