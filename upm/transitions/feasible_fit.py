"""The ``feasible`` window as a small convex problem per DOF (quadprog): near the UPM curve,
minimum jerk, C1 joins to both clips, every frame inside the allowed range."""

from __future__ import annotations

import functools

import numpy as np
from scipy.interpolate import BSpline

from upm.transitions.base import WindowProblem
from upm.transitions.feasible_range import end_velocity

#: Weight of the squared third differences (deg/frame^3) against the squared distance to
#: the UPM curve (deg^2). Measured on 40 test pairs (eval.pairs.draw_pairs, seed 1,
#: L = 20; the study draws with seed 0): weights 10 / 100 / 1000 give a mean window jerk
#: of 526 / 489 / 436 10^3 deg/s^3 (upm 540, linear 1344) and move the window a median
#: 0.08 / 0.30 / 1.17 degrees from the UPM curve; 100 keeps the window on the map's curve
#: (nearest-real distance) while cutting jerk.
JERK_WEIGHT = 100.0
#: Frames between the window spline's knots: knots every frame gave a mean jerk of 489
#: against 537 with knots every 2 frames (same pairs, weight 100): the turn-backs near
#: a limit are smoother with more freedom.
KNOT_SPACING = 1.0

#: Penalty on the range excess (per deg^2) when the range must be soft.
SOFT_RANGE_WEIGHT = 1e6

@functools.lru_cache(maxsize=64)
def _layout(frames: int, k_before: int, k_after: int):
    """Matrices of the window fit for one layout (read-only, cached).

    Returns
    -------
    dict
        ``window`` (L, n): the spline's values at t = 1 .. L from its coefficients;
        ``equality`` (4, n): p(0), p'(0), p(L+1), p'(L+1); ``hessian`` (n, n);
        ``jerk_context`` (n, K1 + K2): the linear term's matrix for the clip frames;
        ``solve`` (n, L + K1 + K2 + 4): coefficients of the equality-constrained optimum
        from ``[u, clip 1 frames, clip 2 frames, equality values]``.
    """
    end = frames + 1
    segments = max(2, int(np.ceil(end / KNOT_SPACING)))
    h = end / segments
    knots = np.concatenate([[0.0] * 3, np.arange(segments + 1) * h, [end] * 3])
    knots[segments + 3] = end
    n = segments + 3
    basis = BSpline(knots, np.eye(n), 3, extrapolate=False)
    window = basis(np.arange(1, frames + 1, dtype=float))
    slope = basis.derivative()
    equality = np.stack([basis(0.0), slope(0.0), basis(float(end) - 1e-12),
                         slope(float(end) - 1e-12)])
    # The sequence [clip 1 (K1), window (L), clip 2 (K2)] and its third differences.
    length = k_before + frames + k_after
    d3 = np.diff(np.eye(length), 3, axis=0)
    touching = [r for r in range(d3.shape[0]) if r + 3 >= k_before and r < k_before + frames]
    d3 = d3[touching]
    d_window = d3[:, k_before:k_before + frames] @ window  # (S, n)
    d_context = np.concatenate([d3[:, :k_before], d3[:, k_before + frames:]], axis=1)
    hessian = window.T @ window + JERK_WEIGHT * d_window.T @ d_window + 1e-9 * np.eye(n)
    jerk_context = -JERK_WEIGHT * d_window.T @ d_context  # (n, K1 + K2)
    kkt = np.block([[hessian, equality.T], [equality, np.zeros((4, 4))]])
    inverse = np.linalg.inv(kkt)[:n]
    rhs = np.zeros((n + 4, frames + k_before + k_after + 4))
    rhs[:n, :frames] = window.T
    rhs[:n, frames:frames + k_before + k_after] = jerk_context
    rhs[n:, frames + k_before + k_after:] = np.eye(4)
    out = {"window": window, "equality": equality, "hessian": hessian,
           "jerk_context": jerk_context, "solve": inverse @ rhs}
    for value in out.values():
        value.setflags(write=False)
    return out


def fit_window(problem: WindowProblem, reference_deg, lower_deg, upper_deg,
               constrained) -> tuple[np.ndarray, dict[str, float]]:
    """The window as the convex problem of the module docstring.

    Parameters
    ----------
    problem : WindowProblem
    reference_deg : ndarray, shape (L, 63)
        The curve to stay near (the UPM curve), continuous with the problem's context.
    lower_deg, upper_deg : ndarray, shape (63,)
    constrained : ndarray of bool, shape (63,)

    Returns
    -------
    window : ndarray, shape (L, 63)
    diagnostics : dict
        ``qp_dofs`` (DOFs whose range was active), ``soft_range_dofs``.
    """
    import quadprog

    before, after = problem.before_deg, problem.after_deg
    k1, k2 = before.shape[0], after.shape[0]
    layout = _layout(problem.frames, k1, k2)
    ends = np.stack([problem.a_deg, end_velocity(before, True),
                     problem.b_deg, end_velocity(after, False)])
    data = np.concatenate([reference_deg, before, after, ends])  # (L + K1 + K2 + 4, 63)
    coefficients = layout["solve"] @ data
    window = layout["window"] @ coefficients
    out_of_range = constrained & ((window < lower_deg).any(axis=0)
                                  | (window > upper_deg).any(axis=0))
    soft = 0
    basis = layout["window"]
    for dof in np.flatnonzero(out_of_range):
        linear = basis.T @ reference_deg[:, dof] + layout["jerk_context"] @ np.concatenate(
            [before[:, dof], after[:, dof]])
        lo, hi = lower_deg[dof], upper_deg[dof]
        constraints = np.concatenate([layout["equality"], basis, -basis]).T
        bounds = np.concatenate([ends[:, dof], np.full(basis.shape[0], lo),
                                 np.full(basis.shape[0], -hi)])
        try:
            # quadprog writes into its arguments: the cached Hessian goes in as a copy.
            solution = quadprog.solve_qp(np.array(layout["hessian"]), linear, constraints,
                                         bounds, 4)[0]
        except ValueError:
            solution = _soft_range(layout, linear, ends[:, dof], lo, hi)
            soft += 1
        window[:, dof] = basis @ solution
    return window, {"qp_dofs": float(out_of_range.sum()), "soft_range_dofs": float(soft)}


def _soft_range(layout, linear, ends, lo, hi) -> np.ndarray:
    """The fit with the range as a heavy penalty on the excess (slack variables)."""
    import quadprog

    basis, hessian = layout["window"], layout["hessian"]
    n, m = hessian.shape[0], basis.shape[0]
    g = np.zeros((n + m, n + m))
    g[:n, :n] = hessian
    g[n:, n:] = SOFT_RANGE_WEIGHT * np.eye(m) + 1e-9 * np.eye(m)
    a = np.concatenate([linear, np.zeros(m)])
    eq = np.concatenate([layout["equality"], np.zeros((4, m))], axis=1)
    upper = np.concatenate([-basis, np.eye(m)], axis=1)  # hi + s - p >= 0
    lower = np.concatenate([basis, np.eye(m)], axis=1)  # p + s - lo >= 0
    slack = np.concatenate([np.zeros((m, n)), np.eye(m)], axis=1)
    c = np.concatenate([eq, upper, lower, slack]).T
    b = np.concatenate([ends, np.full(m, -hi), np.full(m, lo), np.zeros(m)])
    return quadprog.solve_qp(g, a, c, b, 4)[0][:n]


