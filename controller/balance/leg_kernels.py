"""Compiled kernels of the swing leg (:mod:`controller.balance.placement`,
:mod:`controller.balance.foot_tilt`; numba, cached on disk): the swing foot's capture
shift, the damped least-squares joint change that moves a point of the leg, and the ankle
turn that sets the sole's tilt."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def damped_least_squares(jac, move, damping, max_turn):
    """``clip(J^T (J J^T + damping^2 I)^-1 move, -max_turn, max_turn)``: the joint change
    (rad) that moves a point by ``move`` (m) through its Jacobian ``jac`` (k, n) (m/rad),
    damped by ``damping`` (m), each joint's change within +-``max_turn`` (rad)."""
    jjt = jac @ jac.T
    for i in range(jjt.shape[0]):
        jjt[i, i] += damping * damping
    turn = jac.T @ np.linalg.solve(jjt, move)
    return np.minimum(np.maximum(turn, -max_turn), max_turn)


@njit(cache=True, nogil=True)
def capture_shift(com, com_vel, stance_ankle, ref_com, ref_com_vel, ref_stance_ankle,
                  time_constant_s, gain, max_shift_m):
    """The swing foot's horizontal shift, m (2,): ``gain`` times the difference between
    the character's and the reference's capture offsets (centre of mass minus stance
    ankle, plus its velocity times ``time_constant_s``), no longer than ``max_shift_m``.
    See :mod:`controller.balance.placement`. Arrays (3,) (only x and y are read)."""
    shift = np.empty(2)
    for j in range(2):
        sim = (com[j] - stance_ankle[j]) + time_constant_s * com_vel[j]
        ref = (ref_com[j] - ref_stance_ankle[j]) + time_constant_s * ref_com_vel[j]
        shift[j] = gain * (sim - ref)
    norm = np.sqrt(np.dot(shift, shift))
    if norm > max_shift_m:
        for j in range(2):
            shift[j] *= max_shift_m / norm
    return shift


@njit(cache=True, nogil=True)
def move_point(jacp, dofs, move, damping, max_turn, q, qadr):
    """Turn joints to move a point: ``q[qadr] +=`` :func:`damped_least_squares` of the
    columns ``dofs`` (n,) of its Jacobian ``jacp`` (3, nv), rows as many as ``move`` (k,),
    in place."""
    jac = np.empty((move.shape[0], dofs.shape[0]))
    for r in range(move.shape[0]):
        for c in range(dofs.shape[0]):
            jac[r, c] = jacp[r, dofs[c]]
    turn = damped_least_squares(jac, move, damping, max_turn)
    for c in range(qadr.shape[0]):
        q[qadr[c]] += turn[c]


@njit(cache=True, nogil=True)
def tilt_ankle(foot_xmat, up, xaxis, hinges, damping, qpos, qadr, q):
    """Set a swing ankle's targets ``q[qadr]`` (in place) to the angles that turn the foot
    back to the reference's tilt (:mod:`controller.balance.foot_tilt`): the state's ``qpos[qadr]``
    plus the damped least squares ``delta`` of ``sum_k a_k delta_k = (R up) x z``.

    Parameters
    ----------
    foot_xmat : ndarray, shape (9,)
        The foot's orientation ``R`` (row-major).
    up : ndarray, shape (3,)
        The world vertical in the reference's foot frame.
    xaxis : ndarray, shape (njnt, 3)
        Every joint's axis, world frame; ``hinges`` (k,) the ankle's rows of it.
    damping : ndarray, shape (k, k)
    qpos, q : ndarray, shape (nq,)
        The state's angles and the targets; ``qadr`` (k,) the ankle's addresses.

    The products are the BLAS calls numpy makes for the same expressions, so the targets
    are numpy's to the last bit.
    """
    now = foot_xmat.reshape(3, 3) @ up
    turn = np.array((now[1], -now[0], 0.0))  # now x z
    rows = np.empty((hinges.shape[0], 3))
    for r in range(hinges.shape[0]):
        rows[r] = xaxis[hinges[r]]
    axes = rows.T.copy()
    delta = np.linalg.solve(axes.T @ axes + damping, rows @ turn)
    for c in range(qadr.shape[0]):
        q[qadr[c]] = qpos[qadr[c]] + delta[c]
