"""Compiled kernels of the whole-body QP (:mod:`controller.balance.wbc`; numba, cached on
disk).

The balance controller solves one small QP at every physics step (about 50 unknowns).
Built with numpy, the QP's three dozen array calls cost more than their arithmetic and
more than the solver; here each set-up is one call. :func:`qp_terms` gives the terms of the
least-squares rows documented in :mod:`controller.balance.wbc`, with
``x = [qdd_joints; lambda]``: the cost ``1/2 x^T P x - q^T x`` and the inequalities
``C^T x >= d`` (quadprog's convention). The controller sets up the cost alone
(:func:`qp_cost_terms`) and the inequalities only where it solves the QP from scratch, with
the torque bounds it watches (:func:`watched_constraints`: building the full ``C`` at every
step was about a sixth of the set-up); :func:`solve_active_set` solves it from a guessed
active set (the warm start), :func:`recall_active` and :func:`remember_active` keep that
guess in the MuJoCo state's user data.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def qp_terms(M, h, Jc, qvel, qdd_des, edges, weight_n, root_w, w_joints, w_contact,
             w_force, torque_scale, contact_damping, low, high):
    """The QP of one control step: :func:`qp_cost_terms` and :func:`bound_constraints`,
    ``(P, q, C, d, G, g0, T, t0)``.
    """
    P, q, G, g0, T, t0 = qp_cost_terms(M, h, Jc, qvel, qdd_des, edges, weight_n, root_w,
                                       w_joints, w_contact, w_force, torque_scale,
                                       contact_damping)
    C, d = bound_constraints(T, t0, low, high, P.shape[0] - T.shape[0])
    return P, q, C, d, G, g0, T, t0


@njit(cache=True, nogil=True)
def qp_cost_terms(M, h, Jc, qvel, qdd_des, edges, weight_n, root_w, w_joints, w_contact,
                  w_force, torque_scale, contact_damping):
    """The cost of the QP of one control step, and its accelerations and torques as
    linear functions of the unknowns.

    Parameters
    ----------
    M : ndarray, shape (nv, nv)
        Joint-space inertia; the free joint's DOFs are 0-5.
    h : ndarray, shape (nv,)
        Bias minus passive forces.
    Jc : ndarray, shape (3 nc, nv)
        Translational Jacobians of the nc planned floor contact points.
    qvel, qdd_des : ndarray, shape (nv,)
    edges : ndarray, shape (4, 3)
        Unit edges of the friction pyramid (world frame).
    weight_n : float
        The body's weight, N (edge magnitudes are in body weights).
    root_w : ndarray, shape (6,)
        Weights of the root rows (already reduced when nothing touches the floor).
    w_joints : ndarray, shape (nv - 6,)
        Weight of each hinge's acceleration row.
    w_contact, w_force : float
    torque_scale : ndarray, shape (nv - 6,)
        Weight of each hinge's torque per N m (the torque weight over its strength).
    contact_damping : float
        Desired contact-point acceleration per unit of its velocity, 1/s.

    Returns
    -------
    P : ndarray, shape (n, n)
        ``n = nv - 6 + 4 nc``.
    q : ndarray, shape (n,)
    G : ndarray, shape (nv, n)
        ``qdd = G x + g0``.
    g0 : ndarray, shape (nv,)
    T : ndarray, shape (nv - 6, n)
        ``tau_hinges = T x + t0``.
    t0 : ndarray, shape (nv - 6,)
    """
    nv = M.shape[0]
    nj = nv - 6
    nc = Jc.shape[0] // 3
    nl = 4 * nc
    n = nj + nl
    # generalised force of unit edge magnitudes (in body weights), (nv, nl)
    Jl = np.zeros((nv, nl))
    for i in range(nc):
        for e in range(4):
            for k in range(nv):
                Jl[k, 4 * i + e] = weight_n * (edges[e, 0] * Jc[3 * i, k]
                                               + edges[e, 1] * Jc[3 * i + 1, k]
                                               + edges[e, 2] * Jc[3 * i + 2, k])
    # the root rows solved for the root acceleration: qdd = G x + g0
    Mrr_inv = np.linalg.inv(np.ascontiguousarray(M[:6, :6]))
    G = np.zeros((nv, n))
    G[:6, :nj] = -(Mrr_inv @ np.ascontiguousarray(M[:6, 6:]))
    if nl:
        G[:6, nj:] = Mrr_inv @ np.ascontiguousarray(Jl[:6])
    for j in range(nj):
        G[6 + j, j] = 1.0
    g0 = np.zeros(nv)
    g0[:6] = -(Mrr_inv @ np.ascontiguousarray(h[:6]))
    G6 = np.ascontiguousarray(G[:6])

    # least-squares rows, accumulated into P = A^T A and q = A^T b
    R = np.empty((6, n))
    for r in range(6):
        R[r] = root_w[r] * G6[r]
    P = R.T @ R
    rb = root_w * (qdd_des[:6] - g0[:6])
    q = R.T @ rb
    for j in range(nj):
        wj2 = w_joints[j] * w_joints[j]
        P[j, j] += wj2
        q[j] += wj2 * qdd_des[6 + j]
    if nc:
        JcG = Jc @ G
        vc = Jc @ qvel
        bc = -contact_damping * vc - Jc @ g0
        wc2 = w_contact * w_contact
        P += wc2 * (JcG.T @ JcG)
        q += wc2 * (JcG.T @ bc)
        wf2 = w_force * w_force
        for i in range(nl):
            P[nj + i, nj + i] += wf2
    # hinge torques: T x + t0
    Mj = np.ascontiguousarray(M[6:])
    T = Mj @ G
    for k in range(nj):
        for i in range(nl):
            T[k, nj + i] -= Jl[6 + k, i]
    t0 = Mj @ g0 + h[6:]
    ST = np.empty((nj, n))
    for k in range(nj):
        ST[k] = torque_scale[k] * T[k]
    P += ST.T @ ST
    q -= ST.T @ (torque_scale * t0)
    for i in range(n):
        P[i, i] += 1e-9
    return P, q, G, g0, T, t0


@njit(cache=True, nogil=True)
def bound_constraints(T, t0, low, high, nl):
    """The QP's inequalities ``C^T x >= d``: the ``nl`` edge magnitudes (the last
    unknowns) >= 0, ``low <= T x + t0 <= high``; ``T`` (nh, n), the rest (nh,).

    Returns
    -------
    C : ndarray, shape (n, nl + 2 nh)
    d : ndarray, shape (nl + 2 nh,)
    """
    return watched_constraints(T, t0, low, high, nl, np.ones(T.shape[0], dtype=np.bool_))


@njit(cache=True, nogil=True)
def watched_constraints(T, t0, low, high, nl, watched):
    """The columns of :func:`bound_constraints` that the QP is solved with: the forces'
    (the first ``nl``) and both torque bounds of the ``watched`` hinges (nh,), in that
    order (upper bounds, then lower): ``C`` (n, nl + 2 w) and ``d`` (nl + 2 w,), ``w`` the
    number of hinges watched."""
    nh, n = T.shape
    nj = n - nl
    m = nl
    for k in range(nh):
        if watched[k]:
            m += 2
    C = np.zeros((n, m))
    d = np.empty(m)
    for i in range(nl):
        C[nj + i, i] = 1.0
        d[i] = 0.0
    col = nl
    for side in range(2):
        for k in range(nh):
            if watched[k]:
                if side == 0:
                    for i in range(n):
                        C[i, col] = -T[k, i]
                    d[col] = t0[k] - high[k]
                else:
                    for i in range(n):
                        C[i, col] = T[k, i]
                    d[col] = low[k] - t0[k]
                col += 1
    return C, d


@njit(cache=True, nogil=True)
def near_bounds(ctrl, actuator_of_hinge, low, high, strength, share):
    """Which hinges' applied torque is within ``share`` of their strength of a bound:
    bool (nh,). ``ctrl`` (nu,) in actuator order, the rest (nh,) in hinge order."""
    out = np.empty(low.shape[0], dtype=np.bool_)
    for k in range(low.shape[0]):
        c = ctrl[actuator_of_hinge[k]]
        out[k] = c > high[k] - share * strength[k] or c < low[k] + share * strength[k]
    return out


@njit(cache=True, nogil=True)
def break_bounds(tau, low, high, tolerance, watched):
    """Whether the hinge torques ``tau`` (nh,) of a solution break a bound of a hinge not
    ``watched`` by more than ``tolerance`` (nh,) N m; those hinges become watched (in
    place)."""
    broken = False
    for k in range(tau.shape[0]):
        if not watched[k] and (tau[k] > high[k] + tolerance[k]
                               or tau[k] < low[k] - tolerance[k]):
            watched[k] = True
            broken = True
    return broken


@njit(cache=True, nogil=True)
def _cholesky_solve(L, b):
    """``x`` with ``L L^T x = b``; ``L`` (n, n) lower triangular, ``b`` (n,)."""
    n = L.shape[0]
    y = np.empty(n)
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    x = np.empty(n)
    for i in range(n - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, n):
            s -= L[k, i] * x[k]
        x[i] = s / L[i, i]
    return x


@njit(cache=True, nogil=True)
def _solve_equalities(P, q, T, t0, low, high, nl, fixed, upper, lower):
    """The QP of :func:`qp_terms` with the edge magnitudes ``fixed`` (nl,) at 0 and the
    hinges ``upper`` / ``lower`` (nh,) at their upper / lower torque bound, as equalities:
    ``(x (n,), the bound rows' multipliers (nh,), 0 elsewhere, the Lagrangian's gradient
    (n,))``. The fixed magnitudes are eliminated, the torque rows solved by their
    multipliers through the Cholesky factor of the rest of ``P``."""
    n = P.shape[0]
    nj = n - nl
    free = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        if i < nj or not fixed[i - nj]:
            free[m] = i
            m += 1
    PF = np.empty((m, m))
    qF = np.empty(m)
    for a in range(m):
        qF[a] = q[free[a]]
        for b in range(m):
            PF[a, b] = P[free[a], free[b]]
    rows = np.empty(nj, dtype=np.int64)
    sign = np.empty(nj)
    r = 0
    for k in range(nj):
        if upper[k] or lower[k]:
            rows[r] = k
            sign[r] = -1.0 if upper[k] else 1.0  # the constraint: sign * tau >= sign * bound
            r += 1
    L = np.linalg.cholesky(PF)
    xF = _cholesky_solve(L, qF)
    mu = np.zeros(r)
    if r:
        # P x = q + E mu and E^T x = e on the bound rows
        E = np.empty((m, r))
        e = np.empty(r)
        for j in range(r):
            k = rows[j]
            for a in range(m):
                E[a, j] = sign[j] * T[k, free[a]]
            e[j] = t0[k] - high[k] if sign[j] < 0 else low[k] - t0[k]
        Z = np.empty((m, r))
        for j in range(r):
            Z[:, j] = _cholesky_solve(L, np.ascontiguousarray(E[:, j]))
        mu = np.linalg.solve(E.T @ Z, e - E.T @ xF)
        xF = xF + Z @ mu
    x = np.zeros(n)
    for a in range(m):
        x[free[a]] = xF[a]
    gradient = P @ x - q
    multiplier = np.zeros(nj)
    for j in range(r):
        multiplier[rows[j]] = mu[j]
        for i in range(n):
            gradient[i] -= mu[j] * sign[j] * T[rows[j], i]
    return x, multiplier, gradient


@njit(cache=True, nogil=True)
def solve_active_set(P, q, T, t0, low, high, nl, fixed, upper, lower, tol_tau, tol_force,
                     tol_multiplier):
    """The QP of :func:`qp_terms` solved with a guessed active set, and whether the guess
    was right (the solution then is the QP's minimiser with every bound).

    The guess: the edge magnitudes ``fixed`` (nl,) are 0, and the hinges ``upper`` /
    ``lower`` (nh,) are at their upper / lower torque bound. The problem is solved with the
    guess as equalities and the full problem's KKT conditions checked: every other
    magnitude >= -``tol_force``, every torque within its range +-``tol_tau`` (nh,), every
    multiplier >= -``tol_multiplier`` times ``1 + max |q|``.

    Parameters
    ----------
    P : ndarray, shape (n, n)
    q : ndarray, shape (n,)
    T : ndarray, shape (nh, n)
    t0, low, high : ndarray, shape (nh,)
    nl : int
        The edge magnitudes are the last ``nl`` unknowns.

    Returns
    -------
    x : ndarray, shape (n,)
    ok : bool
    """
    n = P.shape[0]
    nj = n - nl
    tol_multiplier = tol_multiplier * (1.0 + np.max(np.abs(q)))
    x, multiplier, gradient = _solve_equalities(P, q, T, t0, low, high, nl, fixed, upper,
                                                lower)
    if not np.all(np.isfinite(x)):
        return x, False
    for i in range(nl):
        if fixed[i]:
            if gradient[nj + i] < -tol_multiplier:
                return x, False
        elif x[nj + i] < -tol_force:
            return x, False
    tau = T @ x + t0
    for k in range(nj):
        if upper[k] or lower[k]:
            if multiplier[k] < -tol_multiplier:
                return x, False
        elif tau[k] > high[k] + tol_tau[k] or tau[k] < low[k] - tol_tau[k]:
            return x, False
    return x, True


@njit(cache=True, nogil=True)
def recall_active(memory, geoms):
    """The edge magnitudes that were 0 at the last solve, if its planned contacts were
    the same geom pairs in the same order: ``(fixed (4 m,) bool, known)``.

    ``memory`` (k,): written by :func:`remember_active` (``[m, geom pairs (2 m),
    per-contact masks of the 4 edges (m)]``, ``m = -1``: nothing); ``geoms`` (m, 2)."""
    m = geoms.shape[0]
    fixed = np.zeros(4 * m, dtype=np.bool_)
    if memory.shape[0] == 0 or memory[0] != m:
        return fixed, False
    for i in range(m):
        if memory[1 + 2 * i] != geoms[i, 0] or memory[2 + 2 * i] != geoms[i, 1]:
            return fixed, False
    for i in range(m):
        mask = int(memory[1 + 2 * m + i])
        for e in range(4):
            fixed[4 * i + e] = (mask >> e) & 1 == 1
    return fixed, True


@njit(cache=True, nogil=True)
def remember_active(memory, geoms, fixed):
    """Write the planned contacts ``geoms`` (m, 2) and which of their edge magnitudes are
    0, ``fixed`` (4 m,), into ``memory`` (k,) for :func:`recall_active` (or that nothing
    is known, where it does not fit)."""
    m = geoms.shape[0]
    if memory.shape[0] == 0:
        return
    if 1 + 3 * m > memory.shape[0]:
        memory[0] = -1.0
        return
    memory[0] = m
    for i in range(m):
        memory[1 + 2 * i] = geoms[i, 0]
        memory[2 + 2 * i] = geoms[i, 1]
        mask = 0
        for e in range(4):
            if fixed[4 * i + e]:
                mask |= 1 << e
        memory[1 + 2 * m + i] = mask


@njit(cache=True, nogil=True)
def hinges_at_bounds(ctrl, actuator_of_hinge, low, high, tolerance):
    """Which hinges' applied torque is within ``tolerance`` (nh,) N m of the upper and of
    the lower bound (a finite one): ``(upper, lower)``, bool (nh,) each. ``ctrl`` (nu,) in
    actuator order, the rest (nh,) in hinge order."""
    nh = low.shape[0]
    upper = np.empty(nh, dtype=np.bool_)
    lower = np.empty(nh, dtype=np.bool_)
    for k in range(nh):
        c = ctrl[actuator_of_hinge[k]]
        upper[k] = high[k] < np.inf and c >= high[k] - tolerance[k]
        lower[k] = low[k] > -np.inf and c <= low[k] + tolerance[k]
    return upper, lower
