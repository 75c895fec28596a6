"""``spacetime``: a minimum-effort window found by numerical optimisation (a stand-in for
Rose et al. 1996, the paper's Table 4 timing foil).

**Problem.** As in Rose et al., each DOF's trajectory over the window is a cubic B-spline
(clamped, uniform knots from A at t = 0 to B at t = L + 1) whose end coefficients are
fixed by the boundary constraints — position and velocity of clip 1 at A (its last step)
and of clip 2 at B (its first step) — and whose inner coefficients (``round(L / 4)``
per DOF, at least 1: 5 x 45 = 225 unknowns for L = 20) minimise the *effort*

    E = sum_t sum_bones m_b |c_b(t+1) - 2 c_b(t) + c_b(t-1)|^2
        + I_a sum_t sum_dofs (q(t+1) - 2 q(t) + q(t-1))^2

over the frames from the one before A to the one after B: the mass-weighted squared
acceleration of every bone's centre c_b (forward kinematics with the root held still:
Gauss's measure of constraint, the inertial part of a torque objective), plus a small
joint-space term with an armature inertia ``I_a`` = 0.01 kg m^2 (angles in radians) that
keeps DOFs which move no mass — a twist about a straight limb — from drifting. E is a
sum of squares, minimised by a trust-region Newton method on its Gauss-Newton Hessian
(scipy's ``trust-exact``) with the analytic Jacobian (bone Jacobians from the forward
kinematics), starting from the least-squares fit of the linear blend; Gauss-Newton is
what SQP — Rose et al.'s solver — reduces to on an unconstrained sum of squares.

**What it is not.** Rose et al. minimise joint torque squared from the full inverse
dynamics (gravity and velocity-product terms included) with foot-contact constraints;
this objective is the inertial part only, without gravity, contacts or the root, and the
masses are a standard anthropometric table (:data:`MASS_FRACTION`), not the subject's.
Like theirs it is an iterative optimisation over the whole window whose cost grows with
DOFs and frames — which is what Table 4 compares. Continuity: C1 at both edges (the
B-spline leaves A with clip 1's velocity and reaches B with clip 2's).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BSpline
from scipy.optimize import minimize

from upm.motion.kinematics import global_transforms
from upm.motion.skeleton import JOINTS, POSTURE_SIZE, Skeleton
from upm.ops.rotations import axis_rotation
from upm.transitions.base import TransitionMethod, WindowProblem, WindowResult

#: Segment mass as a share of body mass, per CMU bone (Winter, *Biomechanics and Motor
#: Control of Human Movement*, table 4.1: hand 0.006, forearm 0.016, upper arm 0.028,
#: foot 0.0145, leg 0.0465, thigh 0.100, head and neck 0.081, trunk 0.497, the trunk
#: split over the spine bones). Bones not listed weigh nothing. Only the ratios matter.
MASS_FRACTION: dict[str, float] = {
    "lhipjoint": 0.0135, "rhipjoint": 0.0135, "lowerback": 0.14, "upperback": 0.14,
    "thorax": 0.15, "lclavicle": 0.02, "rclavicle": 0.02,
    "lowerneck": 0.006, "upperneck": 0.006, "head": 0.069,
    "lhumerus": 0.028, "rhumerus": 0.028, "lradius": 0.016, "rradius": 0.016,
    "lhand": 0.006, "rhand": 0.006,
    "lfemur": 0.100, "rfemur": 0.100, "ltibia": 0.0465, "rtibia": 0.0465,
    "lfoot": 0.0115, "rfoot": 0.0115, "ltoes": 0.003, "rtoes": 0.003,
}
BODY_MASS_KG = 70.0


class _Model:
    """Per-skeleton arrays for the effort and its gradient."""

    def __init__(self, skeleton: Skeleton):
        names = skeleton.bone_names
        self.skeleton = skeleton
        self.bones = np.array([i for i, n in enumerate(names) if MASS_FRACTION.get(n, 0) > 0])
        self.mass = BODY_MASS_KG * np.array([MASS_FRACTION[names[i]] for i in self.bones])
        self.parents = skeleton.parents
        self.joint_bones = np.array([skeleton.bone_index(j) for j in JOINTS])
        self.joint_parents = self.parents[self.joint_bones]
        self.axis_frames = skeleton.axis_matrices[self.joint_bones]  # (21, 3, 3)
        self.declared = np.flatnonzero(skeleton.declared)  # posture indices that move
        # moved[k, j]: the centre of massive bone k moves with joint j (k is j or below it).
        moved = np.zeros((self.bones.size, len(JOINTS)), dtype=bool)
        for row, bone in enumerate(self.bones):
            b = bone
            while b >= 0:
                hit = np.flatnonzero(self.joint_bones == b)
                if hit.size:
                    moved[row, hit[0]] = True
                b = self.parents[b]
        # ... per declared DOF (its joint is index // 3).
        self.moved = moved[:, self.declared // 3]  # (K, D)

    def centres(self, posture_deg: np.ndarray, jacobian: bool = False):
        """Bone centres (T, K, 3) m, root still; with ``jacobian`` also
        d centre / d angle, (T, K, 3, D) metres per degree for the declared DOFs."""
        n = posture_deg.shape[0]
        rotations, positions = global_transforms(self.skeleton, posture_deg, np.zeros((n, 6)))
        centres = 0.5 * (positions[:, self.bones] + positions[:, self.parents[self.bones]])
        if not jacobian:
            return centres
        angles = posture_deg.reshape(n, len(JOINTS), 3)
        parent_frame = rotations[:, self.joint_parents] @ self.axis_frames  # R_p C
        rz = axis_rotation(angles[..., 2], "Z")
        ry = axis_rotation(angles[..., 1], "Y")
        # World axis of each DOF: x turns inside Rz Ry, y inside Rz, z directly.
        axes = np.stack([(parent_frame @ rz @ ry)[..., :, 0], (parent_frame @ rz)[..., :, 1],
                         parent_frame[..., :, 2]], axis=2).reshape(n, POSTURE_SIZE, 3)
        pivots = np.repeat(positions[:, self.joint_parents], 3, axis=1)  # (T, 63, 3)
        axes, pivots = axes[:, self.declared], pivots[:, self.declared]
        lever = centres[:, :, None, :] - pivots[:, None, :, :]  # (T, K, D, 3)
        jac = np.cross(axes[:, None, :, :], lever) * self.moved[None, :, :, None]
        return centres, np.radians(1.0) * np.moveaxis(jac, -1, 2)


@functools.lru_cache(maxsize=32)
def _model(skeleton: Skeleton) -> _Model:
    return _Model(skeleton)


#: Armature inertia of every DOF, kg m^2 (angles in radians).
ARMATURE_KG_M2 = 0.01

#: scipy ``trust-exact`` options. The objective is scaled to 1 at the start (the fit of
#: the linear blend); the trust region starts wide (1000 degrees of B-spline coefficient)
#: because the first Gauss-Newton steps are tens of degrees long.
SOLVER_OPTIONS = {"gtol": 1e-6, "maxiter": 200, "initial_trust_radius": 1e3,
                  "max_trust_radius": 1e5}


def effort(skeleton: Skeleton, frames_deg) -> float:
    """The objective E of a run of consecutive postures (see the module docstring).

    Parameters
    ----------
    skeleton : Skeleton
    frames_deg : array_like, shape (F, 63)
        Consecutive postures, continuous along time (unwrapped).

    Returns
    -------
    float
        kg m^2 per frame^4.
    """
    model = _model(skeleton)
    x = np.asarray(frames_deg, dtype=float)
    c = model.centres(x)
    acc = c[2:] - 2.0 * c[1:-1] + c[:-2]
    q = np.radians(x[:, model.declared])
    qacc = q[2:] - 2.0 * q[1:-1] + q[:-2]
    return float(np.einsum("k,tkd,tkd->", model.mass, acc, acc)
                 + ARMATURE_KG_M2 * np.sum(qacc**2))


def _basis(frames: int) -> tuple[np.ndarray, int]:
    """Knots of the window's clamped cubic B-spline (from t = 0 to L + 1) and its number
    of free (inner) coefficients, ``round(L / 4)``, at least 1."""
    end = float(frames + 1)
    n_free = max(1, round(frames / 4))
    inner = np.linspace(0.0, end, n_free + 2)
    return np.concatenate([[0.0] * 3, inner, [end] * 3]), n_free


@dataclass(frozen=True, eq=False)
class SpacetimeSolution:
    """The optimised window.

    Attributes
    ----------
    spline : scipy.interpolate.BSpline
        The trajectory of the declared DOFs, t in frames from A (0) to B (L + 1); values
        shape (D,) per time (degrees, continuous with the problem's context).
    declared : ndarray of int, shape (D,)
        The posture indices the spline drives (the others stay at A's value, 0 on CMU).
    window_deg : ndarray, shape (L, 63)
    effort, effort_linear : float
        The objective of the solution and of the linear blend (same frames, kg m^2 per
        frame^4).
    unknowns, iterations, evaluations : int
    converged : bool
    """

    spline: BSpline
    declared: np.ndarray
    window_deg: np.ndarray
    effort: float
    effort_linear: float
    unknowns: int
    iterations: int
    evaluations: int
    converged: bool


class _Objective:
    """Residuals r(z) (E = r . r) and their Jacobian for the free B-spline coefficients z."""

    def __init__(self, problem: WindowProblem):
        model = _model(problem.skeleton)
        self.model = model
        declared = model.declared
        n, n_dof = problem.frames, declared.size
        knots, n_free = _basis(n)
        self.knots, self.n_free, self.n_dof = knots, n_free, n_dof
        a, b = problem.a_deg[declared], problem.b_deg[declared]
        v_a, v_b = problem.velocity_a[declared], problem.velocity_b[declared]
        # Clamped cubic: q(0) = c0, q'(0) = 3 (c1 - c0) / (knots[4] - knots[1]); likewise
        # at B. The two end coefficients on each side carry the boundary constraints.
        self.end_coefs = (a, a + v_a * (knots[4] - knots[1]) / 3.0,
                          b - v_b * (knots[-2] - knots[-5]) / 3.0, b)
        design = BSpline.design_matrix(problem.window_times, knots, 3).toarray()
        ends = np.stack(self.end_coefs)  # (4, D)
        self.fixed = design[:, [0, 1, -2, -1]] @ ends  # (L, D)
        self.free_basis = design[:, 2:-2]  # (L, n_free)

        before, after = problem.before_deg[-2:], problem.after_deg[:2]
        self.linear = np.concatenate([before, problem.linear(), after])
        first = before.shape[0]
        self.window = slice(first, first + n)
        rows = self.linear.shape[0]
        self.fixed_rows = np.r_[0:first, first + n:rows]
        self.fixed_centres = model.centres(self.linear[self.fixed_rows])
        second = np.zeros((rows - 2, rows))
        k = np.arange(rows - 2)
        second[k, k], second[k, k + 1], second[k, k + 2] = 1.0, -2.0, 1.0
        self.second_window = second[:, self.window]  # (F-2, L)
        self.root_mass = np.sqrt(model.mass)[None, :, None]
        self.root_armature = np.sqrt(ARMATURE_KG_M2) * np.radians(1.0)
        # The joint-space residuals are linear in z: their Jacobian is constant.
        self.joint_jacobian = self.root_armature * np.einsum(
            "ts,sf,de->tdfe", self.second_window, self.free_basis, np.eye(n_dof)
        ).reshape(-1, n_free * n_dof)
        self._z = None

    def start(self) -> np.ndarray:
        """Free coefficients fitting the linear blend (least squares), flat."""
        target = self.linear[self.window][:, self.model.declared] - self.fixed
        return np.linalg.lstsq(self.free_basis, target, rcond=None)[0].ravel()

    def frames(self, z) -> np.ndarray:
        x = self.linear.copy()
        x[self.window, self.model.declared] = self.fixed + self.free_basis @ z.reshape(
            self.n_free, self.n_dof)
        return x

    def _update(self, z) -> None:
        if self._z is not None and np.array_equal(self._z, z):
            return
        x = self.frames(z)
        centres, jac = self.model.centres(x[self.window], jacobian=True)
        c = np.empty((x.shape[0],) + centres.shape[1:])
        c[self.fixed_rows], c[self.window] = self.fixed_centres, centres
        acc = self.root_mass * (c[2:] - 2.0 * c[1:-1] + c[:-2])
        q = x[:, self.model.declared]
        qacc = self.root_armature * (q[2:] - 2.0 * q[1:-1] + q[:-2])
        self._z, self._jac_angles, self._jac = z.copy(), jac, None
        self._residuals = np.concatenate([acc.ravel(), qacc.ravel()])

    def residuals(self, z) -> np.ndarray:
        self._update(z)
        return self._residuals

    def jacobian(self, z) -> np.ndarray:
        """d residuals / d z, shape (R, n_free * D)."""
        self._update(z)
        if self._jac is None:
            jac = self._jac_angles  # (L, K, 3, D): d centre / d angle
            n, size = jac.shape[0], self.n_free * self.n_dof
            per_coef = jac[:, :, :, None, :] * self.free_basis[:, None, None, :, None]
            body = self.second_window @ per_coef.reshape(n, -1)
            body = body.reshape(-1, self.model.bones.size, 3, size) * self.root_mass[..., None]
            self._jac = np.concatenate([body.reshape(-1, size), self.joint_jacobian])
        return self._jac

    def spline(self, z) -> BSpline:
        coefs = np.concatenate([np.stack(self.end_coefs[:2]), z.reshape(self.n_free, self.n_dof),
                                np.stack(self.end_coefs[2:])])
        return BSpline(self.knots, coefs, 3)


def optimise(problem: WindowProblem) -> SpacetimeSolution:
    """Minimise the effort over the window (see the module docstring)."""
    objective = _Objective(problem)
    z0 = objective.start()
    scale = 1.0 / max(float(np.sum(objective.residuals(z0) ** 2)), 1e-300)

    def value(z):
        return scale * float(np.sum(objective.residuals(z) ** 2))

    def gradient(z):
        return 2.0 * scale * (objective.jacobian(z).T @ objective.residuals(z))

    def gauss_newton_hessian(z):
        j = objective.jacobian(z)
        return 2.0 * scale * (j.T @ j)

    result = minimize(value, z0, jac=gradient, hess=gauss_newton_hessian, method="trust-exact",
                      options=dict(SOLVER_OPTIONS))
    x = objective.frames(result.x)
    return SpacetimeSolution(
        spline=objective.spline(result.x), declared=objective.model.declared,
        window_deg=x[objective.window], effort=float(result.fun) / scale,
        effort_linear=effort(problem.skeleton, objective.linear), unknowns=int(result.x.size),
        iterations=int(result.nit), evaluations=int(result.nfev), converged=bool(result.success))


def solve(problem: WindowProblem) -> WindowResult:
    solution = optimise(problem)
    return WindowResult(solution.window_deg, diagnostics={
        "effort": solution.effort,
        "effort_linear": solution.effort_linear,
        "unknowns": float(solution.unknowns),
        "iterations": float(solution.iterations),
        "evaluations": float(solution.evaluations),
        "converged": float(solution.converged),
    })


METHOD = TransitionMethod(
    name="spacetime", solve=solve, continuity="C1", key_kind=None,
    summary="minimum-effort B-spline window with position and velocity boundary constraints, "
            "trust-region Gauss-Newton (a stand-in for Rose et al. 1996)",
)
