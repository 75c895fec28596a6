"""Widening the literature's human ranges to the real motion of the train split.

The literature gives clinical ranges (a goniometer, one joint at a time); real motion
capture adds the joint centres' estimation error and people beyond the norm (dancers).
:func:`refine` widens each range to the train split's extreme values — the 0.05th and
99.95th percentiles, plus :data:`MARGIN_DEG` — by at most
:data:`upm.motion.human_rom.MAX_WIDEN_DEG`, so that a flipped marker solve stays invalid.
"""

from __future__ import annotations

import numpy as np

from upm.motion.anatomy import JOINT_KIND, anatomical_angles_deg
from upm.motion.human_rom import (
    BALL_LITERATURE,
    BALL_PLANES_DEG,
    MAX_WIDEN_DEG,
    columns_rule,
    euler_names,
    literature_box,
    swing_rule,
)
from upm.motion.skeleton import JOINTS

#: Degrees added beyond the train split's extreme percentiles.
MARGIN_DEG = 2.0
#: The percentiles taken as the train split's extremes.
PERCENTILES = (0.05, 99.95)
#: Frames below this elevation leave the plane of elevation undefined, degrees.
MIN_ELEVATION_DEG = 20.0
#: Half-width of the frames' planes counted for each tabulated plane, degrees.
PLANE_HALF_WIDTH_DEG = 22.5


def pooled_angles(motions) -> dict[str, np.ndarray]:
    """Every joint's anatomical angles over some motions, concatenated by joint."""
    pooled: dict[str, list] = {}
    for motion in motions:
        for joint, value in anatomical_angles_deg(motion.skeleton, motion.posture_deg).items():
            pooled.setdefault(joint, []).append(value)
    return {joint: np.concatenate(values) for joint, values in pooled.items()}


def _widen_box(values: np.ndarray, low: float, high: float) -> tuple[float, float] | None:
    q_low, q_high = np.percentile(values, PERCENTILES)
    new_low = max(min(low, q_low - MARGIN_DEG), low - MAX_WIDEN_DEG)
    new_high = min(max(high, q_high + MARGIN_DEG), high + MAX_WIDEN_DEG)
    if new_low == low and new_high == high:
        return None
    return (round(float(new_low), 1), round(float(new_high), 1))


def refine(motions) -> dict[str, tuple[float, float]]:
    """The train-widened ranges (:data:`upm.motion.human_rom.TRAIN_WIDENED`) of motions.

    Parameters
    ----------
    motions : iterable of upm.Motion
        The train split's clips.

    Returns
    -------
    dict of str to (float, float)
        ``rule -> (low, high)`` degrees for every widened box rule, and
        ``"lfemur.swing@45" -> (0, elevation)`` for every widened plane of a hip or
        shoulder.
    """
    angles = pooled_angles(motions)
    out: dict[str, tuple[float, float]] = {}
    for joint in JOINTS:
        kind, value = JOINT_KIND[joint], angles[joint]
        if kind == "hinge":
            rule = columns_rule(joint, "flexion")
            widened = _widen_box(value, *literature_box(rule))
            if widened:
                out[rule] = widened
        elif kind == "euler":
            for k, axis in enumerate(euler_names(joint)):
                rule = f"{joint}.{axis}"
                widened = _widen_box(value[:, k], *literature_box(rule))
                if widened:
                    out[rule] = widened
        else:
            out.update(_refine_ball(joint, value))
    return out


def _refine_ball(joint: str, value: np.ndarray) -> dict[str, tuple[float, float]]:
    from upm.motion.anatomy import base_name

    out = {}
    rule = f"{joint}.twist"
    widened = _widen_box(value[:, 2], *literature_box(rule))
    if widened:
        out[rule] = widened
    elevation, plane = value[:, 0], value[:, 1]
    limits = BALL_LITERATURE[base_name(joint)][0]
    for k, centre in enumerate(BALL_PLANES_DEG):
        near = np.abs((plane - centre + 180.0) % 360.0 - 180.0) <= PLANE_HALF_WIDTH_DEG
        chosen = elevation[near & (elevation >= MIN_ELEVATION_DEG)]
        if chosen.size < 20:
            continue
        q = float(np.percentile(chosen, PERCENTILES[1])) + MARGIN_DEG
        new = min(max(limits[k], q), limits[k] + MAX_WIDEN_DEG, 180.0)
        if new > limits[k]:
            out[swing_rule(joint, centre)] = (0.0, round(new, 1))
    return out
