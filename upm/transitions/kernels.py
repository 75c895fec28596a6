"""Compiled loops behind a transition's element-wise steps (numba, cached on disk).

A transition works on a few frames at a time, where each numpy call costs more in its
fixed overhead than in its arithmetic; here each step is one call. Every loop does the
numpy code's operations in the same order, so that its results are the same to the last
bit (additions, products, quotients, ``%`` and rounding are correctly rounded IEEE
operations either way; ``math.cos``/``math.sin`` call the same C library as numpy's
float64 loops). The steps that would not be bit-identical -- matrix products (numpy hands
them to BLAS, whose kernels fuse multiply-adds), numpy's ``arctan2`` and sums (numpy adds
pairwise) -- stay numpy calls in the callers.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def dropout_candidates(posture):
    """The joints of a 21-joint posture ``(T, 63)`` whose three angles are all exactly zero
    in some frames but not in every frame: the only joints that can hold a marker dropout
    (:mod:`upm.motion.dropouts`). Returns their indices, ascending."""
    n_frames, n_joints = posture.shape[0], posture.shape[1] // 3
    found = np.empty(n_joints, dtype=np.int64)
    count = 0
    for j in range(n_joints):
        zero_frames = 0
        for t in range(n_frames):
            if posture[t, 3 * j] == 0.0 and posture[t, 3 * j + 1] == 0.0 \
                    and posture[t, 3 * j + 2] == 0.0:
                zero_frames += 1
        if 0 < zero_frames < n_frames:
            found[count] = j
            count += 1
    return found[:count]


@njit(cache=True, nogil=True, inline="always")
def _unwrap_into(p, out):
    """``upm.ops.angles.unwrap_deg(p)`` (= ``np.unwrap(p, period=360, axis=0)``) into
    ``out``: the same operations, the correction summed along time as ``cumsum`` does."""
    out[0] = p[0]
    for d in range(p.shape[1]):
        total = 0.0
        for t in range(1, p.shape[0]):
            dd = p[t, d] - p[t - 1, d]
            ddmod = (dd + 180.0) % 360.0 - 180.0
            if ddmod == -180.0 and dd > 0.0:
                ddmod = 180.0
            correction = ddmod - dd
            if abs(dd) < 180.0:
                correction = 0.0
            total = correction if t == 1 else total + correction
            out[t, d] = p[t, d] + total


@njit(cache=True, nogil=True)
def window_context(before, after):
    """The context postures of a window problem (:func:`upm.transitions.join.make_problem`):
    ``before`` (K1, D) and ``after`` (K2, D) unwrapped along time, ``after`` then shifted by
    ``360 * round((before[-1] - after[0]) / 360)`` per DOF (B within 180 degrees of A)."""
    before_deg = np.empty(before.shape)
    after_deg = np.empty(after.shape)
    _unwrap_into(before, before_deg)
    _unwrap_into(after, after_deg)
    last = before_deg.shape[0] - 1
    for d in range(after.shape[1]):
        shift = 360.0 * np.rint((before_deg[last, d] - after_deg[0, d]) / 360.0)
        for t in range(after.shape[0]):
            after_deg[t, d] = after_deg[t, d] + shift
    return before_deg, after_deg


@njit(cache=True, nogil=True, inline="always")
def _wrap(x):
    """``upm.ops.angles.wrap_deg`` of one value."""
    w = (x + 180.0) % 360.0 - 180.0
    return w - 360.0 if w >= 180.0 else w


@njit(cache=True, nogil=True)
def wrap_window(posture, declared):
    """The window's postures ``(L, D)`` wrapped to [-180, 180), undeclared DOFs 0."""
    out = np.empty(posture.shape)
    for t in range(posture.shape[0]):
        for d in range(posture.shape[1]):
            out[t, d] = _wrap(posture[t, d]) if declared[d] else 0.0
    return out


@njit(cache=True, nogil=True)
def wrap_pair(a, b):
    """``wrap_deg(a)`` and ``wrap_deg(b)`` of two ``(D,)`` postures."""
    out_a, out_b = np.empty(a.shape), np.empty(b.shape)
    for d in range(a.shape[0]):
        out_a[d] = _wrap(a[d])
        out_b[d] = _wrap(b[d])
    return out_a, out_b


@njit(cache=True, nogil=True)
def key_on_turn(key, a, b, alpha):
    """A key posture ``key`` (D,) from a source, against A and B (D,) and ``alpha``:
    ``wrap_deg(key)``, the key on the turn nearest the alpha-point ``c = a + alpha (b -
    a)`` (``c + angle_diff_deg(key, c)``), the squared differences ``(key_on_turn - c)**2``
    (summed by the caller) and whether every value of ``key`` is finite."""
    wrapped, near, squares = np.empty(key.shape), np.empty(key.shape), np.empty(key.shape)
    finite = True
    for d in range(key.shape[0]):
        finite = finite and math.isfinite(key[d])
        c = a[d] + alpha * (b[d] - a[d])
        wrapped[d] = _wrap(key[d])
        near[d] = c + _wrap(key[d] - c)
        squares[d] = (near[d] - c) ** 2
    return wrapped, near, squares, finite


@njit(cache=True, nogil=True)
def linear_extra(a, b, frames):
    """The extra channels' window: ``wrap_deg(a + s * wrap_deg(b - a))`` at ``s = t / (L +
    1)``, ``t = 1 .. L`` (``frames`` = L), for ``a``, ``b`` (E,)."""
    out = np.empty((frames, a.shape[0]))
    for t in range(frames):
        s = (t + 1) / (frames + 1)
        for e in range(a.shape[0]):
            out[t, e] = _wrap(a[e] + s * _wrap(b[e] - a[e]))
    return out


@njit(cache=True, nogil=True)
def axis_factors(angles_deg):
    """The rotations about X, Y and Z of Euler angles ``(N, 3)`` degrees, ``(N, 3, 3, 3)``:
    ``[n, i]`` is the rotation by ``angles_deg[n, i]`` about axis i, entry for entry as
    :func:`upm.ops.rotations.euler_to_matrix` lays them out before composing them."""
    m = np.zeros((angles_deg.shape[0], 3, 3, 3))
    for n in range(angles_deg.shape[0]):
        for i in range(3):
            theta = angles_deg[n, i] * (math.pi / 180.0)
            c, s = math.cos(theta), math.sin(theta)
            j, k = (i + 1) % 3, (i + 2) % 3
            m[n, i, i, i] = 1.0
            m[n, i, j, j] = c
            m[n, i, k, k] = c
            m[n, i, k, j] = s
            m[n, i, j, k] = -s
    return m


@njit(cache=True, nogil=True)
def root_path(before, after, relative, frames, alpha, window, new_after):
    """The horizontal velocity blend of :func:`upm.transitions.root.blend_root`: fills
    ``window[:, (0, 2)]`` (L, 6) and ``new_after[:, :3]`` (T2, 6) from the roots ``before``
    (T1, 6) and ``after`` (T2, 6) and clip 2's turned translation ``relative`` (T2, 3)
    relative to B. Returns the key height ``ty_A + alpha (ty_B - ty_A)``."""
    last = before.shape[0] - 1
    for h in (0, 2):
        v1 = before[last, h] - before[last - 1, h] if before.shape[0] > 1 else 0.0
        v2 = relative[1, h] if after.shape[0] > 1 else 0.0
        total = 0.0
        for i in range(frames + 1):
            w = i / frames
            step = (1.0 - w) * v1 + w * v2
            total = step if i == 0 else total + step
            position = before[last, h] + total
            if i < frames:
                window[i, h] = position
            else:
                for t in range(after.shape[0]):
                    new_after[t, h] = position + relative[t, h]
    for t in range(after.shape[0]):
        new_after[t, 1] = after[t, 1]
    return before[last, 1] + alpha * (after[0, 1] - before[last, 1])


@njit(cache=True, nogil=True)
def root_keys(before, key_height, after, vectors, k1, k2):
    """The root splines' key values (k1 + 1 + k2, 4): height, then rotation vector; clip
    1's last ``k1`` frames, the key (height ``key_height``, rotation vector 0), clip 2's
    first ``k2`` frames (``vectors`` (k1 + k2, 3): the context's rotation vectors)."""
    keys = np.zeros((k1 + 1 + k2, 4))
    first = before.shape[0] - k1
    for r in range(k1):
        keys[r, 0] = before[first + r, 1]
        keys[r, 1:] = vectors[r]
    keys[k1, 0] = key_height
    for r in range(k2):
        keys[k1 + 1 + r, 0] = after[r, 1]
        keys[k1 + 1 + r, 1:] = vectors[k1 + r]
    return keys
