"""The particle control law: Wilson's kinematic drive, one compiled call a sub-step.

For each Python sub-step s = 1..S of a camera frame, each particle's planar target
moves along the straight line from its last frame's target to this frame's (``x*_s``,
at constant velocity ``u``), and the particle is driven by Wilson's law, with the
target's velocity fed forward::

    v* = (x*_s − x) / Δt + (1 − h/Δt) u   (|v*| ≤ physics.max_particle_speed)
    F  = m (v* − v) / Δt                  (|F| ≤ physics.max_particle_force)

in the table plane, with h the sub-step and Δt = ``physics.control_time`` (or h if
longer; ``physics.stiff_tangent``, an experiment, gives the part along an object's
side a shorter Δt of its own, :attr:`DriveLaw.tangent_tau`; ``physics.critical_damping``,
another, adds (1 − h/Δt)·m/Δt of damping on ``v − u``, :attr:`DriveLaw.damping`). At
Δt = h this is the paper's law; for Δt > h the feed forward keeps a free particle on
a moving target instead of lagging by u·Δt. A particle held off its point by a depth d
(inside an object) pushes with about m·d/Δt² (1152 N/m at the defaults: squeezing
deeper grips harder). A bottom particle sliding on the table stays short of
its point by its table friction over that stiffness (about 0.09 mm at the defaults).

In z, a bottom particle resting on an object is pressed down by ``proxy.down_force``
(a finger's press on its top; its weight is cancelled, so the press does not depend
on its mass), one on the table by the press scaled with the particle's mass
(:attr:`SceneConfig.particle_scale`: a full press beside a 5 g box drags it, 10° short
on a 90° turn, docs/design.md, section 3b), and, if it rises above the surface
under it, pulled back by the same law: friction cannot hold a bottom particle down
(it is planar), and a squeezed face tilted by a degree pushes it up harder than the
press, so without the pull it could be squirted up a face or wedged under an edge.
The surface is measured by rays once a frame, where the particle starts it, and
followed along its slope as the particle moves (:class:`SupportPlanes`); the pull
is no faster than ``physics.substep_travel`` a sub-step. Without either, a particle
climbing a ball's shoulder, or put down on a steeply tilted face, was yanked into
the surface by the stale height (docs/design.md, section 3b). A bottom particle's
downward speed carried from one sub-step to the next (a fall off the edge its
support was measured on) is no more than that, the press's own change added on
top, so that a particle resting on its support presses as before. A particle in layer
l > 0 of a stack is driven the same way to ``proxy.stack_spacing · l`` above its
bottom particle.

The law is applied as a velocity (``F·h/m`` added to the particle's velocity before
Bullet's step), so each sub-step costs one PyBullet call per particle to set it and
one to read the position back: PyBullet has no batched form of either for separate
bodies. :class:`ParticleDrive` holds what one frame's sub-steps share; the velocity
of each sub-step is one call of :func:`drive_velocities`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from graspenv.config import PhysicsConfig, ProxyConfig
from graspenv.jit import njit

__all__ = [
    "REST_TOLERANCE",
    "DriveLaw",
    "ParticleDrive",
    "Stacks",
    "SupportPlanes",
    "TargetPaths",
    "drive_velocities",
    "frame_substeps",
]

#: A bottom particle may sit this far above its support before it is pulled down,
#: metres (Bullet's resting contacts sink about 0.01-0.03 mm, never rise).
REST_TOLERANCE = 2e-4


def frame_substeps(travel: float, physics: PhysicsConfig) -> int:
    """The sub-steps of a frame in which the fastest point of an object or particle
    moves ``travel`` metres: ``physics.substeps``, raised so that no point moves more
    than ``physics.substep_travel`` in one sub-step, up to ``physics.max_substeps``.

    A box turned on the table at one 1/60 s step a frame tips onto a corner and sinks
    into the table, and so does a box spun by a bare torque with no particle near
    (docs/design.md, section 3b): Bullet's box-on-box contact needs short steps once
    the corners move millimetres a step. Slow frames keep the configured count.
    """
    base = physics.substeps
    most = max(base, physics.max_substeps)
    if most == base or travel <= base * physics.substep_travel:
        return base
    return min(most, math.ceil(travel / physics.substep_travel))


class TargetPaths(NamedTuple):
    """Where each particle's target goes over a frame: along the straight line from
    ``start`` to ``start + step``, at constant velocity.

    Attributes:
        start: each particle's target at the start of the frame, metres, (n, 2).
        step: its target's travel over the frame, metres, (n, 2).
        feed_forward: the target velocity's share the position term misses, m/s,
            (n, 2).
        normal: the table-plane normal of the object side beside each target, (n,
            2); a zero row has none. Along the side the law may be stiffer
            (:attr:`DriveLaw.tangent_tau`).
    """

    start: NDArray[np.float64]
    step: NDArray[np.float64]
    feed_forward: NDArray[np.float64]
    normal: NDArray[np.float64]


class Stacks(NamedTuple):
    """How K stacks of L particles lie in the rows of a drive: stack by stack, each
    bottom first.

    Attributes:
        is_bottom: which particles are at the bottom of their stack, (K·L,).
        bottom_of: for each upper particle, the row of its stack's bottom one,
            (U,), in row order of the upper particles.
        rise: for each upper particle, its height above the bottom one, metres, (U,).
    """

    is_bottom: NDArray[np.bool_]
    bottom_of: NDArray[np.intp]
    rise: NDArray[np.float64]

    @classmethod
    def of(cls, k: int, layers: int, spacing: float) -> Stacks:
        """``k`` stacks of ``layers`` particles, ``spacing`` metres apart."""
        if layers == 1:  # single particles, the common case: no stacks to hold
            return cls(np.ones(k, bool), np.zeros(0, np.intp), np.zeros(0))
        is_upper = np.tile(np.arange(layers) > 0, k)
        return cls(
            ~is_upper,
            np.repeat(np.arange(k) * layers, layers)[is_upper],
            np.tile(np.arange(layers) * spacing, k)[is_upper],
        )


class SupportPlanes(NamedTuple):
    """What each bottom particle rests on this frame, one row per bottom particle.

    Attributes:
        rest_z: its resting height (the support under its disc plus its radius),
            metres, (B,).
        at: where that was measured (its centre at the frame's start), metres,
            (B, 2).
        slope: the support's slope there (dz/dx, dz/dy), (B, 2); 0 on the table,
            a level top or an edge (``RayCaster.support_planes``).
    """

    rest_z: NDArray[np.float64]
    at: NDArray[np.float64]
    slope: NDArray[np.float64]


class DriveLaw(NamedTuple):
    """The constants of Wilson's law a frame's sub-steps share (module docstring).

    Attributes:
        tau: the law's Δt, seconds.
        gain: h / Δt.
        v_max: the commanded speed's limit, m/s.
        dv_max: the velocity change a sub-step's force limit allows, m/s.
        lift_dv: gravity's velocity change over a sub-step, m/s (an upper particle's
            weight is cancelled).
        pull_max: the fastest a bottom particle is pulled down to its support, m/s:
            ``physics.substep_travel`` a sub-step.
        tangent_tau: the law's Δt along an object's side, for a particle with a
            normal (:attr:`TargetPaths.normal`), seconds: ``tau``, or shorter
            (``physics.stiff_tangent``).
        tangent_gain: h / ``tangent_tau``.
        rate: 1 / the frame's duration, 1/s.
        damping: the share of a particle's velocity relative to its target's taken
            off a sub-step beyond the law's own: (h/Δt)·(1 − h/Δt) with
            ``physics.critical_damping``, else 0.
        tangent_damping: the same along an object's side, at the tangent's Δt.
    """

    tau: float
    gain: float
    v_max: float
    dv_max: float
    lift_dv: float
    pull_max: float
    tangent_tau: float
    tangent_gain: float
    rate: float
    damping: float
    tangent_damping: float


class ParticleDrive(NamedTuple):
    """One frame's control law for K contour points of L-particle stacks.

    Attributes:
        targets: each particle's target over the frame, K·L rows.
        stacks: how the stacks lie in those rows.
        law: the law's constants.
        substeps: sub-steps in the frame.
        press_dv: the vertical velocity change of a bottom particle on the table a
            sub-step (the press, with its weight cancelled), m/s.
        top_press_dv: the same for a bottom particle resting on an object, m/s.
        table_rest: the resting height of a particle on the table, metres.
    """

    targets: TargetPaths
    stacks: Stacks
    law: DriveLaw
    substeps: int
    press_dv: float
    top_press_dv: float
    table_rest: float

    @classmethod
    def for_frame(
        cls,
        start: NDArray[np.float64],
        goal: NDArray[np.float64],
        layers: int,
        frame_dt: float,
        substeps: int,
        proxy: ProxyConfig,
        physics: PhysicsConfig,
        top_press: float,
        control_dt: float | None = None,
        normals: NDArray[np.float64] | None = None,
        tangent_dt: float | None = None,
    ) -> ParticleDrive:
        """The law for a frame in which particles go from ``start`` to ``goal``
        (metres, (K·L, 2), stacks of ``layers`` bottom first), pressed by
        ``proxy.down_force`` on the table and by ``top_press`` (newtons) on an
        object, in ``substeps`` sub-steps. ``control_dt`` is the law's Δt (default:
        ``physics.control_time``, or the sub-step if longer); a frame given more
        sub-steps than configured (:func:`frame_substeps`) keeps the configured
        law's Δt, so it resolves the same law more finely. ``tangent_dt`` is the
        law's Δt along an object's side (default: Δt) for the particles with a
        ``normals`` row (K·L, 2; zero rows have none), the sub-step if longer."""
        h = frame_dt / substeps
        tau = max(physics.control_time, h) if control_dt is None else max(control_dt, h)
        tangent_tau = tau if tangent_dt is None else min(max(tangent_dt, h), tau)
        mass = proxy.particle_mass
        step = goal - start
        if normals is None or tangent_tau == tau:
            normals = np.zeros_like(goal)
        elif normals.shape != goal.shape:
            raise ValueError(f"normals must have shape {goal.shape}, got {normals.shape}")
        return cls(
            targets=TargetPaths(
                start,
                step,
                # With Δt equal to the sub-step the position term alone lands on the
                # moving target (the paper's law); with a longer Δt it would lag by
                # u·Δt, so the target's velocity is fed forward by the share it misses.
                (1.0 - h / tau) * step / frame_dt,
                normals,
            ),
            stacks=Stacks.of(len(goal) // layers, layers, proxy.stack_spacing),
            law=DriveLaw(
                tau=tau,
                gain=h / tau,
                v_max=physics.max_particle_speed,
                dv_max=physics.max_particle_force * h / mass,
                lift_dv=physics.gravity * h,
                pull_max=physics.substep_travel / h,
                tangent_tau=tangent_tau,
                tangent_gain=h / tangent_tau,
                rate=1.0 / frame_dt,
                damping=_extra_damping(h / tau, physics),
                tangent_damping=_extra_damping(h / tangent_tau, physics),
            ),
            substeps=substeps,
            # Bullet adds g·h itself; the weight is cancelled and the press applied.
            press_dv=(physics.gravity - proxy.down_force / mass) * h,
            top_press_dv=(
                physics.gravity - (proxy.down_force if top_press is None else top_press) / mass
            )
            * h,
            table_rest=proxy.particle_radius,
        )

    @property
    def is_bottom(self) -> NDArray[np.bool_]:
        """Which particles are at the bottom of their stack, (K·L,)."""
        return self.stacks.is_bottom

    def presses(self, rest_z: NDArray[np.float64]) -> NDArray[np.float64]:
        """Each bottom particle's press a sub-step (:attr:`press_dv` on the table,
        :attr:`top_press_dv` on an object), m/s, from the resting heights (metres,
        one per bottom particle, in row order); they change once a frame."""
        on_object = rest_z > self.table_rest + REST_TOLERANCE
        return np.where(on_object, self.top_press_dv, self.press_dv)

    def velocities(
        self,
        substep: int,
        position: NDArray[np.float64],
        velocity: NDArray[np.float64],
        rest: SupportPlanes,
        press: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """The velocities to set before sub-step ``substep`` (1..S), m/s, (K·L, 3),
        from the particles' positions and velocities now, the bottom particles'
        supports and their presses (:meth:`presses`), one per bottom particle in row
        order."""
        # The kernel takes the bundles' arrays one by one: it runs every sub-step, and
        # numba types a NamedTuple argument in Python at each call (about a
        # microsecond), plain arrays in C.
        return drive_velocities(
            position,
            velocity,
            *self.targets,
            substep / self.substeps,
            *self.stacks,
            *rest,
            press,
            *self.law,
        )


def _extra_damping(gain: float, physics: PhysicsConfig) -> float:
    """The share of the velocity relative to the target's that
    ``physics.critical_damping`` takes off a sub-step at ``gain`` = h/Δt: the law's
    damping then is (2 − h/Δt)·m/Δt, the one for which a free particle's two
    eigenvalues a sub-step are equal (1 − h/Δt, both real), and at h = Δt the law's
    own."""
    return gain * (1.0 - gain) if physics.critical_damping else 0.0


@njit
def drive_velocities(
    position: NDArray[np.float64],
    velocity: NDArray[np.float64],
    start: NDArray[np.float64],
    step: NDArray[np.float64],
    feed_forward: NDArray[np.float64],
    normal: NDArray[np.float64],
    fraction: float,
    is_bottom: NDArray[np.bool_],
    bottom_of: NDArray[np.intp],
    rise: NDArray[np.float64],
    rest_z: NDArray[np.float64],
    rest_xy: NDArray[np.float64],
    rest_slope: NDArray[np.float64],
    press_dv: NDArray[np.float64],
    tau: float,
    gain: float,
    v_max: float,
    dv_max: float,
    lift_dv: float,
    pull_max: float,
    tangent_tau: float,
    tangent_gain: float,
    rate: float,
    damping: float,
    tangent_damping: float,
) -> NDArray[np.float64]:
    """One sub-step of the law (module docstring) for every particle: the velocity
    to set, m/s, (n, 3), from the particles' states now, the frame's targets, stacks
    and law, and the bottom particles' supports (:class:`SupportPlanes`) and presses
    (:meth:`ParticleDrive.velocities`). ``fraction`` is how far through the frame the
    sub-step ends."""
    n = len(position)
    new = velocity.copy()
    # The tangential part of a particle's velocity change at the tangent's gain.
    tangent_scale = tangent_gain / gain
    for i in range(n):
        ex = start[i, 0] + fraction * step[i, 0] - position[i, 0]
        ey = start[i, 1] + fraction * step[i, 1] - position[i, 1]
        nx, ny = normal[i, 0], normal[i, 1]
        on_side = nx != 0.0 or ny != 0.0
        if not on_side:
            vx = feed_forward[i, 0] + ex / tau
            vy = feed_forward[i, 1] + ey / tau
        else:
            # Across the side at Δt, along it at the tangent's Δt (each with its own
            # feed forward): the squeeze keeps its stiffness, the drag does not lag.
            en = ex * nx + ey * ny
            un = (step[i, 0] * nx + step[i, 1] * ny) * rate
            ux, uy = step[i, 0] * rate - un * nx, step[i, 1] * rate - un * ny
            along = 1.0 - tangent_gain
            across = (1.0 - gain) * un + en / tau
            vx = across * nx + along * ux + (ex - en * nx) / tangent_tau
            vy = across * ny + along * uy + (ey - en * ny) / tangent_tau
        speed = np.hypot(vx, vy)
        if speed > v_max:
            vx *= v_max / speed
            vy *= v_max / speed
        dvx = gain * (vx - velocity[i, 0])
        dvy = gain * (vy - velocity[i, 1])
        if on_side:
            dn = dvx * nx + dvy * ny
            dvx = dn * nx + tangent_scale * (dvx - dn * nx)
            dvy = dn * ny + tangent_scale * (dvy - dn * ny)
        if damping != 0.0:
            # physics.critical_damping: a damper on the velocity relative to the
            # target's, across the side at Δt and along it at the tangent's Δt.
            rx = step[i, 0] * rate - velocity[i, 0]
            ry = step[i, 1] * rate - velocity[i, 1]
            rn = rx * nx + ry * ny  # zero off a side, where all of it is at Δt
            along = tangent_damping if on_side else damping
            dvx += damping * rn * nx + along * (rx - rn * nx)
            dvy += damping * rn * ny + along * (ry - rn * ny)
        size = np.hypot(dvx, dvy)
        if size > dv_max:
            dvx *= dv_max / size
            dvy *= dv_max / size
        new[i, 0] += dvx
        new[i, 1] += dvy
    bottom = 0
    upper = 0
    for i in range(n):
        if is_bottom[i]:
            # Downward speed carried into this sub-step (a fall off the edge its
            # support was measured on) is no more than the pull's; the press adds on.
            new[i, 2] = max(new[i, 2], -pull_max) + press_dv[bottom]
            # A bottom particle that rose above its support is pulled back; the
            # support followed along its slope from where the frame measured it.
            support = (
                rest_z[bottom]
                + rest_slope[bottom, 0] * (position[i, 0] - rest_xy[bottom, 0])
                + rest_slope[bottom, 1] * (position[i, 1] - rest_xy[bottom, 1])
            )
            excess = position[i, 2] - support - REST_TOLERANCE
            if excess > 0.0:
                pull = -min(excess / tau, pull_max)
                new[i, 2] += min(max(gain * (pull - velocity[i, 2]), -dv_max), 0.0)
            bottom += 1
        else:
            z_goal = position[bottom_of[upper], 2] + rise[upper]
            vz = min(max((z_goal - position[i, 2]) / tau, -v_max), v_max)
            lift = min(max(gain * (vz - velocity[i, 2]), -dv_max), dv_max)
            new[i, 2] = velocity[i, 2] + lift_dv + lift
            upper += 1
    return new
