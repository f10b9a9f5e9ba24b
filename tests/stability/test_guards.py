"""Each numerical guard is needed: a hard case keeps every invariant with the guard
at its default and breaks a named one with the guard off (or set very loose).

The speed limit (``physics.max_particle_speed``) has no test here: switched off
(1000 m/s) it left the object poses bit-identical in 21 of the 26 hard cases and
within 5 nm in the other 5, and broke no invariant that holds with it, there or in
strikes at up to 12 m/s across the full table. The force limit caps a particle's
acceleration at F/m = 250 m/s², so it needs 20 ms of free running to reach 5 m/s,
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


def _off(guard: str, value: Any, build: Callable[[], Case], broken: str, **section: Any) -> Any:
    """A parameter set: the case ``build`` makes, the guard ``guard`` (``section.key``,
    also the test id) set to ``value`` with ``section``'s other keys as given, and the
    invariant that then breaks."""
    name, key = guard.split(".")
    return pytest.param(build, {name: {key: value, **section}}, {broken}, id=guard)


def _strike_at_four_substeps() -> Case:
    return cases.strike(0.8).with_sections(physics={"max_substeps": 4})


GUARDS = [
    # CCD guards the frames whose sub-steps are at their cap (physics.max_substeps):
    # at a fixed four sub-steps a particle following a 0.8 m/s finger, without CCD,
    # passes 1.99 mm into the box's side (0.29 mm with it). Until the pull onto a
    # particle's support was capped at physics.substep_travel a sub-step, a 1 m/s
    # strike without CCD was pulled down there (a surface met at a ray's start is
    # no support) and on through the table: 11.7 mm below it; capped, the 1 m/s
    # particle ends 1.02 mm into the box. With the sub-steps raised to the motion
    # strikes at 0.8, 1, 2 and 5 m/s hold without CCD; no case built so far needs
    # CCD then.
    _off("physics.ccd", False, _strike_at_four_substeps, "inside_object", max_substeps=4),
    # CCD at Bullet's own allowed penetration (4 cm) is no better than none.
    _off(
        "physics.allowed_ccd_penetration",
        0.04,
        _strike_at_four_substeps,
        "inside_object",
        max_substeps=4,
    ),
    # A 20 mm squeeze held on the sides instead of the top springs the box away
    # when one finger lifts.
    _off("proxy.penetration_limit", False, cases.deep_release, "speed"),
    _off("proxy.penetration_margin", 0.03, cases.deep_release, "speed"),
    # Particles of a fixed 20 g squeezing a 5 g box 3 mm outweigh it fourfold: in
    # the first frame of the turn a particle is 1.04 mm inside it (the box at
    # 0.85 m/s; at a fixed four sub-steps it jumps out of the grip, 2.4 mm and
    # 1.7 m/s against a bound of 1.3 m/s). With 0.5 g particles (a tenth of its
    # mass) it is held like the 0.2 kg box.
    _off(
        "proxy.mass_ratio",
        0.0,
        lambda: cases.pinch_box("pinch 5 g", cases.box(mass=0.005)),
        "inside_object",
    ),
    # Under a stiff control law a 2 mm squeeze asks 37 N of each particle; without
    # the clamp they push into the 20 g box (and throw it about).
    _off("physics.max_particle_force", 1.0e6, cases.stiff_pinch, "inside_object"),
]


@pytest.mark.parametrize(("build", "off", "broken"), GUARDS)
def test_guard_is_needed(build: Callable[[], Case], off: dict[str, Any], broken: set[str]) -> None:
    case = build()
    guarded = cases.run(case)
    guarded.assert_ok()
    unguarded = cases.run(case.with_sections(**off))
    assert broken <= unguarded.broken(), unguarded.summary()
