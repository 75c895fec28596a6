"""One physics step of the balance controller (:func:`controller.balance.follow`).

At every physics step (``mj_step1``, control, ``mj_step2``) the controller

1. takes the reference at the step's time (prepared by :func:`controller.balance.follow`:
   dropouts filled, low-passed, grounded): hinges and root position interpolated linearly
   between frames, the root quaternion by normalised linear interpolation, velocities and
   accelerations from central differences (:func:`controller.checks.dynamics.finite_differences`);
2. moves the swing foot (:mod:`controller.balance.placement`): by the swing hip, towards where
   the capture offset says it should land, and, by hip and knee, no lower than the
   reference's swing ankle (a swing foot that scrapes the floor is lifted); turns a foot
   in the air by its ankle to the reference's tilt (:mod:`controller.balance.foot_tilt`: the hip
   and knee changes would tilt the sole with them); lets a toe pressed on the floor lie
   flat (:meth:`BalanceControl._flatten_toes`); then keeps every hinge target
   ``tracking.limit_margin_deg`` inside its joint's range (the limits' forces are not in the
   plan);
3. asks for ``qdd_des = qdd_ref + kp e + kd (qd_ref - qd)`` (clipped to
   ``tracking.max_acceleration``) with ``e`` the difference between the target and the state
   (``mj_differentiatePos``): the hinges and the root's orientation and height stiffly, the
   root's horizontal position not at all, only its velocity (the character may drift from
   the reference's path: the drift is reported as ``root_drift_m`` rather than fought);
4. solves whole-body inverse dynamics with the step's floor contacts in friction pyramids,
   no force on the root and each joint's torque range (:class:`controller.balance.wbc.WholeBodyID`),
   in the default mode holding the spine to the clip's posture while the character's
   capture offset is near the reference's (``spine.held_m``: the trunk is left free to
   balance the body where it is not, and in the search's other modes);
5. applies the joint torques through torque actuators: the model is used with its position
   servos turned into torque motors of the same strength (:func:`torque_model`). The root
   has no actuator and ``xfrc_applied`` is never written.

How it does the second step is the controller's :class:`controller.config.Mode`; the
configuration's ``modes`` are the ones the search (:mod:`controller.balance.search`) tries
where the default leads to trouble. Every constant named here in ``section.key`` form is a
field of the :class:`controller.config.ControllerConfig` the controller is given.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from controller.balance.foot_tilt import SwingFootTilt
from controller.balance.placement import capture_error_m
from controller.balance.step_kernels import (
    clip_targets,
    clip_torques,
    desired_acceleration,
    reference_at,
)
from controller.checks.contacts import floor_contacts
from controller.config import DEFAULT, ControllerConfig, Mode


def torque_model(model):
    """A copy of the humanoid whose position servos are torque motors of the same strength.

    Each actuator's force becomes its control (gain 1, no bias), still clamped to the
    actuator's ``forcerange``; the control is not limited otherwise.
    """
    sim = copy.deepcopy(model)
    sim.actuator_gainprm[:] = 0.0
    sim.actuator_gainprm[:, 0] = 1.0
    sim.actuator_biasprm[:] = 0.0
    sim.actuator_biastype[:] = 0
    sim.actuator_ctrllimited[:] = 0
    return sim


def actuator_torque_range(model) -> np.ndarray:
    """Each actuator's torque range, shape (nu, 2) (``forcerange``; unlimited: inf)."""
    limited = model.actuator_forcelimited.astype(bool)[:, None]
    return np.where(limited, model.actuator_forcerange, np.array([-np.inf, np.inf]))


class BalanceControl:
    """One physics step of the controller: targets, foot placement, QP, torques."""

    def __init__(self, sim, smooth, ref_qvel, ref_qacc, substeps, solver, placement,
                 torque_range_nm, config: ControllerConfig = DEFAULT):
        """``sim``: the torque model (:func:`torque_model`); ``smooth``, ``ref_qvel``,
        ``ref_qacc``: the reference's qpos (T, nq), velocities and accelerations (T, nv);
        ``substeps``: physics steps per frame; ``solver``: the QP
        (:class:`controller.balance.wbc.WholeBodyID`); ``placement``:
        :class:`controller.balance.placement.FootPlacement`; ``torque_range_nm``: (nu, 2);
        ``config``: the tuning constants (:class:`controller.config.ControllerConfig`)."""
        import mujoco

        from controller.qpos import joint_layout

        self.sim, self.smooth = sim, smooth
        self._mj_step1, self._mj_step2 = mujoco.mj_step1, mujoco.mj_step2
        self._mj_differentiatePos = mujoco.mj_differentiatePos
        self.ref_qvel, self.ref_qacc = ref_qvel, ref_qacc
        self.substeps, self.solver, self.placement = substeps, solver, placement
        self.n_frames = smooth.shape[0]
        self.config = config
        self.kp, self.kd = tracking_gains(sim.nv, config.tracking)
        self.max_acceleration = config.tracking.max_acceleration
        self.min_toe_pitch_rate = config.toes.min_pitch_rate
        layout = joint_layout(sim)
        self.hinge_q, self.hinge_v = layout.qpos_address, layout.dof_address
        margin = np.deg2rad(config.tracking.limit_margin_deg)
        low, high = np.deg2rad(layout.range_deg.T)
        self.low, self.high = low + margin, high - margin
        self.low_nm, self.high_nm = (np.ascontiguousarray(a)
                                     for a in np.asarray(torque_range_nm).T)
        self.q_ref = np.empty(sim.nq)
        self.qd_ref = np.empty(sim.nv)
        self.qdd_ref = np.empty(sim.nv)
        self.qdd_des = np.empty(sim.nv)
        self.err = np.zeros(sim.nv)
        self.foot_tilt = (SwingFootTilt(sim, smooth, placement.ankle, config)
                          if config.foot_tilt.enabled else None)
        self.toes = {b for b in range(sim.nbody)
                     if "toes" in (mujoco.mj_id2name(sim, mujoco.mjtObj.mjOBJ_BODY, b) or "")}
        # (body, hinge, its qpos address, capsule) of each toe with one hinge
        self.toe_hinges = []
        capsule = int(mujoco.mjtGeom.mjGEOM_CAPSULE)
        for b in sorted(self.toes):
            hinges = [j for j in range(sim.njnt) if sim.jnt_bodyid[j] == b]
            capsules = [g for g in range(sim.ngeom)
                        if sim.geom_bodyid[g] == b and sim.geom_type[g] == capsule]
            if len(hinges) == 1 and capsules:
                self.toe_hinges.append((b, hinges[0], int(sim.jnt_qposadr[hinges[0]]),
                                        capsules[0]))

    def _excluded(self, how: str, frame: int):
        """The bodies whose floor contacts the plan does not lean on
        (:attr:`controller.config.Mode.swing_contacts_excluded`)."""
        if how == "none":
            return ()
        swing = self.placement.swing_bodies(frame)
        return swing & self.toes if how == "swing toes" else swing

    def step(self, data, k: int, mode: Mode, gain: float | None = None):
        """Control and take physics step ``k``; returns the applied and the planned
        torques, (nu,) each."""
        sim, n_frames, q_ref, qd_ref, qdd_ref = (self.sim, self.n_frames, self.q_ref,
                                                 self.qd_ref, self.qdd_ref)
        s = k / self.substeps
        i = min(int(s), n_frames - 2)
        reference_at(self.smooth, self.ref_qvel, self.ref_qacc, i, s - i, q_ref, qd_ref,
                     qdd_ref)
        self._mj_step1(sim, data)
        frame = min(int(round(s)), n_frames - 1)
        floor = floor_contacts(sim, data)
        floor_bodies = floor[1].tolist()
        if self.config.placement.enabled:
            gain = self.config.mode_gain(mode) if gain is None else gain
            self.placement.adjust(data, frame, q_ref, gain, mode.swing_clearance_m,
                                  floor_bodies)
        if self.foot_tilt is not None:
            self.foot_tilt.adjust(data, frame, q_ref, self.placement.touching(floor_bodies))
        self._flatten_toes(data, q_ref, floor_bodies)
        # targets inside the joint ranges: the limits' forces are not in the plan
        clip_targets(q_ref, qd_ref, qdd_ref, self.hinge_q, self.hinge_v, self.low, self.high)
        self._mj_differentiatePos(sim, self.err, 1.0, data.qpos, q_ref)
        desired_acceleration(qdd_ref, self.kp, self.err, self.kd, qd_ref, data.qvel,
                             self.max_acceleration, self.qdd_des)
        held = spine_held(data, self.config.spine) if mode.spine_held else 0.0
        tau = self.solver.torques(
            data, self.qdd_des, exclude=self._excluded(mode.swing_contacts_excluded, frame),
            floor=floor, spine_held=held)
        applied = clip_torques(tau, self.low_nm, self.high_nm)
        data.ctrl[:] = applied
        self._mj_step2(sim, data)
        return applied, tau

    def _flatten_toes(self, data, q_ref, floor_bodies) -> None:
        """A toe pressed on the floor yields until it lies flat: its target in ``q_ref``
        (in place) becomes the angle at which its capsule is level (to first order).
        ``floor_bodies``: the bodies of the state's floor contacts (list of int).

        The toe's strength (about 20 N m) cannot carry the body on the toe's tip: a human
        forefoot bears weight on the ball with the toes pressed flat (the MTP joint
        dorsiflexed by the floor), and a tracked toe angle from mocap would keep the tip
        down and the ball off the floor.
        """
        for body, hinge, qadr, geom in self.toe_hinges:
            if body not in floor_bodies:
                continue
            # the capsule's axis, and how fast its height changes as the hinge turns (the
            # vertical component of axis x direction; either sign of either will do)
            xmat = data.geom_xmat[geom]
            dx, dy, dz = xmat[2], xmat[5], xmat[8]
            ax, ay, _ = data.xaxis[hinge]
            rate = ax * dy - ay * dx
            if abs(rate) >= self.min_toe_pitch_rate:
                q_ref[qadr] = data.qpos[qadr] - dz / rate


def spine_held(data, spine) -> float:
    """How firmly the spine is held to the clip's posture, 0 to 1, by the difference
    between the character's and the reference's capture offsets (the state's): 1 within
    ``spine.held_m`` (:class:`controller.config.sections.SpineConfig`), 0 from
    ``spine.free_m``, linearly between."""
    error = capture_error_m(data)
    if not error.size:
        return 0.0
    return min(1.0, max(0.0, (spine.free_m - float(error[0]))
                        / (spine.free_m - spine.held_m)))


def tracking_gains(nv: int, tracking=DEFAULT.tracking):
    """The tracking's stiffness and damping per degree of freedom, (nv,) each: the hinges
    at ``tracking.joint_hz``, the root's rotation and height at ``root_rotation_hz`` and
    ``root_height_hz``, its horizontal position damped only
    (:class:`controller.config.sections.TrackingConfig`)."""

    def pd(hz):
        w = 2 * math.pi * hz
        return w * w, 2 * tracking.damping_ratio * w

    kp = np.empty(nv)
    kd = np.empty(nv)
    kp[6:], kd[6:] = pd(tracking.joint_hz)
    kp[3:6], kd[3:6] = pd(tracking.root_rotation_hz)
    kp[2], kd[2] = pd(tracking.root_height_hz)
    kp[:2], kd[:2] = 0.0, tracking.root_horizontal_damping_per_s
    return kp, kd

