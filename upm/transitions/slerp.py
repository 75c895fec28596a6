"""``slerp``: per-joint spherical linear interpolation of the joint rotations.

Each joint's rotation in its axis frame, ``M = Rz(rz) Ry(ry) Rx(rx)``, is interpolated
along the shortest great arc from A's to B's: ``M(s) = M_A exp(s log(M_A^T M_B))`` with
``s = t / (L + 1)``. (Slerping M or the bone's local rotation ``C M C^T`` is the same
path: conjugation by the fixed axis frame C preserves geodesics.) Then back to the
joint's declared Euler DOFs:

- 3 declared DOFs: exactly, away from gimbal lock. A rotation has two Euler solutions
  (and their whole-turn shifts); the window takes, frame by frame, the one that makes
  the angles change least along time from A's angles to B's (a two-state shortest path
  over the frames, exact: :func:`continuous_branches`). Choosing per frame the solution
  nearest the linear blend instead flips branch mid-window where the two are about
  equally near (178.8 degrees in one frame on 16_15@180 -> 05_11@40). Where the arc
  passes close to gimbal lock (middle angle near +-90), every Euler path of the exact
  rotations swings the first and last angles fast; there, and only for the joints whose
  angles step more than :data:`FAST_STEP_DEG` in a frame, the angles are refined by
  damped least squares (:func:`damped_projection`): rotations near the arc, steps small;
  the rotation error this leaves is reported with the 2-DOF projection's residual;
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

from upm.motion.skeleton import N_JOINTS
from upm.ops.angles import angle_diff_deg
from upm.ops.rotations import (
    _alternate_euler,
    axis_rotation,
    euler_to_matrix,
    matrix_to_euler_deg,
    rotation_exp,
    rotation_log,
)
from upm.transitions.base import TransitionMethod, WindowProblem, WindowResult

_SWEEPS = 50
_TOLERANCE_DEG = 1e-9
#: A 3-DOF joint whose exact Euler path steps more than this in one frame (beyond the
#: linear blend's own step) is passing near gimbal lock: its angles get the damped
#: projection. Real clips at 120 fps step a few degrees per frame at most.
FAST_STEP_DEG = 10.0
#: Weight of the squared angle steps (radians) against the squared chordal rotation
#: error in the damped projection. Near gimbal lock no Euler path follows the arc with
#: small steps: on 16_15@180 -> 05_11@40 (rhumerus passes 1.4 degrees from the lock)
#: weights 0.02 / 0.2 / 1 / 2 / 5 give a largest step of 43.8 / 26.3 / 18.9 / 16.9 / 14.7
#: degrees for a largest rotation error of 3.1 / 6.1 / 9.7 / 12.3 / 16.8 degrees; the
#: clips' own largest step there is 18.3 degrees. 2 keeps the angles as smooth as the
#: clips at the cost of leaving the arc near the lock (reported in the diagnostics).
DAMPING = 2.0


def _wrapped_sq(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    d = np.mod(x - y + 180.0, 360.0) - 180.0
    return np.einsum("...i,...i->...", d, d)


def continuous_branches(principal, alternate, start_deg, end_deg) -> np.ndarray:
    """Per frame, the Euler solution that makes the path from ``start_deg`` to
    ``end_deg`` change least: minimum sum of squared (wrapped) steps over the two
    solutions of every frame, by dynamic programming; unwrapped from ``start_deg``.

    Parameters
    ----------
    principal, alternate : ndarray, shape (T, J, 3)
        The two Euler solutions of each frame's rotation.
    start_deg, end_deg : ndarray, shape (J, 3)
        The angles before the first and after the last frame.

    Returns
    -------
    ndarray, shape (T, J, 3)
    """
    options = np.stack([principal, alternate])  # (2, T, J, 3)
    n_frames = options.shape[1]
    cost = _wrapped_sq(options[:, 0], start_deg[None])  # (2, J)
    back = np.zeros((n_frames, 2) + cost.shape[1:], dtype=int)
    for t in range(1, n_frames):
        step = _wrapped_sq(options[None, :, t - 1], options[:, None, t])  # (to, from, J)
        total = cost[None] + step
        back[t] = np.argmin(total, axis=1)
        cost = np.min(total, axis=1)
    cost = cost + _wrapped_sq(options[:, -1], end_deg[None])
    state = np.argmin(cost, axis=0)  # (J,)
    joints = np.arange(state.size)
    chosen = np.empty_like(principal)
    for t in range(n_frames - 1, -1, -1):
        chosen[t] = options[state, t, joints]
        state = back[t, state, joints]
    chained = np.concatenate([np.asarray(start_deg, dtype=float)[None], chosen])
    return np.unwrap(chained, period=360.0, axis=0)[1:]


def damped_projection(target, start_deg, end_deg, initial_deg) -> tuple[np.ndarray, float]:
    """Euler angles of one joint along the window, near the target rotations and smooth.

    Minimises ``sum_t |R(angles_t) - M_t|_F^2 + DAMPING * sum_t |angles_t -
    angles_{t-1}|^2`` (radians; the steps include those from ``start_deg`` and to
    ``end_deg``) with scipy's ``least_squares`` from ``initial_deg``.

    Parameters
    ----------
    target : ndarray, shape (T, 3, 3)
    start_deg, end_deg, : ndarray, shape (3,)
    initial_deg : ndarray, shape (T, 3)

    Returns
    -------
    angles : ndarray, shape (T, 3)
    residual_deg : float
        The largest angle between a found rotation and its target.
    """
    from scipy.optimize import least_squares

    n_frames = target.shape[0]
    weight = np.sqrt(DAMPING)
    start, end = np.radians(start_deg), np.radians(end_deg)

    def residuals(x):
        angles = x.reshape(n_frames, 3)
        chained = np.concatenate([start[None], angles, end[None]])
        rotation_error = euler_to_matrix(np.degrees(angles), "XYZ") - target
        return np.concatenate([rotation_error.ravel(), weight * np.diff(chained, axis=0).ravel()])

    # The Jacobian in closed form: R = Rz Ry Rx and dR_k/dθ = K_k R_k (K_k: the skew
    # matrix of axis k), so each frame's 9 rotation residuals depend on its 3 angles only.
    steps = np.zeros((3 * (n_frames + 1), 3 * n_frames))
    index = np.arange(3 * n_frames)
    steps[index, index] = weight
    steps[index + 3, index] = -weight
    skew = np.zeros((3, 3, 3))
    for k, (i, j) in enumerate(((2, 1), (0, 2), (1, 0))):
        skew[k, i, j], skew[k, j, i] = 1.0, -1.0
    rows = np.arange(9 * n_frames).reshape(n_frames, 9)

    def jacobian(x):
        degrees = np.degrees(x.reshape(n_frames, 3))
        rx, ry, rz = (axis_rotation(degrees[:, k], "XYZ"[k]) for k in range(3))
        d = np.stack([rz @ ry @ skew[0] @ rx, rz @ skew[1] @ ry @ rx, skew[2] @ rz @ ry @ rx],
                     axis=-1)  # (T, 3, 3, 3): derivative of R_t by its angle k, last axis
        rotation = np.zeros((9 * n_frames, 3 * n_frames))
        for k in range(3):
            rotation[rows, 3 * np.arange(n_frames)[:, None] + k] = d[..., k].reshape(n_frames, 9)
        return np.concatenate([rotation, steps])

    fit = least_squares(residuals, np.radians(initial_deg).ravel(), jac=jacobian,
                        method="trf")
    angles = np.degrees(fit.x.reshape(n_frames, 3))
    residual = float(rotation_angle_deg(euler_to_matrix(angles, "XYZ"), target).max())
    return angles, residual


def _alternate(angles_deg: np.ndarray) -> np.ndarray:
    return _alternate_euler(angles_deg, "XYZ")


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
            principal = matrix_to_euler_deg(slerped[:, joints], "XYZ")
            angles = continuous_branches(principal, _alternate(principal), a[joints],
                                         b[joints])
            end = angles[-1] + angle_diff_deg(b[joints], angles[-1])
            chained = np.concatenate([a[joints][None], angles, end[None]])
            steps = np.abs(np.diff(chained, axis=0)).max(axis=(0, 2))
            own = np.abs(angle_diff_deg(b[joints], a[joints])).max(axis=1) / problem.end_time
            for k in np.flatnonzero(steps > own + FAST_STEP_DEG):
                angles[:, k], error = damped_projection(slerped[:, joints[k]], a[joints[k]],
                                                        end[k], angles[:, k])
                residual = max(residual, error)
            window[:, joints] = angles
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
