"""Compiled loops behind :func:`upm.ops.rotations.matrix_to_quaternion`,
:func:`~upm.ops.rotations.rotation_log` and :func:`~upm.ops.rotations.rotation_exp` (numba,
cached on disk).

A transition converts a handful of rotations at a time, where a dozen numpy calls per
conversion cost far more than their arithmetic; here each conversion is one call. Inputs
are flattened by the callers: matrices ``(N, 9)`` row-major, vectors ``(N, 3)``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def quaternions(flat):
    """Unit quaternions (w, x, y, z), w >= 0, of rotation matrices ``(N, 9)``: Shepperd's
    method, the largest of the four diagonal combinations (the first on a tie)."""
    out = np.empty((flat.shape[0], 4))
    for n in range(flat.shape[0]):
        m00, m01, m02, m10, m11, m12, m20, m21, m22 = flat[n]
        t = (1.0 + m00 + m11 + m22, 1.0 + m00 - m11 - m22, 1.0 - m00 + m11 - m22,
             1.0 - m00 - m11 + m22)
        best = 0
        for i in range(1, 4):
            if t[i] > t[best]:
                best = i
        if best == 0:
            q = (t[0], m21 - m12, m02 - m20, m10 - m01)
        elif best == 1:
            q = (m21 - m12, t[1], m01 + m10, m02 + m20)
        elif best == 2:
            q = (m02 - m20, m01 + m10, t[2], m12 + m21)
        else:
            q = (m10 - m01, m02 + m20, m12 + m21, t[3])
        scale = 1.0 / math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
        if q[0] < 0.0:
            scale = -scale
        for i in range(4):
            out[n, i] = q[i] * scale
    return out


@njit(cache=True, nogil=True)
def logs(flat):
    """Rotation vectors (radians, angle in [0, pi]) of rotation matrices ``(N, 9)``."""
    q = quaternions(flat)
    out = np.empty((flat.shape[0], 3))
    for n in range(flat.shape[0]):
        sine = math.sqrt(q[n, 1] * q[n, 1] + q[n, 2] * q[n, 2] + q[n, 3] * q[n, 3])
        # angle / sin(angle / 2) -> 2 as the angle -> 0.
        scale = 2.0 * math.atan2(sine, q[n, 0]) / sine if sine > 1e-12 else 2.0
        for i in range(3):
            out[n, i] = scale * q[n, 1 + i]
    return out


@njit(cache=True, nogil=True)
def exps(vectors):
    """Rotation matrices ``(N, 9)`` of rotation vectors ``(N, 3)``: Rodrigues' formula."""
    out = np.empty((vectors.shape[0], 9))
    for n in range(vectors.shape[0]):
        x, y, z = vectors[n]
        theta2 = x * x + y * y + z * z
        theta = math.sqrt(theta2)
        if theta < 1e-8:
            a, b = 1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0
        else:
            a, b = math.sin(theta) / theta, (1.0 - math.cos(theta)) / theta2
        # I + a K + b K^2 with K the cross-product matrix of (x, y, z)
        out[n, 0] = 1.0 - b * (y * y + z * z)
        out[n, 1] = -a * z + b * x * y
        out[n, 2] = a * y + b * x * z
        out[n, 3] = a * z + b * x * y
        out[n, 4] = 1.0 - b * (x * x + z * z)
        out[n, 5] = -a * x + b * y * z
        out[n, 6] = -a * y + b * x * z
        out[n, 7] = a * x + b * y * z
        out[n, 8] = 1.0 - b * (x * x + y * y)
    return out


@njit(cache=True, nogil=True)
def continuous_euler(flat, first_axis, middle_axis, last_axis, sign, start, lock_cos):
    """The loop behind :func:`upm.ops.rotations.continuous_euler_deg`: per frame the principal
    Tait-Bryan angles of ``flat`` (T, 9) (order ``first_axis, middle_axis, last_axis``;
    ``sign`` +1 for a cyclic order), the branch nearer the previous frame's, and whole
    turns removed along time from ``start`` (3,) as ``np.unwrap`` removes them."""
    n = flat.shape[0]
    out = np.empty((n, 3))
    i, j, k, e = first_axis, middle_axis, last_axis, sign
    prev_principal = np.empty(3)
    prev_alt = np.empty(3)
    principal = np.empty(3)
    alt = np.empty(3)
    chosen_prev = start.copy()
    correction = np.zeros(3)
    use_alt = False
    for t in range(n):
        m = flat[t]
        cos_middle = math.hypot(m[3 * i + i], m[3 * j + i])
        middle = math.atan2(-e * m[3 * k + i], cos_middle)
        if cos_middle < lock_cos:  # gimbal lock: only first +- last is defined; last = 0
            first = math.atan2(-e * m[3 * j + k], m[3 * j + j])
            last = 0.0
        else:
            first = math.atan2(e * m[3 * k + j], m[3 * k + k])
            last = math.atan2(e * m[3 * j + i], m[3 * i + i])
        principal[i], principal[j], principal[k] = first, middle, last
        for c in range(3):
            principal[c] = principal[c] * (180.0 / math.pi)
        alt[:] = principal
        alt[i] += 180.0
        alt[j] = 180.0 - alt[j]
        alt[k] += 180.0
        if t == 0:
            use_alt = _distance(alt, start) < _distance(principal, start)
        elif _distance(principal, prev_alt) < _distance(principal, prev_principal):
            use_alt = not use_alt
        prev_principal[:] = principal
        prev_alt[:] = alt
        for c in range(3):
            x = alt[c] if use_alt else principal[c]
            dd = x - chosen_prev[c]
            ddmod = (dd + 180.0) % 360.0 - 180.0
            if ddmod == -180.0 and dd > 0.0:
                ddmod = 180.0
            if abs(dd) >= 180.0:
                correction[c] += ddmod - dd
            out[t, c] = x + correction[c]
            chosen_prev[c] = x
    return out


@njit(cache=True, nogil=True)
def _distance(x, y):
    s = 0.0
    for c in range(3):
        d = (x[c] - y[c] + 180.0) % 360.0 - 180.0
        s += d * d
    return s
