"""``slerp``: per-joint spherical linear interpolation of the joint rotations.

Each joint's rotation in its axis frame, ``M = Rz(rz) Ry(ry) Rx(rx)``, is interpolated
along the shortest great arc from A's to B's: ``M(s) = M_A exp(s log(M_A^T M_B))`` with
``s = t / (L + 1)``. (Slerping M or the bone's local rotation ``C M C^T`` is the same
path: conjugation by the fixed axis frame C preserves geodesics.) Then back to the
joint's declared Euler DOFs:

- 3 declared DOFs: exactly, the Euler solution nearest the linear blend of the angles;
- 1 or 2 declared DOFs (CMU: tibiae, radii and toes rx; clavicles ry rz; feet and hands
  rx rz): most rotations have no exact representation. The DOFs are set to the angles
  whose rotation is nearest the slerped one (maximum ``trace(R^T M)``, i.e. minimum
  chordal distance), found by coordinate ascent from the linear blend — each step solves
  one angle in closed form. A single-DOF joint is exact (its rotations share one axis,
  so slerp is the linear blend). The remaining angle between the projected and the
  slerped rotation is reported as ``projection_residual_max_deg``.

Continuity: C0 (constant angular speed along the arc, so the velocity jumps at the edges
as with ``linear``).
"""

from __future__ import annotations

import numpy as np

from upm.rotations import (
    axis_rotation,
    euler_to_matrix,
    matrix_to_euler_deg,
    rotation_exp,
    rotation_log,
)
from upm.skeleton import N_JOINTS
from upm.transitions.base import TransitionMethod, WindowProblem, WindowResult

_SWEEPS = 50
_TOLERANCE_DEG = 1e-9


def _factor(angle_deg: np.ndarray, axis: int) -> np.ndarray:
    return axis_rotation(angle_deg, "XYZ"[axis])


def project_to_dofs(matrix, declared, start_deg) -> np.ndarray:
    """Angles of the declared axes whose ``Rz Ry Rx`` is nearest each rotation.

    Parameters
    ----------
    matrix : array_like, shape (..., 3, 3)
        Target rotations.
    declared : sequence of bool, length 3
        Which of x, y, z may move (the others stay 0).
    start_deg : array_like, shape (..., 3)
        Starting angles (about X, Y, Z); undeclared ones are ignored.

    Returns
    -------
    ndarray, shape (..., 3)
        Maximisers of ``trace(R(angles)^T M)`` by coordinate ascent, each angle on the
        turn nearest its start.
    """
    m = np.asarray(matrix, dtype=float)
    start = np.asarray(start_deg, dtype=float)
    angles = np.where(np.asarray(declared, dtype=bool), start, 0.0)
    axes = [k for k in range(3) if declared[k]]
    sweeps = 1 if len(axes) == 1 else _SWEEPS
    mt = np.swapaxes(m, -1, -2)
    for _ in range(sweeps):
        previous = angles.copy()
        for k in axes:
            # R = P R_k Q (Q: factors applied before axis k, P: after); trace(R^T M) =
            # trace(R_k N) with N = Q M^T P, maximal at atan2(N_jk - N_kj, N_jj + N_kk).
            q = np.broadcast_to(np.eye(3), m.shape).copy()
            for i in range(k):
                q = _factor(angles[..., i], i) @ q
            p = np.broadcast_to(np.eye(3), m.shape).copy()
            for i in range(k + 1, 3):
                p = _factor(angles[..., i], i) @ p
            n = q @ mt @ p
            j, m2 = (k + 1) % 3, (k + 2) % 3
            theta = np.degrees(np.arctan2(n[..., j, m2] - n[..., m2, j],
                                          n[..., j, j] + n[..., m2, m2]))
            angles[..., k] = theta + 360.0 * np.round((start[..., k] - theta) / 360.0)
        if np.abs(angles - previous).max(initial=0.0) < _TOLERANCE_DEG:
            break
    return angles


def rotation_angle_deg(r0, r1) -> np.ndarray:
    """Angle of the rotation between ``r0`` and ``r1`` (..., 3, 3), degrees."""
    relative = np.swapaxes(r0, -1, -2) @ r1
    return np.degrees(np.linalg.norm(rotation_log(relative), axis=-1))


def solve(problem: WindowProblem) -> WindowResult:
    n_frames = problem.frames
    a = problem.a_deg.reshape(N_JOINTS, 3)
    b = problem.b_deg.reshape(N_JOINTS, 3)
    s = problem.window_times / problem.end_time
    linear = problem.linear().reshape(n_frames, N_JOINTS, 3)

    m_a = euler_to_matrix(a, "XYZ")
    m_b = euler_to_matrix(b, "XYZ")
    arc = rotation_log(np.swapaxes(m_a, -1, -2) @ m_b)  # (21, 3)
    slerped = m_a[None] @ rotation_exp(s[:, None, None] * arc[None])  # (L, 21, 3, 3)

    declared = problem.skeleton.declared.reshape(N_JOINTS, 3)
    window = np.zeros((n_frames, N_JOINTS, 3))
    residual = 0.0
    for pattern in {tuple(row) for row in declared}:
        joints = np.flatnonzero((declared == pattern).all(axis=1))
        if not any(pattern):
            continue
        if all(pattern):
            window[:, joints] = matrix_to_euler_deg(slerped[:, joints], "XYZ",
                                                    near_deg=linear[:, joints])
            continue
        angles = project_to_dofs(slerped[:, joints], pattern, linear[:, joints])
        window[:, joints] = angles
        projected = euler_to_matrix(angles, "XYZ")
        residual = max(residual, float(rotation_angle_deg(projected, slerped[:, joints]).max()))
    return WindowResult(window.reshape(n_frames, 3 * N_JOINTS), diagnostics={
        "projection_residual_max_deg": residual,
    })


METHOD = TransitionMethod(
    name="slerp", solve=solve, continuity="C0", key_kind=None,
    summary="per-joint quaternion slerp in each bone's axis frame, back to the ASF Euler DOFs",
)
