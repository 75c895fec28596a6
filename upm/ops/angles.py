"""Periodic angle maths in degrees, batched over any leading shape.

Every difference between two angles is taken the short way round the circle, wrapped
to ``[-180, 180)``.
"""

from __future__ import annotations

import numpy as np


def wrap_deg(angle_deg):
    """Wrap angles to ``[-180, 180)`` degrees.

    Parameters
    ----------
    angle_deg : array_like, any shape
        Angles in degrees, possibly unwrapped (e.g. 1251).

    Returns
    -------
    ndarray, same shape
    """
    a = np.asarray(angle_deg, dtype=float)
    wrapped = np.mod(a + 180.0, 360.0) - 180.0
    # np.mod can return 360.0 for tiny negative inputs (float rounding); fold it back.
    return np.where(wrapped >= 180.0, wrapped - 360.0, wrapped)


def angle_diff_deg(a_deg, b_deg):
    """Shortest signed difference ``a - b`` in ``[-180, 180)`` degrees (broadcasting)."""
    return wrap_deg(np.subtract(a_deg, b_deg, dtype=float))


def interpolate_deg(a_deg, b_deg, alpha):
    """The point at ratio ``alpha`` from ``a`` to ``b``, the short way round.

    The paper's Table 3 ``AngularMedium``, with the convention **alpha = 0 is A and
    alpha = 1 is B** (the paper's code weights the other way round). The result is
    continuous from ``a``: ``alpha = 0`` returns ``a`` exactly (unwrapped as given) and
    ``alpha = 1`` returns ``b`` modulo 360.

    Parameters
    ----------
    a_deg, b_deg : array_like
        Angles in degrees; broadcast together.
    alpha : float or array_like
        Ratio(s) in ``[0, 1]``; broadcast with the angles.

    Returns
    -------
    ndarray
        ``a + alpha * wrap(b - a)``.
    """
    a = np.asarray(a_deg, dtype=float)
    return a + np.asarray(alpha, dtype=float) * angle_diff_deg(b_deg, a)


def unwrap_deg(angle_deg, axis: int = 0):
    """Remove 360-degree jumps along ``axis`` (time), so consecutive samples differ by
    less than 180 degrees. The first sample is kept as given.

    ``np.unwrap(angle_deg, period=360, axis=axis)`` to the last bit -- the same
    operations in the same order -- without its generic set-up, which costs more than
    the arithmetic on a transition's few frames.
    """
    p = np.asarray(angle_deg, dtype=float)
    if axis != 0:
        return np.unwrap(p, period=360.0, axis=axis)
    if p.shape[0] < 2:
        return p.copy()
    dd = p[1:] - p[:-1]
    ddmod = np.mod(dd + 180.0, 360.0) - 180.0
    np.copyto(ddmod, 180.0, where=(ddmod == -180.0) & (dd > 0))
    correction = ddmod - dd
    np.copyto(correction, 0.0, where=np.abs(dd) < 180.0)
    out = p.copy()
    out[1:] = p[1:] + correction.cumsum(axis=0)
    return out


def angular_distance_sq(x_deg, w_deg):
    """Squared Euclidean distance of wrapped per-DOF differences (the paper's d_j).

    Parameters
    ----------
    x_deg : array_like, shape (..., D)
    w_deg : array_like, shape (..., D)
        Broadcast together.

    Returns
    -------
    ndarray, shape (...)
    """
    d = angle_diff_deg(x_deg, w_deg)
    return np.einsum("...i,...i->...", d, d)
