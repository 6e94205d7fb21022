"""Hypothesis strategies shared by the shape, scaling and bounds tests."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from p3d_cli.geometry.rotation import rotation_from_quaternion


@st.composite
def scales(draw):
    """Three factors within 1e-6..1e6 whose largest ratio is at most 1e6."""
    low = draw(st.floats(-6, 0))
    span = draw(st.floats(0, 6))
    t = draw(st.lists(st.floats(0, 1), min_size=3, max_size=3))
    return 10.0 ** (low + span * np.array(t))


@st.composite
def rotations(draw):
    """Proper rotations from random (normalised) quaternions."""
    q = draw(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda v: np.linalg.norm(v) > 1e-3))
    return rotation_from_quaternion(*q)
