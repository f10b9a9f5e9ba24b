"""Each numerical guard is needed: a hard case keeps every invariant with the guard
at its default and breaks a named one with the guard off (or set very loose).

The speed limit (``physics.max_particle_speed``) has no test here: switched off
(1000 m/s) it left the object poses bit-identical in 21 of the 26 hard cases and
within 5 nm in the other 5, and broke no invariant that holds with it, there or in
strikes at up to 12 m/s across the full table (measured with the old
maximal-coordinate default). The force limit caps a particle's acceleration at
F/m = 1000 m/s² (20 N on 20 g), so it needs 5 ms of free running to reach 5 m/s,
and a particle lagging its contour point by more than the penetration margin
(5 mm: any finger faster than about 1.2 m/s) is lifted onto the object's top
before it strikes a side.
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
    return cases.strike(0.5, mass=1.0).with_sections(physics={"max_substeps": 4})


def _light_pinch_at_four_substeps() -> Case:
    obj = cases.box(mass=0.005)
    return cases.pinch(obj, cases.scene(obj, physics={"max_substeps": 4}), "pinch 5 g", depth=0.005)


GUARDS = [
    # CCD guards the frames whose sub-steps are at their cap (physics.max_substeps):
    # at a fixed four sub-steps a particle following a 0.5 m/s finger into a 1 kg
    # box, without CCD, passes 1.47 mm into its side (0.22 mm with it). With the
    # sub-steps raised to the motion, strikes at 0.5-5 m/s on boxes of 5 g-1 kg
    # hold without CCD; no case built so far needs CCD then. (Before the objects
    # were reduced-coordinate bodies, the case was a 0.8 m/s strike on the 0.2 kg
    # box; it now ends 0.46 mm in without CCD.)
    _off("physics.ccd", False, _strike_at_four_substeps, "inside_object"),
    # CCD at Bullet's own allowed penetration (4 cm) is no better than none.
    _off("physics.allowed_ccd_penetration", 0.04, _strike_at_four_substeps, "inside_object"),
    # A 20 mm squeeze held on the sides instead of the top springs the box away
    # when one finger lifts.
    _off("proxy.penetration_limit", False, cases.deep_release, "speed"),
    _off("proxy.penetration_margin", 0.03, cases.deep_release, "speed"),
    # Particles of a fixed 20 g squeezing a 5 g box 5 mm outweigh it fourfold: at a
    # fixed four sub-steps they kick it past its speed bound in the turn (1.89 m/s
    # against 1.33; a particle ends 0.69 mm inside it), where 0.5 g particles, a
    # tenth of its mass, keep every invariant. At 50 solver iterations, before the
    # default's 150, a particle ended 2.77 mm inside it (0.14 mm with the guard);
    # the 3 mm squeeze at the sub-steps that follow the motion stayed within 0.92 mm
    # without the guard.
    _off("proxy.mass_ratio", 0.0, _light_pinch_at_four_substeps, "speed"),
    # Under a stiff control law (32 sub-steps) a 6 mm squeeze asks about 440 N of
    # each 20 g particle; without the clamp one ends 1.16 mm inside the 50 g box in
    # the turn (0.02 mm with the default's 20 N; 1.17 and 0.08 mm at 50 solver
    # iterations and 10 N). The margin is thin: at 16 sub-steps, at 4 mm, or on
    # boxes of 0.2 kg and more, no case built so far breaks without the clamp.
    _off("physics.max_particle_force", 1.0e6, cases.stiff_pinch, "inside_object"),
]


@pytest.mark.parametrize(("build", "off", "broken"), GUARDS)
def test_guard_is_needed(build: Callable[[], Case], off: dict[str, Any], broken: set[str]) -> None:
    case = build()
    guarded = cases.run(case)
    guarded.assert_ok()
    unguarded = cases.run(case.with_sections(**off))
    assert broken <= unguarded.broken(), unguarded.summary()
