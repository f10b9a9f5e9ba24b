"""One bench scenario at many sub-pixel placements: how wide its error's spread is.

The bench plays each scenario at three placements; where a setting's figure moves
between two versions of the code, more placements tell a shift from a heavy tail.

Run: ``python -m graspenv.bench.placements SCENARIO COUNT [OVERRIDES_JSON]``,
e.g. ``python -m graspenv.bench.placements turn 12
'{"proxy": {"track_hand_rotation": false, "predicted_resampling": false}}'``.
"""

from __future__ import annotations

import json
import sys

import numpy as np

from graspenv.bench import scenarios
from graspenv.config import load_config

#: The error each scenario is judged by.
ERRORS = {
    "turn": "yaw_error_deg",
    "noisy": "yaw_error_deg",
    "slide": "travel_error_mm",
    "two hands": "travel_error_mm",
    "slip": "slip_error_pct",
}


def main(argv: list[str]) -> None:
    scenario, count = argv[0], int(argv[1])
    overrides = json.loads(argv[2]) if len(argv) > 2 else {}
    base = load_config(None, **overrides)
    values = np.array(
        [
            scenarios.SCENARIOS[scenario](base, offset).errors[ERRORS[scenario]]
            for offset in scenarios.placement_offsets(count, base)
        ]
    )
    size = np.abs(values)
    print(
        f"{scenario} {ERRORS[scenario]} at {count} placements: mean |error| {size.mean():.3f}, "
        f"median {np.median(size):.3f}, largest {size.max():.3f}; {np.round(values, 2).tolist()}"
    )


if __name__ == "__main__":
    main(sys.argv[1:])
