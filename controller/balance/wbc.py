"""Whole-body inverse dynamics with floor contact: the joint torques of one control step.

Given the state (after ``mj_step1``: kinematics, inertia, bias forces, contacts) and the
desired generalised acceleration ``qdd_des`` (nv,), find the acceleration ``qdd`` and the
floor forces ``f`` that best satisfy, in weighted least squares,

- ``qdd`` close to ``qdd_des`` (the root rows and the joint rows weighted separately; the
  spine's and neck's rows more while the controller holds the trunk to the clip's posture,
  :meth:`WholeBodyID.joint_weights`);
- every floor contact point kept from accelerating (``a_c = J_c qdd ~ -k v_c``, soft);
- small forces and small torques relative to each joint's strength (regularisation);

subject, exactly, to

- the 6 unactuated root rows of ``M qdd + h = S^T tau + J_c^T f``: no force acts on the
  root but gravity, inertia and the floor (``h`` = bias minus passive forces);
- each contact force inside a linearised friction pyramid: ``f = sum_e lambda_e d_e``
  with ``d_e = n +- mu t`` on 4 edges and ``lambda_e >= 0`` (the floor only pushes).

- every joint torque ``tau = (M qdd + h - J_c^T f)_joints`` within the joint's strength
  (the actuator's ``forcerange``): the ankles of these humanoids cannot hold the body's
  weight far from the ankle, so the plan must not count on it.

The root rows are solved for the root acceleration, which leaves a quadratic programme in
the joint accelerations and the edge magnitudes (about 45 + 4 x contacts unknowns). Its
terms are set up in one compiled call (:func:`controller.balance.qp_kernels.qp_cost_terms`; the
inequalities only where the QP is solved from scratch).

From one physics step to the next the QP's active set (which edge magnitudes are 0, which
torques are at a bound) rarely changes. So it is first solved with the last step's active
set as equalities (:func:`controller.balance.qp_kernels.solve_active_set`: the edges remembered with
the planned contacts' geoms in the MuJoCo state's ``userdata``, so that a rollout from a
saved state solves exactly as the run did; the torques at a bound read from the applied
torques), and the full problem's KKT conditions checked. Where they fail, or the contacts
changed, ``quadprog``
(Goldfarb-Idnani, dense) solves it from scratch, with the torque bounds of the hinges whose
applied torque is near a bound in the first solve and any other bound its solution breaks in
the next (the minimiser is that of the QP with every bound either way: the problem is
convex). The tolerances are tight enough that both give the same torques to about 1e-5 N m
(the QP is nearly flat in how the weight is shared among the contact edges, so a looser
multiplier test accepts points whose torques differ by newton-metres).
"""

from __future__ import annotations

import numpy as np
import quadprog

from controller.balance.qp_kernels import (
    break_bounds,
    hinges_at_bounds,
    near_bounds,
    qp_cost_terms,
    recall_active,
    remember_active,
    solve_active_set,
    watched_constraints,
)
from controller.checks.contacts import floor_contacts
from controller.config import DEFAULT, ControllerConfig

_NO_GEOMS = np.zeros((0, 2), dtype=np.int32)
_NO_POINTS = np.zeros((0, 3))


class WholeBodyID:
    """The per-step solver of one model (buffers allocated once).

    Parameters
    ----------
    model : mujoco.MjModel
        The simulated humanoid: one free joint at DOFs 0-5, then one hinge per actuator.
    joint_dofs : ndarray of int, shape (nu,)
        The DOF each actuator drives, in actuator order.
    torque_range_nm : ndarray, shape (nu, 2)
        Each actuator's torque range (its ``forcerange``: lower, upper).
    config : controller.config.ControllerConfig
        Its ``qp`` (the least-squares weights), ``contact`` (the friction pyramid, the
        contact damping), ``solver`` (the warm start's tolerances) and ``spine.bodies``.
    """

    def __init__(self, model, joint_dofs, torque_range_nm,
                 config: ControllerConfig = DEFAULT):
        import mujoco

        self.model = model
        self._mj_fullM, self._mj_jac = mujoco.mj_fullM, mujoco.mj_jac
        self.nv = int(model.nv)
        self.joint_dofs = np.asarray(joint_dofs, dtype=int)
        if sorted(self.joint_dofs.tolist()) != list(range(6, self.nv)):
            raise ValueError("whole-body control needs the free joint at DOFs 0-5 and one "
                             "actuator per hinge")
        self.hinge_row = self.joint_dofs - 6  # actuator a drives hinge row hinge_row[a]
        torque_range = np.asarray(torque_range_nm, dtype=float)
        self.low = np.empty(self.nv - 6)
        self.high = np.empty(self.nv - 6)
        self.low[self.hinge_row] = torque_range[:, 0]
        self.high[self.hinge_row] = torque_range[:, 1]
        self.strength = np.maximum(-self.low, self.high)
        self.w = config.qp
        self.contact_damping = float(config.contact.damping_per_s)
        solver = config.solver
        self.near_bound = solver.near_bound_share
        self.force_tolerance = solver.force_tolerance_bw
        self.multiplier_tolerance = solver.multiplier_tolerance
        self.mass = float(np.sum(model.body_mass[1:]))
        self.weight_n = self.mass * float(np.linalg.norm(model.opt.gravity))
        self.M = np.zeros((self.nv, self.nv))
        self._jacp = np.zeros((3, self.nv))
        mu = config.contact.friction
        self.edges = np.array([[mu, 0, 1], [-mu, 0, 1], [0, mu, 1], [0, -mu, 1]], float)
        self.edges /= np.linalg.norm(self.edges, axis=1, keepdims=True)
        # root rotation rows are about the pelvis's own axes; its z axis is the body's up
        root_w = np.array([self.w.root_horizontal] * 2 + [self.w.root_height]
                          + [self.w.root_rotation] * 2 + [self.w.root_yaw])
        self.root_w = root_w
        self.torque_scale = self.w.torque / self.strength
        names = [model.joint(int(model.dof_jntid[d])).name.split("_")[0]
                 for d in range(6, self.nv)]
        self.spine_rows = np.flatnonzero(np.isin(names, config.spine.bodies))
        self.joint_w = np.full(self.nv - 6, self.w.joints)
        self._held_w = self.joint_w.copy()
        self.actuator_of_hinge = np.argsort(self.hinge_row)
        self.tolerance = solver.bound_tolerance_share * self.strength
        self.at_bound = solver.at_bound_share * np.where(np.isfinite(self.strength),
                                                         self.strength, 0.0)

    def floor_contacts(self, data, exclude=(), floor=None):
        """The planned floor contacts: ``(points (m, 3), bodies (m,), index (m,))``, index
        into ``data.contact``, without the contacts of the bodies in ``exclude``;
        ``floor``: the state's :func:`controller.checks.contacts.floor_contacts` if already
        found."""
        return self._planned(data, exclude, floor)[:3]

    def _planned(self, data, exclude, floor):
        """:meth:`floor_contacts` and their geom pairs, ``(m, 2)``."""
        index, body = floor_contacts(self.model, data) if floor is None else floor
        if not index.size:
            return _NO_POINTS, body, index, _NO_GEOMS
        contact = data.contact
        pts, geoms = contact.pos[index], contact.geom[index]
        if exclude:
            keep = np.array([b not in exclude for b in body.tolist()], dtype=bool)
            pts, body, index, geoms = pts[keep], body[keep], index[keep], geoms[keep]
        return pts, body, index, geoms

    def solve(self, data, qdd_des, contact_damping: float | None = None, exclude=(),
              floor=None):
        """Torques for the current state.

        Parameters
        ----------
        data : mujoco.MjData
            After ``mj_step1`` (or ``mj_forward``).
        qdd_des : ndarray, shape (nv,)
        contact_damping : float
            Desired contact-point acceleration ``-contact_damping * v_c``, 1/s.
        exclude : set of int
            Bodies whose floor contacts are not planned as support (a swing foot that
            scrapes the floor: the floor still pushes it, the plan does not lean on it).
        floor : tuple of ndarray, optional
            The state's :func:`controller.checks.contacts.floor_contacts`, if already found.

        Returns
        -------
        tau : ndarray, shape (nu,)
            Torques in actuator order (not clipped).
        qdd : ndarray, shape (nv,)
            The planned acceleration.
        normal_n : float
            The planned total normal force, N.
        """
        tau, x, G, g0, nc = self._plan(data, qdd_des, contact_damping, exclude, floor)
        qdd = G @ x + g0
        # every edge has the same normal component
        lam = x[self.nv - 6:]
        normal = float(np.sum(lam) * self.edges[0, 2] * self.weight_n) if nc else 0.0
        return tau, qdd, normal

    def torques(self, data, qdd_des, exclude=(), floor=None, spine_held: float = 0.0):
        """The torques of :meth:`solve` alone (nu,), at the default contact damping."""
        return self._plan(data, qdd_des, None, exclude, floor, spine_held)[0]

    def joint_weights(self, spine_held: float) -> np.ndarray:
        """Each hinge acceleration row's weight (nv - 6,): ``joints``, the spine's and
        neck's hinges (the configuration's ``spine.bodies``) times ``1 + (spine - 1) spine_held``. A
        view of the solver's own buffer, valid until the next call."""
        if not spine_held:
            return self.joint_w
        self._held_w[self.spine_rows] = (self.joint_w[self.spine_rows]
                                         * (1.0 + (self.w.spine - 1.0) * spine_held))
        return self._held_w

    def _plan(self, data, qdd_des, contact_damping, exclude, floor, spine_held=0.0):
        """:meth:`solve`'s QP: ``(tau (nu,), x (n,), G (nv, n), g0 (nv,), contacts)``."""
        if contact_damping is None:
            contact_damping = self.contact_damping
        model, nv, w = self.model, self.nv, self.w
        M = self.M
        self._mj_fullM(model, data, M)
        h = np.subtract(data.qfrc_bias, data.qfrc_passive)
        pts, bodies, _, geoms = self._planned(data, exclude, floor)
        nc = pts.shape[0]
        Jc = np.empty((3 * nc, nv))
        jacp = self._jacp
        for i in range(nc):
            self._mj_jac(model, data, jacp, None, pts[i], int(bodies[i]))
            Jc[3 * i:3 * i + 3] = jacp
        nj = nv - 6
        # Without floor contact nothing but the limbs' reaction turns the root: asking for
        # a root acceleration would only fling the limbs.
        root_w = self.root_w if nc else self.root_w * w.flight_root
        P, q, G, g0, T, t0 = qp_cost_terms(
            M, h, Jc, np.asarray(data.qvel), np.asarray(qdd_des, dtype=float), self.edges,
            self.weight_n, root_w, self.joint_weights(spine_held), w.contact, w.force,
            self.torque_scale,
            float(contact_damping))
        nl = P.shape[0] - nj
        # Warm start: the edges whose force was 0 at the last step (carried in the MuJoCo
        # state's userdata, so a rollout from a saved state solves as the run did) and the
        # hinges whose applied torque is at a bound are guessed to be the active set; the
        # guess is right when the KKT conditions hold (the QP's minimiser, at about a
        # quarter of the cost), else the QP is solved from scratch.
        # (its last entry is the foot placement's: controller.balance.placement.capture_error_m)
        memory = data.userdata[:-1]
        x = None
        if nl:
            fixed, known = recall_active(memory, geoms)
            if known:
                upper, lower = hinges_at_bounds(data.ctrl, self.actuator_of_hinge, self.low,
                                                self.high, self.at_bound)
                try:
                    x, ok = solve_active_set(P, q, T, t0, self.low, self.high, nl, fixed,
                                             upper, lower, self.tolerance,
                                             self.force_tolerance,
                                             self.multiplier_tolerance)
                except np.linalg.LinAlgError:  # a guess with no solution: not this one
                    ok = False
                x = x if ok else None
        if x is not None:
            tau_hinge = T @ x + t0
        else:
            x, tau_hinge, fixed = self._solve_cold(data, P, q, T, t0, nl)
        remember_active(memory, geoms, fixed)
        return tau_hinge[self.hinge_row], x, G, g0, nc

    def _solve_cold(self, data, P, q, T, t0, nl):
        """The QP from scratch: ``(x, hinge torques, which edge magnitudes are 0 (nl,))``.

        Most torque bounds are far from binding; the QP is solved with those of the hinges
        whose applied torque (in the state) is near its bound, and solved again with any
        bound its solution breaks, until it breaks none: the same minimiser as with every
        bound (the problem is convex), at about half the solver's cost.
        """
        nj = self.nv - 6
        watched = near_bounds(data.ctrl, self.actuator_of_hinge, self.low, self.high,
                              self.strength, self.near_bound)
        while True:
            try:
                if nl or watched.any():
                    Cs, ds = watched_constraints(T, t0, self.low, self.high, nl, watched)
                    x, _, _, _, _, active = quadprog.solve_qp(P, q, Cs, ds, 0)
                else:
                    x, active = np.linalg.solve(P, q), None
            except (ValueError, np.linalg.LinAlgError):
                # numerically infeasible: least squares, forces clipped at 0
                x = np.linalg.lstsq(P, q, rcond=None)[0]
                x[nj:] = np.maximum(x[nj:], 0.0)
                return x, T @ x + t0, x[nj:] <= 0.0
            tau_hinge = T @ x + t0
            if not break_bounds(tau_hinge, self.low, self.high, self.tolerance, watched):
                fixed = np.zeros(nl, dtype=bool)
                if nl:
                    active = active[(active >= 1) & (active <= nl)] - 1  # 1-based columns
                    fixed[active] = True
                return x, tau_hinge, fixed
