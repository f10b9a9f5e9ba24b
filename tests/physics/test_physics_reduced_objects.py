"""Why ``physics.reduced_objects`` exists, measured on PyBullet alone and through the
pipeline.

A box held between two rows of fixed spheres 13 mm below its centre of mass, pushed
along the rows' line (so that statically nothing needs to move), spins about the
spheres' contact normal as a maximal-coordinate rigid body and holds as a one-link
multibody. If a PyBullet release mends the rigid-body path, the first test fails and
the knob's default can be looked at again (docs/design.md, section 3b).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pybullet as pb
import pytest

from graspenv.bench import grid
from graspenv.bench.scenarios import push_until_slip
from graspenv.config import load_config

HALF = (0.03, 0.03, 0.015)  # the 6 x 6 x 3 cm box
GRIP_Z = 0.002  # the spheres' centres, metres above the box's bottom
RADIUS = 0.002


def _spin_rate(maximal: bool, push: float = 5.0, steps: int = 40) -> float:
    """|ω| of the box after ``steps`` sub-steps of the push, rad/s (no gravity)."""
    client = pb.connect(pb.DIRECT)
    try:
        pb.setPhysicsEngineParameter(fixedTimeStep=1 / 240, physicsClientId=client)
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=HALF, physicsClientId=client)
        box = pb.createMultiBody(
            0.2,
            shape,
            basePosition=[0, 0, HALF[2]],
            useMaximalCoordinates=maximal,
            physicsClientId=client,
        )
        pb.changeDynamics(box, -1, lateralFriction=0.5, physicsClientId=client)
        sphere = pb.createCollisionShape(pb.GEOM_SPHERE, radius=RADIUS, physicsClientId=client)
        for side in (-1, 1):
            for y in np.arange(-2, 3) * 0.004:
                body = pb.createMultiBody(
                    0,
                    sphere,
                    basePosition=[side * (HALF[0] + RADIUS - 3e-4), float(y), GRIP_Z],
                    useMaximalCoordinates=True,
                    physicsClientId=client,
                )
                pb.changeDynamics(body, -1, lateralFriction=2.0, physicsClientId=client)
        for _ in range(120):
            pb.stepSimulation(physicsClientId=client)
        pb.resetBaseVelocity(box, [0, 0, 0], [0, 0, 0], physicsClientId=client)
        for _ in range(steps):
            position, _ = pb.getBasePositionAndOrientation(box, physicsClientId=client)
            line = [position[0], position[1], GRIP_Z]  # through the spheres' line
            pb.applyExternalForce(box, -1, [0, push, 0], line, pb.WORLD_FRAME, client)
            pb.stepSimulation(physicsClientId=client)
        _, angular = pb.getBaseVelocity(box, physicsClientId=client)
        return float(np.linalg.norm(angular))
    finally:
        pb.disconnect(client)


def test_pybullet_rigid_bodies_spin_in_an_off_centre_grip() -> None:
    maximal, reduced = _spin_rate(True), _spin_rate(False)
    assert maximal > 1.0, maximal  # measured 3.6 rad/s: 33° in a sixth of a second
    assert reduced < 0.01, reduced  # measured 0.0009 rad/s


@pytest.mark.parametrize("reduced", [False, True])
def test_a_three_cm_box_slips_near_coulomb_only_in_reduced_coordinates(reduced: bool) -> None:
    """Squeezed 3 mm, pushed along the grip's line: slip force against Coulomb."""
    base = load_config(None).replace(
        physics={"reduced_objects": reduced, "contact_erp": 0.4, "max_particle_force": 20.0}
    )
    cell = replace(grid.BASE_CELL, position=(0.013, -0.041))
    errors = push_until_slip(
        base,
        cell.object(),
        cell.depth,
        relative_rate=grid.SLIP_RAMP,
        ramp_frames=400,
        height=base.proxy.particle_radius,
    ).errors
    if reduced:
        assert abs(errors["slip_error_pct"]) < 10.0, errors
    else:
        assert errors["slip_error_pct"] < -80.0, errors  # measured -96 %
