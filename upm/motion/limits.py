"""Joint-limit excess of periodic angles."""

from __future__ import annotations

import numpy as np

#: CMU values sitting exactly on a limit carry float noise; this much is not a violation.
LIMIT_TOLERANCE_DEG = 1e-6


def limit_excess_deg(angle_deg, limits_deg, tolerance_deg: float = LIMIT_TOLERANCE_DEG):
    """Degrees by which each angle lies outside its limits, on the circle.

    The angle is compared modulo 360 (CMU angles are sometimes unwrapped past 360): the
    excess is the shorter way from the angle to the nearer end of its allowed arc, 0
    inside it (within ``tolerance_deg`` of either end).

    Parameters
    ----------
    angle_deg : array_like, shape (..., D)
    limits_deg : array_like, shape (D, 2)
        Lower and upper limit of each DOF, lower <= upper, span below 360.

    Returns
    -------
    ndarray, shape (..., D)
        Non-negative degrees.
    """
    limits = np.asarray(limits_deg, dtype=float)
    lo, hi = limits[:, 0], limits[:, 1]
    # measured from a tolerance below the lower end, so that a value a hair below it
    # (-3e-14 against 0) is inside instead of wrapping to nearly 360
    above_lo = np.mod(np.asarray(angle_deg, dtype=float) - lo + tolerance_deg,
                      360.0) - tolerance_deg
    span = hi - lo
    outside = above_lo > span + tolerance_deg
    excess = np.minimum(above_lo - span, 360.0 - above_lo)
    return np.where(outside, np.maximum(excess, 0.0), 0.0)


def outside_share(motion) -> tuple[float, float]:
    """Share of a motion's angle samples outside their ASF limits.

    Returns
    -------
    all_share : float
        Over every declared rotation DOF of every bone (the 21 joints and the
        non-articulated channels): the figure the CMU README quotes (3-17 %).
    posture_share : float
        Over the declared DOFs of the 63-value posture only.
    """
    skeleton = motion.skeleton
    declared = skeleton.declared
    posture_out = limit_excess_deg(motion.posture_deg[:, declared],
                                   skeleton.limits_deg[declared]) > 0
    n_posture = posture_out.size
    count = int(posture_out.sum())
    total = n_posture
    if motion.extra_deg is not None and motion.extra_deg.shape[1]:
        extra_out = limit_excess_deg(motion.extra_deg, skeleton.extra_limits_deg) > 0
        count += int(extra_out.sum())
        total += extra_out.size
    return count / total, float(posture_out.mean()) if n_posture else 0.0
