"""Hypothesis strategies of the contact tests."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from graspenv.bench.contact_scenes import Finger

#: Semi-axes of a fingertip's contact ellipse, metres: 6 to 12 mm.
fingertip_axes = st.tuples(st.floats(0.006, 0.012), st.floats(0.006, 0.012))

#: A fingertip ellipse anywhere on the default table (0.61 × 0.46 m) with its whole
#: footprint on it, at any angle.
fingertips: st.SearchStrategy[Finger] = st.builds(
    lambda x, y, axes, angle: (np.array([x, y]), axes, angle),
    st.floats(-0.28, 0.28),
    st.floats(-0.2, 0.2),
    fingertip_axes,
    st.floats(0.0, np.pi),
)
