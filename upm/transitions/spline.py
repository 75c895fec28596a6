"""Key-frame interpolation with a cubic B-spline (paper section 3.2).

The spline interpolates its key frames: a few real frames of clip 1 up to A, the key
value at the window's middle, and a few real frames of clip 2 from B (scipy's
``make_interp_spline``, cubic, not-a-knot ends). Because it passes through the clip
frames on both sides of each join and is twice continuously differentiable, the window
continues each clip with its own position, velocity and acceleration (up to the
spline's interpolation error between frames).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import make_interp_spline

#: Frames of each clip the spline passes through, A or B included. Three fix the
#: position, velocity and acceleration of the clip at the join (two would fix only the
#: velocity, and the curvature at the join would be set by the far key frame). Measured
#: on five real pairs (tests/transition_data.py, classnn, 20 frames): going from 3 to 6
#: moves the median DOF of the window by 0.005 degrees and the most affected DOF by
#: 0.2-3.7 degrees (the fastest-moving DOFs).
SPLINE_CONTEXT = 3


def keyframe_spline(times, values, query_times) -> np.ndarray:
    """Evaluate the interpolating cubic B-spline through key frames.

    Parameters
    ----------
    times : array_like, shape (n,)
        Strictly increasing key times (frames).
    values : array_like, shape (n, D)
        Key values (already continuous along time: unwrap angles first).
    query_times : array_like, shape (m,)

    Returns
    -------
    ndarray, shape (m, D)
        With fewer than 4 keys the degree drops to n - 1 (2 keys: a straight line).
    """
    times = np.asarray(times, dtype=float)
    values = np.asarray(values, dtype=float)
    degree = min(3, times.size - 1)
    return make_interp_spline(times, values, k=degree, axis=0)(np.asarray(query_times, float))
