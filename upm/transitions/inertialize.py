"""``inertialize``: offset decay with Bollo's quintic (GDC 2016/2018, Gears of War).

Inertialization switches to the target motion at once and adds an offset that starts at
(source - target) and decays to zero. Here the window is *inserted* between A and B, so
there is no live target during it; the choice made here:

- the **target** during the window is clip 2 extrapolated backwards from B at its
  starting velocity: ``target(t) = B + v_B (t - (L + 1))``;
- the **source** is clip 1, seen only through its state at A: the offset starts at
  ``x0 = A - target(0)`` with velocity ``v0 = v_A - v_B`` (per DOF, degrees per frame);
- the offset follows Bollo's quintic, reaching zero with zero velocity and acceleration
  at B (blend time ``t1 = L + 1``), its initial acceleration ``a0 = -(8 v0 t1 + 20 x0) /
  t1^2`` as in his talk.

Bollo's velocity clamp (an offset moving away from zero starts still) and his shortened
blend time (``-5 x0 / v0``) are left out: with a live target they avoid overshoot, but
here they would break the velocity join at A. Continuity: C1 at both edges (the window
leaves A with clip 1's velocity and reaches B with clip 2's). Holden's "dead blending"
(extrapolate the source, cross-fade to the target) is the other option; it is not
implemented.
"""

from __future__ import annotations

import numpy as np

from upm.transitions.base import TransitionMethod, WindowProblem, WindowResult


def quintic_offset(x0, v0, t1: float, t) -> np.ndarray:
    """Bollo's quintic offset decay.

    Parameters
    ----------
    x0, v0 : array_like, shape (D,)
        Offset and its velocity at t = 0 (per frame).
    t1 : float
        Blend time: the offset, its velocity and acceleration are 0 at ``t1``.
    t : array_like, shape (m,)
        Times (frames) in [0, t1].

    Returns
    -------
    ndarray, shape (m, D)
    """
    x0, v0 = np.asarray(x0, dtype=float), np.asarray(v0, dtype=float)
    t = np.asarray(t, dtype=float)[:, None]
    a0 = -(8.0 * v0 * t1 + 20.0 * x0) / t1**2
    c5 = -(a0 * t1**2 + 6.0 * v0 * t1 + 12.0 * x0) / (2.0 * t1**5)
    c4 = (3.0 * a0 * t1**2 + 16.0 * v0 * t1 + 30.0 * x0) / (2.0 * t1**4)
    c3 = -(3.0 * a0 * t1**2 + 12.0 * v0 * t1 + 20.0 * x0) / (2.0 * t1**3)
    return ((((c5 * t + c4) * t + c3) * t + 0.5 * a0) * t + v0) * t + x0


def solve(problem: WindowProblem) -> WindowResult:
    t1 = float(problem.end_time)
    v_a, v_b = problem.velocity_a, problem.velocity_b
    target = problem.b_deg + v_b * (problem.window_times - t1)[:, None]
    x0 = problem.a_deg - (problem.b_deg - v_b * t1)
    offset = quintic_offset(x0, v_a - v_b, t1, problem.window_times)
    return WindowResult(target + offset, diagnostics={
        "initial_offset_max_deg": float(np.abs(x0).max()),
    })


METHOD = TransitionMethod(
    name="inertialize", solve=solve, continuity="C1", key_kind=None,
    summary="offset decay (Bollo's quintic) from clip 1's state at A onto clip 2 "
            "extrapolated back from B",
)
