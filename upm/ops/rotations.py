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


def _entries():
    """Flat positions in a (3 axes, 3, 3) array of the unit, cos, sin and -sin entries of
    the three axis rotations (as :func:`axis_rotation` lays them out)."""
    unit, cos, sin, minus_sin = [], [], [], []
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        unit.append(9 * i + 3 * i + i)
        cos += [9 * i + 3 * j + j, 9 * i + 3 * k + k]
        sin.append(9 * i + 3 * k + j)
        minus_sin.append(9 * i + 3 * j + k)
    # cos and sin of angle i fill their two / one entries of rotation i
    return (np.array(unit), np.array(cos).reshape(3, 2), np.array(sin),
            np.array(minus_sin))


_UNIT, _COS_PAIRS, _SIN, _MINUS_SIN = _entries()
_COS = _COS_PAIRS.T  # (2, 3): assigning c (..., 3) to each row fills both cos entries


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
    # The rotations about X, Y and Z at once (the entries of axis_rotation, placed by
    # index), then composed in order: a few array operations whatever the order.
    theta = np.deg2rad(a)
    c, s = np.cos(theta), np.sin(theta)
    m = np.zeros(a.shape[:-1] + (27,))
    m[..., _UNIT] = 1.0
    m[..., _COS] = c[..., None, :]
    m[..., _SIN] = s
    m[..., _MINUS_SIN] = -s
    m = m.reshape(a.shape[:-1] + (3, 3, 3))
    first, middle, last = (_AXIS_INDEX[axis] for axis in order)
    return m[..., last, :, :] @ (m[..., middle, :, :] @ m[..., first, :, :])


def _alternate_euler(angles_deg: np.ndarray, order: str) -> np.ndarray:
    """The other Tait-Bryan solution of the same rotation: the first and last angles of
    ``order`` + 180, the middle one 180 - itself. Same layout as the input (X, Y, Z)."""
    alt = np.array(angles_deg, dtype=float, copy=True)
    first, middle, last = (_AXIS_INDEX[a] for a in order)
    alt[..., first] += 180.0
    alt[..., middle] = 180.0 - alt[..., middle]
    alt[..., last] += 180.0
    return alt


#: Below this cosine of the middle angle, a rotation is taken as in gimbal lock.
_GIMBAL_LOCK_COS = 1e-12


def _nearest_turn(angles_deg: np.ndarray, near_deg: np.ndarray) -> np.ndarray:
    """Shift each angle by whole turns to lie within 180 degrees of ``near_deg``."""
    return angles_deg + 360.0 * np.round((near_deg - angles_deg) / 360.0)


def matrix_to_euler_deg(matrix, order: str = "XYZ", near_deg=None) -> np.ndarray:
    """Euler angles of rotation matrices: the inverse of :func:`euler_to_matrix`.

    A rotation has two Tait-Bryan solutions (and every whole-turn shift of them). Without
    ``near_deg`` the principal one is returned (middle angle in [-90, 90], the others in
    [-180, 180]); with it, the solution and turn nearest to ``near_deg`` (per frame, on
    the circle first, then shifted to lie within 180 degrees of it).

    Parameters
    ----------
    matrix : array_like, shape (..., 3, 3)
    order : str
        The rotation order (first letter applied first), as in :func:`euler_to_matrix`.
    near_deg : array_like, shape (..., 3), optional
        Reference angles (about X, Y, Z).

    Returns
    -------
    ndarray, shape (..., 3)
        Angles about X, Y, Z in degrees, whatever the order. At gimbal lock (middle angle
        +-90) the first and last angles are not unique; one valid pair is returned.
    """
    m = np.asarray(matrix, dtype=float)
    if sorted(order) != ["X", "Y", "Z"]:
        raise ValueError(f"rotation order must be a permutation of XYZ, not {order!r}")
    shape = m.shape[:-2]
    flat = m.reshape(-1, 3, 3)
    # R = R_k(last) R_j(middle) R_i(first) for order (i, j, k); e = +1 for cyclic orders.
    i, j, k = (_AXIS_INDEX[axis] for axis in order)
    e = 1.0 if (j - i) % 3 == 1 else -1.0
    cos_middle = np.hypot(flat[:, i, i], flat[:, j, i])
    middle = np.arctan2(-e * flat[:, k, i], cos_middle)
    first = np.arctan2(e * flat[:, k, j], flat[:, k, k])
    last = np.arctan2(e * flat[:, j, i], flat[:, i, i])
    locked = cos_middle < _GIMBAL_LOCK_COS
    if locked.any():
        # Only first + last (or first - last) is defined: take last = 0.
        first[locked] = np.arctan2(-e * flat[locked, j, k], flat[locked, j, j])
        last[locked] = 0.0
    angles = np.empty(flat.shape[:1] + (3,))
    angles[:, i], angles[:, j], angles[:, k] = first, middle, last
    np.degrees(angles, out=angles)
    angles = angles.reshape(shape + (3,))
    if near_deg is None:
        return angles
    near = np.broadcast_to(np.asarray(near_deg, dtype=float), angles.shape)
    alt = _alternate_euler(angles, order)

    def distance(candidate):
        d = np.mod(candidate - near + 180.0, 360.0) - 180.0
        return np.einsum("...i,...i->...", d, d)

    use_alt = distance(alt) < distance(angles)
    chosen = np.where(use_alt[..., None], alt, angles)
    return _nearest_turn(chosen, near)


def continuous_euler_deg(matrix, order: str, start_deg) -> np.ndarray:
    """Euler angles of a rotation sequence that change continuously from ``start_deg``.

    Each frame takes the Tait-Bryan solution (of the two) and the whole turn nearest to
    the previous frame's angles, so a smooth rotation path gives angles without
    360-degree or branch jumps (except through gimbal lock, where the angles of any
    representation change fast): the principal solution switches branch at frame t when
    it is nearer the previous frame's alternate solution than its principal one.

    Parameters
    ----------
    matrix : array_like, shape (T, 3, 3)
        Rotations along time.
    order : str
        Rotation order, as in :func:`euler_to_matrix`.
    start_deg : array_like, shape (3,)
        The angles just before the first frame (about X, Y, Z): the output continues
        from them.

    Returns
    -------
    ndarray, shape (T, 3)
    """
    from upm.ops.rotation_kernels import continuous_euler

    m = np.asarray(matrix, dtype=float)
    if sorted(order) != ["X", "Y", "Z"]:
        raise ValueError(f"rotation order must be a permutation of XYZ, not {order!r}")
    if m.shape[0] == 0:
        return np.zeros((0, 3))
    # The principal solution as matrix_to_euler_deg gives it; branch and turns in one
    # compiled pass along time (:func:`upm.ops.rotation_kernels.continuous_euler`).
    i, j, k = (_AXIS_INDEX[axis] for axis in order)
    return continuous_euler(np.ascontiguousarray(m.reshape(-1, 9)), i, j, k,
                            1.0 if (j - i) % 3 == 1 else -1.0,
                            np.array(start_deg, dtype=float).reshape(3), _GIMBAL_LOCK_COS)


def matrix_to_quaternion(matrix) -> np.ndarray:
    """Unit quaternions ``(w, x, y, z)`` of rotation matrices, with ``w >= 0``.

    Shepperd's method: the largest of the four diagonal combinations gives the
    best-conditioned row (compiled loop: :mod:`upm.ops.rotation_kernels`).

    Parameters
    ----------
    matrix : array_like, shape (..., 3, 3)

    Returns
    -------
    ndarray, shape (..., 4)
    """
    from upm.ops.rotation_kernels import quaternions

    m = np.asarray(matrix, dtype=float)
    return quaternions(np.ascontiguousarray(m.reshape(-1, 9))).reshape(m.shape[:-2] + (4,))


def rotation_log(matrix) -> np.ndarray:
    """Rotation vectors (axis times angle, radians, angle in [0, pi]) of rotation matrices.

    Parameters
    ----------
    matrix : array_like, shape (..., 3, 3)

    Returns
    -------
    ndarray, shape (..., 3)
    """
    from upm.ops.rotation_kernels import logs

    m = np.asarray(matrix, dtype=float)
    return logs(np.ascontiguousarray(m.reshape(-1, 9))).reshape(m.shape[:-2] + (3,))


def rotation_exp(rotvec) -> np.ndarray:
    """Rotation matrices of rotation vectors (radians): Rodrigues' formula.

    Parameters
    ----------
    rotvec : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    from upm.ops.rotation_kernels import exps

    v = np.asarray(rotvec, dtype=float)
    return exps(np.ascontiguousarray(v.reshape(-1, 3))).reshape(v.shape[:-1] + (3, 3))
