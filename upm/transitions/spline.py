"""Key-frame interpolation with a cubic B-spline (paper section 3.2).

The spline interpolates its key frames: a few real frames of clip 1 up to A, the key
value at the window's middle, and a few real frames of clip 2 from B (scipy's
``make_interp_spline``, cubic, not-a-knot ends). Because it passes through the clip
frames on both sides of each join and is twice continuously differentiable, the window
continues each clip with its own position, velocity and acceleration (up to the
spline's interpolation error between frames).
"""

from __future__ import annotations

import functools

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

    Notes
    -----
    The interpolating spline is linear in its key values, so its value at the query
    times is ``W @ values`` with a ``(m, n)`` weight matrix that depends on the times
    only: :func:`spline_weights` computes it once per time layout (a transition's
    layout depends on L and the context lengths only) and caches it.
    """
    values = np.asarray(values, dtype=float)
    return spline_weights(times, query_times) @ values


def spline_weights(times, query_times) -> np.ndarray:
    """The weights ``W``, shape (m, n), of the interpolating spline: its values at
    ``query_times`` are ``W @ values`` for key values ``values`` (n, D) at ``times``.
    Read-only; cached per (times, query_times)."""
    return _weights(tuple(np.asarray(times, dtype=float).tolist()),
                    tuple(np.asarray(query_times, dtype=float).tolist()))


@functools.lru_cache(maxsize=256)
def _weights(times: tuple, query_times: tuple) -> np.ndarray:
    t = np.array(times)
    degree = min(3, t.size - 1)
    weights = make_interp_spline(t, np.eye(t.size), k=degree, axis=0)(np.array(query_times))
    weights.setflags(write=False)
    return weights


@functools.lru_cache(maxsize=64)
def window_weights(k1: int, k2: int, frames: int) -> np.ndarray:
    """The weights (L, k1 + 1 + k2) of a transition's splines (:func:`spline_weights`): key
    frames at the last ``k1`` frames of clip 1 (A at 0), the key at the window's middle
    ``(L + 1) / 2`` and the first ``k2`` frames of clip 2 (B at L + 1), evaluated at the
    window's frames 1 .. L (``frames`` = L). Read-only."""
    n_steps = frames + 1
    times = np.concatenate([np.arange(1 - k1, 1), [0.5 * n_steps], n_steps + np.arange(k2)])
    return spline_weights(times, np.arange(1, frames + 1, dtype=float))
