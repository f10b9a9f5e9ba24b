from __future__ import annotations

import math

import numpy as np
import pytest

from graspenv.surface.controller import ControllerConfig, FingerController, GripState
from graspenv.surface.geometry import Surface

SURFACE = Surface()


def test_grip_turn_moves_fingers_round_the_centre() -> None:
    ctl = FingerController(ControllerConfig(), SURFACE, "grip")
    ctl.place_grip(GripState(np.zeros(2), 0.0, 0.06, True))
    before = ctl.finger_positions()
    for _ in range(30):
        ctl.apply([0.0, 0.0, 1.0, 0.0, 1.0])
        ctl.advance()
    after = ctl.finger_positions()
    a, b = before[1] - before[0], after[1] - after[0]
    turned = math.atan2(a[0] * b[1] - a[1] * b[0], float(a @ b))
    assert turned == pytest.approx(30 * SURFACE.dt * ControllerConfig().max_turn_rate, abs=1e-9)
    assert np.linalg.norm(after[1] - after[0]) == pytest.approx(
        np.linalg.norm(before[1] - before[0])
    )
    assert ctl.touching().all()


def test_grip_opening_is_limited() -> None:
    cfg = ControllerConfig(max_opening=0.08)
    ctl = FingerController(cfg, SURFACE, "grip")
    ctl.place_grip(GripState(np.zeros(2), 0.0, 0.07, False))
    for _ in range(60):
        ctl.apply([0, 0, 0, 1.0, -1.0])
        ctl.advance()
    gap = np.linalg.norm(np.subtract(*ctl.finger_positions())) - 2 * cfg.finger_radius
    assert gap == pytest.approx(0.08)
    assert not ctl.touching().any()


def test_fingers_mode_moves_each_finger_and_stays_on_the_table() -> None:
    ctl = FingerController(ControllerConfig(n_fingers=2), SURFACE, "fingers")
    ctl.place_fingers([[0.0, 0.0], [0.25, 0.0]], [True, False])
    for _ in range(120):
        ctl.apply([1.0, 0.0, 1.0, 1.0, 0.0, -1.0])
        ctl.advance()
    x = ctl.finger_positions()[:, 0]
    limit = SURFACE.size[0] / 2 - ControllerConfig().finger_radius
    assert x[1] == pytest.approx(limit)
    assert x[0] == pytest.approx(min(limit, 120 * SURFACE.dt * 0.2))
    assert ctl.touching().tolist() == [True, False]


def test_actions_are_clipped_and_bad_ones_refused() -> None:
    ctl = FingerController(ControllerConfig(), SURFACE, "grip")
    assert ctl.apply([5.0, -5.0, 0, 0, 0]).tolist()[:2] == [1.0, -1.0]
    with pytest.raises(ValueError, match="finite"):
        ctl.apply([np.inf, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="shape"):
        ctl.apply([0, 0])
    with pytest.raises(ValueError, match="action_mode"):
        FingerController(ControllerConfig(), SURFACE, "paws")  # type: ignore[arg-type]


def test_a_new_controller_moves_its_fingers_from_their_grip() -> None:
    """Before any place_grip, the fingers' twists follow the initial grip (no jump)."""
    from graspenv.surface.controller import ControllerConfig, FingerController
    from graspenv.surface.geometry import Surface

    controller = FingerController(ControllerConfig(), Surface(), "grip")
    controller.apply(np.array([0.5, 0.0, 0.0, 0.0, 1.0]))
    speeds = [np.hypot(*v) for v in controller.finger_velocities()]
    np.testing.assert_allclose(speeds, 0.5 * ControllerConfig().max_speed, rtol=1e-9)
    grip = controller.grip
    before = float(grip.centre[0])
    grip.centre[0] = 1.0  # a copy: the controller's grip is unchanged
    assert controller.grip.centre[0] == before
