"""Tracking: the humanoid's position servos follow a motion in simulation (SPEC section 6).

Two modes:

- ``"free"``: the root is free on the floor. The simulation starts from the first frame's
  pose (the whole reference moved in height so that the first frame's lowest point is
  just into the floor: mocap feet hover or sink, a window may begin in the air or on a
  box) and velocity (finite differences), and only the servos move the body: whether it
  stays up is part of the answer.
- ``"driven"``: the root is driven along the reference: before every physics step the
  free joint's position, orientation and velocity are set from the reference
  (interpolated to the step), so the servos only have to move the limbs; floor contacts
  still push the feet and self-contacts still block the limbs.

Servo targets are the reference's hinge angles, unwrapped along time, interpolated
linearly to every physics step and wrapped back (MuJoCo clamps each to its joint's range:
a target beyond the ASF limit cannot be reached). The physics step is the largest step
no longer than the model's (2 ms, ``step.max_step_s``) that divides the frame period
(120 fps: 5 steps of 1.667 ms per frame), so every frame falls on a step.

Reported per frame (the state at the frame's step): the joint tracking error (RMS over
the hinges of the wrapped difference from the reference, degrees), the joint-limit
constraint rows active (``efc_type == mjCNSTR_LIMIT_JOINT``), the self-contacts, the
pelvis and head heights and the largest servo torque; and over the run the share of
steps with a limit active, the fall and MuJoCo's warnings. The character has **fallen**
when its pelvis or head is below half its standing height (``falls.fraction``) while the
reference's is not, and more than a tenth of it (``falls.margin``) below the reference's
(a reference that crouches or lies down is not a fall: :mod:`controller.falls`). A simulation
whose state becomes non-finite, or on which MuJoCo warns of a bad qpos/qvel/qacc
(it then resets the state itself), is stopped: ``diverged_frame`` says where, and
later frames are NaN.
"""

from __future__ import annotations

import time

import numpy as np

from controller.config import DEFAULT, ControllerConfig
from controller.falls import fall_frame, reference_heights
from controller.mjwarnings import collected_warnings, warning_counts
from controller.qpos import wrap_rad
from controller.tracking.plan import (
    MODES,
    TrackingPlan,
    physics_substeps,
    plan_tracking,
    servo_lead_s,
)
from controller.tracking.result import Tracking

__all__ = ["MODES", "Tracking", "TrackingPlan", "physics_substeps",
           "plan_tracking", "servo_lead_s", "track", "track_plan", "track_qpos"]


def track(model, motion, mode: str = "free", lead: bool = True,
          config: ControllerConfig = DEFAULT) -> Tracking:
    """Simulate the humanoid with its servos following a motion.

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid of the motion's skeleton (not modified: a copy is simulated).
    motion : upm.Motion
        The reference, at least 2 frames.
    mode : str
        ``"free"`` (root free on the floor) or ``"driven"`` (root along the reference).
    lead : bool
        Servo targets ahead of the reference by ``kv/kp`` (:func:`servo_lead_s`).
    config : controller.config.ControllerConfig
        Its ``step`` (the longest physics step) and ``falls`` (the fall rule).

    Returns
    -------
    Tracking
    """
    from controller.qpos import to_qpos

    if motion.n_frames < 2:
        raise ValueError("tracking needs a motion of at least 2 frames")
    return track_qpos(model, to_qpos(model, motion), motion.fps, mode, lead, config)


def track_qpos(model, reference_qpos, fps: float, mode: str = "free",
               lead: bool = True, config: ControllerConfig = DEFAULT) -> Tracking:
    """:func:`track` on a reference given as ``qpos``, shape (T, nq), at ``fps``."""
    return track_plan(model, plan_tracking(model, reference_qpos, fps, mode, lead, config),
                      config)


def track_plan(model, plan: TrackingPlan, config: ControllerConfig = DEFAULT) -> Tracking:
    """The tracking simulation of a :class:`TrackingPlan` (made by :func:`plan_tracking`,
    or with the servo targets ``plan.ctrl`` changed: the offline search's replay,
    :mod:`controller.offline`), on ``model`` (the humanoid the plan was made of)."""
    import mujoco

    from controller.body import body_figures
    from controller.mjwarnings import fatal
    from controller.qpos import joint_layout

    mode = plan.mode
    sim, ref, substeps = plan.model, plan.reference_qpos, plan.substeps
    ctrl, root_q, root_v = plan.ctrl, plan.root_qpos, plan.root_qvel
    n_frames = ref.shape[0]
    layout = joint_layout(model)
    free_q = slice(layout.free_qpos, layout.free_qpos + 7)
    free_v = slice(layout.free_dof, layout.free_dof + 6)
    figures = body_figures(model)
    data = plan.start_data()
    record = _FrameRecorder(sim, n_frames)
    record(data, 0)
    steps = limit_steps = 0
    diverged = None
    with collected_warnings() as messages:
        clock = time.perf_counter()
        for t in range(1, n_frames):
            for k in range((t - 1) * substeps, t * substeps):
                data.ctrl[:] = ctrl[k]
                if root_q is not None:
                    data.qpos[free_q] = root_q[k]
                    data.qvel[free_v] = root_v[k]
                mujoco.mj_step(sim, data)
                steps += 1
                limit_steps += bool(data.nl)
            if fatal(data) or not np.all(np.isfinite(data.qpos)):
                diverged = t
                break
            record(data, t)
        wall = time.perf_counter() - clock

    qpos = record.qpos
    hinge_q = layout.qpos_address
    ref_pelvis, ref_head = reference_heights(sim, ref, record.root_body, record.head_site)
    error = np.full((n_frames, hinge_q.size), np.nan)
    simulated = np.isfinite(qpos[:, 0])
    error[simulated] = wrap_rad(qpos[simulated][:, hinge_q] - ref[simulated][:, hinge_q])
    low, high = np.deg2rad(layout.range_deg.T)
    reachable = np.full_like(error, np.nan)
    reachable[simulated] = (qpos[simulated][:, hinge_q]
                            - np.clip(wrap_rad(ref[simulated][:, hinge_q]), low, high))
    return Tracking(
        mode=mode, fps=float(plan.fps), timestep_s=float(sim.opt.timestep), steps=steps,
        wall_s=wall, hinge_names=layout.names, qpos=qpos,
        dof_error_deg=np.rad2deg(error), dof_reachable_error_deg=np.rad2deg(reachable),
        limit_rows=record.limit_rows, limit_steps=limit_steps,
        limit_joint_frames=record.limit_joint_frames(),
        self_contacts=record.self_contacts, self_depth_m=record.self_depth,
        torque_peak_nm=record.torque_peak, pelvis_height_m=record.pelvis,
        head_height_m=record.head, reference_pelvis_height_m=ref_pelvis,
        reference_head_height_m=ref_head, standing_pelvis_m=figures.pelvis_height_m,
        standing_head_m=figures.head_height_m,
        fall_frame=fall_frame(record.pelvis, record.head, ref_pelvis, ref_head, figures,
                              config.falls),
        diverged_frame=diverged, warnings=warning_counts(data),
        messages=tuple(dict.fromkeys(messages))[:10], config=config,
        saturated_actuators=record.saturated, floor_force_n=record.floor_force,
    )


class _FrameRecorder:
    """The per-frame figures of a tracking simulation, recorded from ``MjData``."""

    def __init__(self, model, n_frames: int):
        import mujoco

        from controller.qpos import free_joint

        self.model = model
        self.limit_type = int(mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT)
        self.root_body = int(model.jnt_bodyid[free_joint(model)])
        self.head_site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "head_end")
        self.qpos = np.full((n_frames, model.nq), np.nan)
        self.limit_rows = np.zeros(n_frames, dtype=int)
        self.self_contacts = np.zeros(n_frames, dtype=int)
        self.self_depth = np.zeros(n_frames)
        self.torque_peak = np.full(n_frames, np.nan)
        self.pelvis = np.full(n_frames, np.nan)
        self.head = np.full(n_frames, np.nan)
        self.saturated = np.zeros(n_frames)
        self.floor_force = np.full(n_frames, np.nan)
        limited = np.asarray(model.actuator_forcelimited, dtype=bool)
        self.force_limit = np.where(limited, np.abs(model.actuator_forcerange).max(axis=1),
                                    np.inf)
        self.joint_frames = np.zeros(model.njnt, dtype=int)

    def __call__(self, data, t: int) -> None:
        from controller.body import floor_normal_force

        self.qpos[t] = data.qpos
        self.floor_force[t] = floor_normal_force(self.model, data)
        ncon = data.ncon
        if ncon:
            bodies = self.model.geom_bodyid[np.asarray(data.contact.geom[:ncon])]
            inner = (bodies[:, 0] != 0) & (bodies[:, 1] != 0)
            self.self_contacts[t] = int(inner.sum())
            if inner.any():
                depth = -np.asarray(data.contact.dist[:ncon])[inner].min()
                self.self_depth[t] = max(0.0, float(depth))
        rows = data.efc_type[:data.nefc] == self.limit_type
        self.limit_rows[t] = int(np.count_nonzero(rows))
        self.joint_frames[data.efc_id[:data.nefc][rows]] += 1
        force = np.abs(data.actuator_force)
        self.torque_peak[t] = float(force.max(initial=0.0))
        if force.size:
            self.saturated[t] = float(np.mean(force >= self.force_limit * (1 - 1e-6)))
        self.pelvis[t] = data.xpos[self.root_body, 2]
        self.head[t] = data.site_xpos[self.head_site, 2]

    def limit_joint_frames(self) -> dict[str, int]:
        """Per hinge (posture DOF name), frames with its limit active, most first."""
        import mujoco

        order = np.argsort(-self.joint_frames, kind="stable")
        return {(mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_JOINT, int(j)) or "")
                .replace("_", ".", 1): int(self.joint_frames[j])
                for j in order if self.joint_frames[j] > 0}
