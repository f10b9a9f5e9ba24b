"""Each numerical guard is needed: a hard case keeps every invariant with the guard
at its default and breaks a named one with the guard off (or set very loose).

The speed limit (``physics.max_particle_speed``) has no test here: switched off
(1000 m/s) it left the object poses bit-identical in 21 of the 26 hard cases and
within 5 nm in the other 5, and broke no invariant that holds with it, there or in
strikes at up to 12 m/s across the full table (measured with the old
maximal-coordinate default). The force limit caps a particle's acceleration at
F/m = 1000 m/s² (20 N on 20 g), so it needs 5 ms of free running to reach 5 m/s,
and a particle lagging its contour point by more than the penetration margin
(7 mm: any finger faster than about 1.7 m/s) is lifted onto the object's top
before it strikes a side.

The force limit (``physics.max_particle_force``) has no test here either since the
points stopped sliding along the fingertips' outlines (``proxy.follow_points``):
the stiff pinch that put a particle 1.16 mm into a 50 g box without it now keeps
every invariant (0.21 mm), and so did every variant tried (pinches of 10-50 g boxes
6-6.5 mm deep at 32 and 64 sub-steps, strikes at 1-5 m/s under the stiff law). It
stays as a bound on what a particle can ask of the solver.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from . import _cases as cases
from ._cases import Case


def _off(guard: str, value: Any, build: Callable[[], Case], broken: str) -> Any:
    """A parameter set: the case ``build`` makes, the guard ``guard`` (``section.key``,
    also the test id) set to ``value`` over the case's own settings, and the
    invariant that then breaks."""
    name, key = guard.split(".")
    return pytest.param(build, {name: {key: value}}, {broken}, id=guard)


def _strike_at_four_substeps() -> Case:
    return cases.strike(3.0, mass=1.0).with_sections(physics={"max_substeps": 4})


def _light_pinch_at_four_substeps() -> Case:
    obj = cases.box(mass=0.005)
    # The plain law along the side: with the shared side load this pinch holds
    # without the guard (below).
    config = cases.scene(obj, physics={"max_substeps": 4}, proxy={"share_side_load": False})
    return cases.pinch(obj, config, "pinch 5 g", depth=0.006)


GUARDS = [
    # CCD guards the frames whose sub-steps are at their cap (physics.max_substeps):
    # at a fixed four sub-steps a particle following a 3 m/s finger into a 1 kg
    # box, without CCD, passes 1.19 mm into its side (none with it). With the
    # sub-steps raised to the motion, strikes at 0.5-5 m/s on boxes of 5 g-1 kg
    # hold without CCD; no case built so far needs CCD then. Until a particle's
    # contacts formed 1 mm before it touched (physics.contact_breaking_threshold;
    # 3.5 µm before) a 0.5 m/s strike was enough (1.47 mm in; 0.17 mm now, and
    # 1 and 2 m/s hold too). Before the objects were reduced-coordinate bodies, the
    # case was a 0.8 m/s strike on the 0.2 kg box.
    _off("physics.ccd", False, _strike_at_four_substeps, "inside_object"),
    # CCD at Bullet's own allowed penetration (4 cm) is no better than none.
    _off("physics.allowed_ccd_penetration", 0.04, _strike_at_four_substeps, "inside_object"),
    # A 20 mm squeeze held on the sides instead of the top springs the box away
    # when one finger lifts.
    _off("proxy.penetration_limit", False, cases.deep_release, "speed"),
    _off("proxy.penetration_margin", 0.03, cases.deep_release, "speed"),
    # Particles of a fixed 20 g squeezing a 5 g box outweigh it fourfold: at a fixed
    # four sub-steps, squeezed 6 mm (the grid's deepest), a particle ends 1.37 mm
    # inside the box in the turn (with the points landing on the outline's nearest
    # point instead of along its normal, the box sank into the table), where 0.5 g
    # particles, a tenth of its mass, keep every invariant. At 5 mm it broke the
    # speed bound (1.89 m/s against 1.33) until the points stopped sliding along
    # the fingertips (proxy.follow_points) and the penetration margin went to 7 mm;
    # then 5 mm kept every invariant without the guard (points on the nearest
    # point). At 50 solver iterations a particle ended 2.77 mm inside the box.
    # Since a particle's contacts form 1 mm before it touches, 6 mm keeps every
    # invariant without the guard (0.77 mm) and 5 mm broke two (a particle 1.57 mm
    # in, the speed bound; 0.04 mm in with the guard). Since CCD sweeps a sphere a
    # quarter of the particle's size (physics.ccd_sphere; a whole particle's sweep
    # held squeezed particles in place), 5 mm keeps every invariant without the
    # guard (0.32 mm in) and 6 mm breaks the speed bound (the box thrown at
    # 2.73 m/s against a bound of 1.81): the case is 6 mm now. Since each
    # fingertip's load along a side is shared by its particles' depths
    # (proxy.share_side_load, 2026-12-06) the pinch keeps every invariant without
    # the guard at 4, 5, 6 and 6.5 mm (fastest 1.56 m/s against 1.80, 0.82 mm in at
    # most), and a 10 g box at 6 mm: the case is measured with the sharing off.
    # The guard stays for the heavy objects' grip ("Particles outweighed light
    # objects" in docs/accuracy.md: the grid's worst turn 2.25° without it, 0.70° with it,
    # 2026-12-05).
    _off("proxy.mass_ratio", 0.0, _light_pinch_at_four_substeps, "speed"),
]


@pytest.mark.parametrize(("build", "off", "broken"), GUARDS)
def test_guard_is_needed(build: Callable[[], Case], off: dict[str, Any], broken: set[str]) -> None:
    case = build()
    guarded = cases.run(case)
    guarded.assert_ok()
    unguarded = cases.run(case.with_sections(**off))
    assert broken <= unguarded.broken(), unguarded.summary()
