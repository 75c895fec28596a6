"""The range a ``feasible`` window must stay in: each DOF's box of the human range of motion
(:func:`upm.motion.human_boxes.human_dof_boxes`, the humanoid's hinge ranges) widened by
what the two end postures already exceed, and the DOFs whose short way crosses a limit
(taken the long way round)."""

from __future__ import annotations

import numpy as np

from upm.motion.human_boxes import human_dof_boxes
from upm.motion.limits import limit_excess_deg
from upm.transitions.base import WindowProblem

#: Frames are kept this far inside the allowed range (degrees): the study counts excess
#: beyond 1e-6 degrees.
RANGE_MARGIN_DEG = 1e-4


def long_way_turns(problem: WindowProblem) -> np.ndarray:
    """Per DOF, the whole turns (-1, 0 or +1) to add to clip 2 so that A -> B stays inside
    the allowed arc: nonzero where the arc is less than a full turn and the short way from
    A to B leaves it but the long way does not (a joint cannot turn through its limit;
    with the arc widened by the ends' excess, this happens on real pairs, e.g. a foot's rz
    beyond its box at B).

    Returns
    -------
    ndarray of float, shape (63,)
    """
    lo, hi, _ = _widened(problem)
    a, b = problem.a_deg, problem.b_deg
    shift = 360.0 * np.floor((a - lo + 1e-6) / 360.0)
    lo_t, hi_t = lo + shift, hi + shift
    tolerance = 1e-5
    turns = np.zeros_like(a)
    for k in (-1.0, 1.0):
        moved = b + 360.0 * k
        fits = ((b < lo_t - tolerance) | (b > hi_t + tolerance)) & (
            moved >= lo_t - tolerance) & (moved <= hi_t + tolerance)
        turns[fits & problem.skeleton.declared & (hi - lo < 360.0 - 1e-6)] = k
    return turns


def range_boxes_deg(skeleton) -> np.ndarray:
    """The boxes ``feasible`` keeps every window frame in, (63, 2) degrees: the human
    range's box per DOF (the humanoid's hinge ranges), not the ASF's nominal limits."""
    return human_dof_boxes(skeleton)


def _widened(problem: WindowProblem):
    limits = range_boxes_deg(problem.skeleton)
    ends = limit_excess_deg(np.stack([problem.a_deg, problem.b_deg]), limits)
    widen = ends.max(axis=0)
    return limits[:, 0] - widen, limits[:, 1] + widen, widen


def allowed_range(problem: WindowProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                   np.ndarray]:
    """The allowed range of each DOF on the turn of the window's (unwrapped) angles.

    Returns
    -------
    lower_deg, upper_deg : ndarray, shape (63,)
        Bounds for the window's frames, on A's turn, ``RANGE_MARGIN_DEG`` inside.
    constrained : ndarray of bool, shape (63,)
        DOFs with a bound: declared, range below a full turn, and B (as the problem has
        it: see :func:`long_way_turns`) inside the arc on A's turn.
    widen_deg : ndarray, shape (63,)
        The larger of A's and B's excess beyond the range's boxes, per DOF.
    """
    lo, hi, widen = _widened(problem)
    a, b = problem.a_deg, problem.b_deg
    shift = 360.0 * np.floor((a - lo + 1e-6) / 360.0)
    lo_t, hi_t = lo + shift, hi + shift
    tolerance = 1e-5
    constrained = (problem.skeleton.declared & (hi - lo < 360.0 - 1e-6)
                   & (a >= lo_t - tolerance) & (a <= hi_t + tolerance)
                   & (b >= lo_t - tolerance) & (b <= hi_t + tolerance))
    lower = np.minimum(lo_t, np.minimum(a, b))
    upper = np.maximum(hi_t, np.maximum(a, b))
    # Inside even when an end sits on the widened bound (a window frame there equal to the
    # end up to rounding would count as added excess).
    margin = np.minimum(RANGE_MARGIN_DEG, 0.25 * (upper - lower))
    lower, upper = lower + margin, upper - margin
    return lower, upper, constrained, widen


def limit_turns(problem: WindowProblem, lower_deg, upper_deg, constrained,
                tolerance_deg: float = 1e-3) -> np.ndarray:
    """DOFs whose C1 join would need a window frame beyond the range: the end posture
    sits on its bound and the clip moves outward across it (at A: clip 1 arriving at the
    bound; at B: clip 2 leaving it inward, which seen from the window is arriving from
    beyond). There the range wins: the spline keeps the clip's slope at the join but
    turns back between the join and the next frame, so the frames show the turn.

    Returns
    -------
    ndarray of bool, shape (2, 63)
        At A, at B.
    """
    v_a = end_velocity(problem.before_deg, True)
    v_b = end_velocity(problem.after_deg, False)
    a, b = problem.a_deg, problem.b_deg
    at_a = constrained & (((a >= upper_deg - tolerance_deg) & (v_a > 0))
                          | ((a <= lower_deg + tolerance_deg) & (v_a < 0)))
    at_b = constrained & (((b >= upper_deg - tolerance_deg) & (v_b < 0))
                          | ((b <= lower_deg + tolerance_deg) & (v_b > 0)))
    return np.stack([at_a, at_b])


def end_velocity(frames_deg: np.ndarray, at_end: bool) -> np.ndarray:
    """Velocity (deg/frame) at the last (``at_end``) or first frame of a clip piece:
    second-order one-sided difference with 3 frames, first-order with 2, 0 with 1."""
    f = frames_deg if at_end else frames_deg[::-1]
    sign = 1.0 if at_end else -1.0
    if f.shape[0] >= 3:
        return sign * (1.5 * f[-1] - 2.0 * f[-2] + 0.5 * f[-3])
    if f.shape[0] == 2:
        return sign * (f[-1] - f[-2])
    return np.zeros(f.shape[1])
