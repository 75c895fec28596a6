"""The root across a transition (paper section 3.2), shared by every method.

- **Horizontal position** (tx, tz): the paper's velocity blend. Clip 1's velocity v1 at A
  (its last step) and clip 2's v2 at B (its first step, after the turn below) are blended
  linearly over the L + 1 steps from A to B and integrated: step i (i = 1 .. L+1) is
  ``v1 (1 - w_i) + v2 w_i`` with ``w_i = (i - 1) / L``, so the first step out of A is
  exactly clip 1's last step and the last step into B exactly clip 2's first step
  (positions and velocities join, C1). Clip 2 is then moved to start where the blend
  ends: the paper's ``p(t) = p(t2) + n(t)``.
- **Heading**: beyond the paper (it says nothing on the subject), clip 2 is turned about
  the vertical (ASF y) axis, positions and orientation, so that its heading at B equals
  clip 1's heading at A. Heading is the twist about y of the root orientation
  (``R = Ry(heading) S`` with S about a horizontal axis); it is undefined only for a
  body upside down. Can be switched off (``align_heading=False``).
- **Height** (ty) and **orientation**: the paper's "linear interpolation smoothed by the
  B-spline": the key value at the window's middle is the linear interpolation at alpha
  between A and B (height: ``ty_A + alpha (ty_B - ty_A)``; orientation: the slerp), and
  a cubic B-spline passes through the last frames of clip 1, that key and the first
  frames of clip 2. The orientation spline runs in rotation-vector space around the key
  orientation (not on the Euler angles: the CMU root order XYZ is in gimbal lock
  whenever the body faces +-x, and the clips' own Euler angles reach 1251 degrees).
  The window's and clip 2's Euler angles are then written continuing from A's (no
  360-degree or branch jumps).
- **Other subjects**: clip 2's root translation is scaled by the ratio of the subjects'
  leg lengths (rest-pose root height above the lowest bone end), so that with clip 1's
  skeleton its feet stay near the floor and its steps match the legs (see
  :func:`leg_length_m`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from upm.motion.skeleton import Skeleton
from upm.ops.angles import wrap_deg
from upm.ops.rotations import (
    _AXIS_INDEX,
    continuous_euler_deg,
    matrix_to_quaternion,
    rotation_exp,
    rotation_log,
)
from upm.transitions import kernels
from upm.transitions.spline import SPLINE_CONTEXT, window_weights


@dataclass(frozen=True)
class RootBlend:
    """The root of a transition.

    Attributes
    ----------
    window : ndarray, shape (L, 6)
        The window's root: tx, ty, tz metres, rx, ry, rz degrees.
    after : ndarray, shape (T2, 6)
        Clip 2's root, turned and moved to continue from the window.
    heading_turn_deg : float
        The turn about the vertical applied to clip 2.
    """

    window: np.ndarray
    after: np.ndarray
    heading_turn_deg: float


def heading_deg(matrix) -> np.ndarray:
    """Heading of root orientations: the twist about the vertical (y) axis.

    Parameters
    ----------
    matrix : array_like, shape (..., 3, 3)

    Returns
    -------
    ndarray, shape (...)
        Degrees in [-180, 180): the angle theta of ``R = Ry(theta) S`` where S turns
        about a horizontal axis.
    """
    return _heading_of_quaternion(matrix_to_quaternion(matrix))


@functools.lru_cache(maxsize=8)
def _order_axes(order: str) -> tuple[int, int, int]:
    """The axis indices (first applied first) of a rotation order, a permutation of XYZ."""
    if sorted(order) != ["X", "Y", "Z"]:
        raise ValueError(f"rotation order must be a permutation of XYZ, not {order!r}")
    return tuple(_AXIS_INDEX[axis] for axis in order)


def _wrap(angle_deg: float) -> float:
    """:func:`upm.ops.angles.wrap_deg` of one float (the same operations)."""
    wrapped = (angle_deg + 180.0) % 360.0 - 180.0
    return wrapped - 360.0 if wrapped >= 180.0 else wrapped


def _heading_of_quaternion(q) -> np.ndarray:
    """:func:`heading_deg` from unit quaternions ``(..., 4)`` (w, x, y, z; w >= 0)."""
    return wrap_deg(2.0 * np.degrees(np.arctan2(q[..., 2], q[..., 0])))


@functools.lru_cache(maxsize=32)
def leg_length_m(skeleton: Skeleton) -> float:
    """Rest-pose height of the root above the skeleton's lowest bone end, metres.

    CMU captures put the floor near y = 0, with the standing root at about this height
    (0.80-0.97 m over the 12 subjects here).
    """
    from upm.motion.kinematics import rest_positions

    return float(-rest_positions(skeleton)[:, 1].min())


def _multiply(p, q):
    """Hamilton product of quaternions given as (w, x, y, z) tuples of floats."""
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return (pw * qw - px * qx - py * qy - pz * qz, pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx, pw * qz + px * qy - py * qx + pz * qw)


def _key_rotation(quat_a, quat_b, turn_deg: float, s: float) -> np.ndarray:
    """The slerp at ``s`` from A to B turned by ``turn_deg`` about the vertical: the
    rotation ``A exp(s log(A^T Ry(turn) B))`` (3, 3), the short way round, worked on
    unit quaternions (w, x, y, z) in plain floats: a handful of scalar operations
    instead of a matrix logarithm and exponential of one matrix each."""
    half_turn = 0.5 * math.radians(turn_deg)
    b = _multiply((math.cos(half_turn), 0.0, math.sin(half_turn), 0.0), tuple(quat_b))
    aw, ax, ay, az = quat_a
    r = _multiply((aw, -ax, -ay, -az), b)
    if r[0] < 0.0:
        r = tuple(-c for c in r)
    sine = math.sqrt(r[1] * r[1] + r[2] * r[2] + r[3] * r[3])
    if sine > 1e-12:
        half = s * math.atan2(sine, r[0])
        f = math.sin(half) / sine
        step = (math.cos(half), f * r[1], f * r[2], f * r[3])
    else:
        step = (1.0, 0.0, 0.0, 0.0)
    w, x, y, z = _multiply((aw, ax, ay, az), step)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def blend_root(before_root, after_root, frames: int, alpha: float, order: str,
               align_heading: bool = True, context: int = SPLINE_CONTEXT) -> RootBlend:
    """The root of the window, and clip 2's root re-anchored after it.

    Parameters
    ----------
    before_root : array_like, shape (T1, 6)
        Clip 1's root (T1 >= 1), ending at A.
    after_root : array_like, shape (T2, 6)
        Clip 2's root (T2 >= 1), starting at B (same frame rate and scale as clip 1).
    frames : int
        L >= 1.
    alpha : float
        Where the key orientation and height sit between A and B (0 is A, 1 is B).
    order : str
        The root's rotation order (``skeleton.root_axis_order``).
    align_heading : bool
        Turn clip 2 about the vertical so its heading at B is clip 1's at A.
    context : int
        Frames of each clip the height and orientation splines pass through.

    Returns
    -------
    RootBlend
    """
    before = np.asarray(before_root, dtype=float)
    after = np.asarray(after_root, dtype=float)
    k1, k2 = min(context, before.shape[0]), min(context, after.shape[0])

    # Few calls, each over every frame that needs it: a small numpy call costs its fixed
    # overhead, not its arithmetic. The element-wise steps are compiled
    # (:mod:`upm.transitions.kernels`, the same operations); matrix products and arctan2
    # stay numpy's, so that the root is the same to the last bit.
    factors = kernels.axis_factors(np.concatenate([before[-k1:, 3:], after[:, 3:]]))
    first, middle, last = _order_axes(order)
    rotations = factors[:, last] @ (factors[:, middle] @ factors[:, first])  # euler_to_matrix
    rot_before, rot_after = rotations[:k1], rotations[k1:]
    quats = matrix_to_quaternion(rotations[k1 - 1:k1 + 1])
    quat_a, quat_b = quats.tolist()
    turn = 0.0
    if align_heading:
        # _heading_of_quaternion, its arctan2 on the same (2,) arrays, the rest on floats
        heading_a, heading_b = np.arctan2(quats[:, 2], quats[:, 0]).tolist()
        turn = _wrap(_wrap(2.0 * math.degrees(heading_a)) - _wrap(2.0 * math.degrees(heading_b)))
    theta = math.radians(turn)
    c, s = math.cos(theta), math.sin(theta)
    turn_matrix = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])  # axis_rotation Y
    rot_after = turn_matrix @ rot_after

    # Clip 2's translation relative to B, turned with it; the horizontal velocity blend.
    relative = (after[:, :3] - after[0, :3]) @ turn_matrix.T
    window = np.empty((frames, 6))
    new_after = np.empty_like(after)
    key_height = kernels.root_path(before, after, relative, frames, alpha, window, new_after)

    key_rot = _key_rotation(quat_a, quat_b, turn, alpha)
    context_rots = np.concatenate([rot_before, rot_after[:k2]])
    vectors = rotation_log(key_rot.T @ context_rots)
    # Height and rotation vector through the same key times: one spline.
    keys = kernels.root_keys(before, key_height, after, vectors, k1, k2)
    splined = window_weights(k1, k2, frames) @ keys
    window[:, 1] = splined[:, 0]
    window_rots = key_rot @ rotation_exp(splined[:, 1:])

    euler = continuous_euler_deg(np.concatenate([window_rots, rot_after]), order,
                                 before[-1, 3:])
    window[:, 3:] = euler[:frames]
    new_after[:, 3:] = euler[frames:]
    return RootBlend(window=window, after=new_after, heading_turn_deg=turn)
