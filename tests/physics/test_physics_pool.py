"""ParticlePool: batches, deterministic ids, parking, no bodies created per frame."""

from __future__ import annotations

import numpy as np
import pybullet as pb
import pytest

from graspenv.physics import PhysicsWorld


def test_initial_batch_is_created_parked(world: PhysicsWorld) -> None:
    batch = world.scene.physics.pool_batch
    assert world.pool.capacity == batch
    assert world.pool.num_active == 0
    # table, floor, one box and the parked batch
    assert world.num_bodies == 3 + batch


def test_acquire_hands_out_lowest_free_ids(world: PhysicsWorld) -> None:
    first = world.pool.acquire(3)
    np.testing.assert_array_equal(first, [0, 1, 2])
    world.pool.release(first[1:2])
    np.testing.assert_array_equal(world.pool.acquire(2), [1, 3])
    np.testing.assert_array_equal(world.pool.active_ids, [0, 1, 2, 3])


def test_pool_grows_by_whole_batches(world: PhysicsWorld) -> None:
    batch = world.scene.physics.pool_batch
    ids = world.pool.acquire(batch + 1)
    assert world.pool.capacity == 2 * batch
    assert world.num_bodies == 3 + 2 * batch
    np.testing.assert_array_equal(ids, np.arange(batch + 1))


def test_no_bodies_created_per_frame_after_warm_up(world: PhysicsWorld) -> None:
    rng = np.random.default_rng(0)
    active = world.pool.acquire(40)
    world.pool.place(active, np.column_stack([rng.uniform(0.1, 0.2, (40, 2)), np.full(40, 0.002)]))
    bodies = world.num_bodies
    for _ in range(30):
        # every frame some contacts lift off and others touch down
        gone, active = active[:5], active[5:]
        world.pool.release(gone)
        new = world.pool.acquire(5)
        world.pool.place(new, np.column_stack([rng.uniform(0.1, 0.2, (5, 2)), np.full(5, 0.002)]))
        active = np.concatenate([active, new])
        world.step_frame(active, rng.uniform(0.1, 0.2, (active.size, 2)))
        assert world.num_bodies == bodies
    assert world.pool.capacity == world.scene.physics.pool_batch


def test_parked_particles_do_not_collide_and_do_not_fall(world: PhysicsWorld) -> None:
    ids = world.pool.acquire(2)
    world.pool.place(ids, [[0.1, 0.1, 0.002], [0.12, 0.1, 0.002]])
    world.pool.release(ids)
    parked = world.pool.positions(ids)
    for _ in range(10):
        world.step_frame([], np.zeros((0, 2)))
    np.testing.assert_array_equal(world.pool.positions(ids), parked)
    assert np.all(parked[:, 2] > 100.0)
    body = int(world.pool.body_ids(ids[:1])[0])
    assert pb.getContactPoints(bodyA=body, physicsClientId=world.client) == ()


def test_release_of_a_parked_particle_is_an_error(world: PhysicsWorld) -> None:
    ids = world.pool.acquire(1)
    world.pool.release(ids)
    with pytest.raises(ValueError, match="not active"):
        world.pool.release(ids)
    with pytest.raises(ValueError, match="parked"):
        world.step_frame(ids, [[0.0, 0.0]])


def test_particle_mass_and_infinite_inertia(world: PhysicsWorld) -> None:
    ids = world.pool.acquire(1)
    body = int(world.pool.body_ids(ids)[0])
    mass, _, inertia, *_ = pb.getDynamicsInfo(body, -1, physicsClientId=world.client)
    assert mass == pytest.approx(world.scene.proxy.particle_mass)
    assert inertia == (0.0, 0.0, 0.0)  # Bullet's "infinite"
