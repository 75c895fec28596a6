"""Frame-rate resampling of a motion (e.g. CMU's 60 fps subjects to 120 fps).

Joint angles, non-articulated channels and the root translation are interpolated with a
cubic spline along time after unwrapping the angles (a DOF that crosses +-180 between two
frames is not sent the long way round); the root orientation with a cubic rotation spline
(scipy's ``RotationSpline``, free of Euler gimbal lock), turned back into the root's Euler
angles continuing from the first frame. The new frames are ``k / fps`` seconds after the
first one, up to the last original frame; where a new frame falls on an original one it
reproduces it (angles modulo 360: the result is continuous along time, i.e. unwrapped).
Downsampling interpolates too (no low-pass filter): fine for mocap, which holds little
energy above 30 Hz.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import make_interp_spline
from scipy.spatial.transform import Rotation, RotationSpline, Slerp

from upm.core.errors import UsageError
from upm.motion.motion import Motion
from upm.ops.angles import unwrap_deg
from upm.ops.rotations import continuous_euler_deg, euler_to_matrix


def _spline(times_s: np.ndarray, values: np.ndarray, new_times_s: np.ndarray) -> np.ndarray:
    if values.shape[1] == 0:
        return np.zeros((new_times_s.size, 0))
    degree = min(3, times_s.size - 1)
    return make_interp_spline(times_s, values, k=degree, axis=0)(new_times_s)


def resample(motion: Motion, fps: float) -> Motion:
    """The motion at another frame rate.

    Parameters
    ----------
    motion : Motion
        T frames at ``motion.fps``.
    fps : float
        The new frame rate (positive).

    Returns
    -------
    Motion
        ``floor((T - 1) * fps / motion.fps) + 1`` frames at ``fps`` (the same motion if
        the rate is already ``fps``).

    Raises
    ------
    UsageError
        If ``fps`` is not a positive finite number.
    """
    fps = float(fps)
    if not (math.isfinite(fps) and fps > 0):
        raise UsageError(f"frame rate must be a positive number, not {fps}")
    if fps == motion.fps or motion.n_frames < 2:
        return motion.replace(fps=fps)
    old_t = np.arange(motion.n_frames) / motion.fps
    n_new = int(math.floor((motion.n_frames - 1) * fps / motion.fps + 1e-9)) + 1
    new_t = np.arange(n_new) / fps
    posture = _spline(old_t, unwrap_deg(motion.posture_deg), new_t)
    extra = None
    if motion.extra_deg is not None:
        extra = _spline(old_t, unwrap_deg(motion.extra_deg), new_t)
    root = np.empty((n_new, 6))
    root[:, :3] = _spline(old_t, motion.root[:, :3], new_t)
    root[:, 3:] = _resample_orientation(motion, old_t, new_t)
    return motion.replace(posture_deg=posture, root=root, extra_deg=extra, fps=fps)


def _resample_orientation(motion: Motion, old_t: np.ndarray, new_t: np.ndarray) -> np.ndarray:
    """Root Euler angles at ``new_t`` from a rotation spline through the original frames."""
    order = motion.skeleton.root_axis_order
    matrices = euler_to_matrix(motion.root[:, 3:], order)
    rotations = Rotation.from_matrix(matrices)
    if old_t.size >= 3:
        new_matrices = RotationSpline(old_t, rotations)(new_t).as_matrix()
    else:
        new_matrices = Slerp(old_t, rotations)(new_t).as_matrix()
    return continuous_euler_deg(new_matrices, order, motion.root[0, 3:])
