"""Rotation matrices from Acclaim Euler angles, batched over any leading shape."""

from __future__ import annotations

import numpy as np

_AXIS_INDEX = {"X": 0, "Y": 1, "Z": 2}


def axis_rotation(angle_deg, axis: str) -> np.ndarray:
    """Rotation matrices about one coordinate axis.

    Parameters
    ----------
    angle_deg : array_like, shape (...)
    axis : {"X", "Y", "Z"}

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Right-handed rotations (column vectors: ``v' = R @ v``).
    """
    theta = np.deg2rad(np.asarray(angle_deg, dtype=float))
    c, s = np.cos(theta), np.sin(theta)
    one, zero = np.ones_like(theta), np.zeros_like(theta)
    i = _AXIS_INDEX[axis]
    # Rows of the rotation about axis i; the other two axes (j, k) in cyclic order.
    j, k = (i + 1) % 3, (i + 2) % 3
    m = np.empty(theta.shape + (3, 3))
    m[..., i, i] = one
    m[..., i, j] = zero
    m[..., i, k] = zero
    m[..., j, i] = zero
    m[..., k, i] = zero
    m[..., j, j] = c
    m[..., j, k] = -s
    m[..., k, j] = s
    m[..., k, k] = c
    return m


def euler_to_matrix(angles_deg, order: str = "XYZ") -> np.ndarray:
    """Compose per-axis rotations, the first letter of ``order`` applied first.

    For Acclaim's ``XYZ``: ``R = Rz(angles[..., 2]) @ Ry(angles[..., 1]) @ Rx(angles[..., 0])``.
    ``angles_deg[..., i]`` is always the angle about X, Y, Z for i = 0, 1, 2, whatever
    the order.

    Parameters
    ----------
    angles_deg : array_like, shape (..., 3)
        Angles about X, Y and Z, in degrees.
    order : str
        A permutation of ``"XYZ"``: the order in which the rotations are applied.

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    a = np.asarray(angles_deg, dtype=float)
    if sorted(order) != ["X", "Y", "Z"]:
        raise ValueError(f"rotation order must be a permutation of XYZ, not {order!r}")
    result = None
    for axis in order:
        r = axis_rotation(a[..., _AXIS_INDEX[axis]], axis)
        result = r if result is None else r @ result
    return result
