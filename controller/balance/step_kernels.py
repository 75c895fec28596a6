"""Compiled kernels of one control step's glue (:mod:`controller.balance.control`; numba,
cached on disk): the reference between frames, the targets clipped into the joint ranges,
the desired acceleration and the applied torques clipped into their range -- each one call
instead of a handful of numpy calls."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def reference_at(qpos, qvel, qacc, i, w, q_out, qd_out, qdd_out):
    """The reference between frames ``i`` and ``i + 1`` at weight ``w`` (0: frame i),
    linear, the root quaternion (qpos 3-6) normalised in the first frame's hemisphere.

    Parameters
    ----------
    qpos : ndarray, shape (T, nq)
    qvel, qacc : ndarray, shape (T, nv)
    i : int
    w : float
    q_out : ndarray, shape (nq,)
    qd_out, qdd_out : ndarray, shape (nv,)
        Written in place.
    """
    a, b = qpos[i], qpos[i + 1]
    for j in range(a.shape[0]):
        q_out[j] = a[j] * (1 - w) + w * b[j]
    sign = 1.0 if np.dot(a[3:7], b[3:7]) >= 0 else -1.0
    quat = (1 - w) * a[3:7] + w * (sign * b[3:7])
    q_out[3:7] = quat / np.sqrt(np.dot(quat, quat))
    va, vb, aa, ab = qvel[i], qvel[i + 1], qacc[i], qacc[i + 1]
    for j in range(va.shape[0]):
        qd_out[j] = (1 - w) * va[j] + w * vb[j]
        qdd_out[j] = (1 - w) * aa[j] + w * ab[j]


@njit(cache=True, nogil=True)
def clip_targets(q_ref, qd_ref, qdd_ref, hinge_q, hinge_v, low, high):
    """Hinge targets inside the joint ranges, in place: a clipped hinge's target velocity
    and acceleration become 0. ``hinge_q``, ``hinge_v``, ``low``, ``high`` (nh,): each
    hinge's qpos and DOF address and range, rad."""
    for k in range(hinge_q.shape[0]):
        angle = q_ref[hinge_q[k]]
        if angle < low[k] or angle > high[k]:
            q_ref[hinge_q[k]] = min(max(angle, low[k]), high[k])
            qd_ref[hinge_v[k]] = 0.0
            qdd_ref[hinge_v[k]] = 0.0


@njit(cache=True, nogil=True)
def desired_acceleration(qdd_ref, kp, err, kd, qd_ref, qvel, max_acceleration, out):
    """``out`` = ``qdd_ref + kp err + kd (qd_ref - qvel)`` within +-``max_acceleration``,
    all (nv,) (NaN stays NaN, as with ``np.clip``)."""
    for j in range(out.shape[0]):
        a = qdd_ref[j] + kp[j] * err[j] + kd[j] * (qd_ref[j] - qvel[j])
        out[j] = a if a != a else min(max(a, -max_acceleration), max_acceleration)


@njit(cache=True, nogil=True)
def clip_torques(tau, low, high):
    """``tau`` (nu,) within ``[low, high]`` (nu,) each, a new array (NaN stays NaN, as
    with ``np.clip``)."""
    out = np.empty(tau.shape[0])
    for j in range(tau.shape[0]):
        t = tau[j]
        out[j] = t if t != t else min(max(t, low[j]), high[j])
    return out
