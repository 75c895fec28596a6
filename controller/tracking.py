"""Tracking: the humanoid's position servos follow a motion in simulation (SPEC section 6).

Two modes:

- ``"free"``: the root is free on the floor. The simulation starts from the first frame's
  pose (raised by its floor penetration, if any, so that it does not start inside the
  floor) and velocity (finite differences), and only the servos move the body: whether it
  stays up is part of the answer.
- ``"driven"``: the root is driven along the reference: before every physics step the
  free joint's position, orientation and velocity are set from the reference
  (interpolated to the step), so the servos only have to move the limbs; floor contacts
  still push the feet and self-contacts still block the limbs.

Servo targets are the reference's hinge angles, unwrapped along time, interpolated
linearly to every physics step and wrapped back (MuJoCo clamps each to its joint's range:
a target beyond the ASF limit cannot be reached). The physics step is the largest step
no longer than the model's (2 ms) that divides the frame period (120 fps: 5 steps of
1.667 ms per frame), so every frame falls on a step.

Reported per frame (the state at the frame's step): the joint tracking error (RMS over
the hinges of the wrapped difference from the reference, degrees), the joint-limit
constraint rows active (``efc_type == mjCNSTR_LIMIT_JOINT``), the self-contacts, the
pelvis and head heights and the largest servo torque; and over the run the share of
steps with a limit active, the fall and MuJoCo's warnings. The character has **fallen**
when its pelvis or head is below :data:`FALL_FRACTION` of its standing height while the
reference's is not (a reference that crouches or lies down is not a fall). A simulation
whose state becomes non-finite, or on which MuJoCo warns of a bad qpos/qvel/qacc
(it then resets the state itself), is stopped: ``diverged_frame`` says where, and
later frames are NaN.
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass

import numpy as np

from controller.contacts import SELF_COLLISION_DEPTH_M
from controller.dynamics import half_step_velocities

#: Fallen: pelvis or head below this share of its standing height (the reference's not).
FALL_FRACTION = 0.5
#: The longest physics step used, seconds (the model's own timestep).
MAX_STEP_S = 0.002
#: The tracking modes.
MODES = ("free", "driven")
#: MuJoCo warnings after which the state is no longer the simulation's.
_FATAL_WARNINGS = ("mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC")


@dataclass(frozen=True)
class Tracking:
    """One tracking simulation of a motion.

    Attributes
    ----------
    mode : str
        ``"free"`` or ``"driven"``.
    fps : float
        The motion's frame rate (the per-frame arrays are at its frames).
    timestep_s : float
        The physics step used.
    steps : int
        Physics steps simulated.
    wall_s : float
        Wall-clock seconds of the stepping loop.
    hinge_names : tuple of str
        Posture DOF of each hinge (``"lfemur.rx"``), the columns of ``dof_error_deg``.
    qpos : ndarray, shape (T, nq)
        The simulated state at every frame (NaN after a divergence).
    dof_error_deg : ndarray, shape (T, H)
        Simulated minus reference hinge angle, wrapped to [-180, 180), degrees.
    dof_reachable_error_deg : ndarray, shape (T, H)
        Simulated angle minus the reference clamped into the hinge's range (what the
        servo is asked to reach: a reference beyond its ASF limit cannot be), degrees.
    limit_rows : ndarray of int, shape (T,)
        Active joint-limit constraint rows at each frame.
    limit_steps : int
        Steps with at least one joint-limit row active.
    limit_joint_frames : dict of str to int
        Per hinge, frames at which its limit was active (most first).
    self_contacts : ndarray of int, shape (T,)
        Self-contacts (any depth) at each frame.
    self_depth_m : ndarray, shape (T,)
        Deepest self-contact at each frame.
    torque_peak_nm : ndarray, shape (T,)
        Largest servo torque at each frame (absolute), N m.
    pelvis_height_m, head_height_m : ndarray, shape (T,)
        Simulated heights; ``reference_pelvis_height_m``, ``reference_head_height_m``
        the reference's.
    standing_pelvis_m, standing_head_m : float
        The model's standing heights (the fall thresholds' base).
    fall_frame : int or None
        First frame at which the character has fallen.
    diverged_frame : int or None
        Frame at which the simulation was stopped for a non-finite state or a fatal
        warning.
    warnings : dict of str to int
        MuJoCo's warning counters that are not zero (``"mjWARN_CONTACTFULL"``: n).
    messages : tuple of str
        MuJoCo's warning texts (the first 10 distinct ones).
    """

    mode: str
    fps: float
    timestep_s: float
    steps: int
    wall_s: float
    hinge_names: tuple[str, ...]
    qpos: np.ndarray
    dof_error_deg: np.ndarray
    dof_reachable_error_deg: np.ndarray
    limit_rows: np.ndarray
    limit_steps: int
    limit_joint_frames: dict[str, int]
    self_contacts: np.ndarray
    self_depth_m: np.ndarray
    torque_peak_nm: np.ndarray
    pelvis_height_m: np.ndarray
    head_height_m: np.ndarray
    reference_pelvis_height_m: np.ndarray
    reference_head_height_m: np.ndarray
    standing_pelvis_m: float
    standing_head_m: float
    fall_frame: int | None
    diverged_frame: int | None
    warnings: dict[str, int]
    messages: tuple[str, ...] = ()

    @property
    def n_frames(self) -> int:
        return self.qpos.shape[0]

    @property
    def error_deg(self) -> np.ndarray:
        """RMS over the hinges of the tracking error at each frame, (T,) degrees."""
        return np.sqrt(np.mean(self.dof_error_deg ** 2, axis=1))

    @property
    def fell(self) -> bool:
        return self.fall_frame is not None

    @property
    def fall_time_s(self) -> float | None:
        return None if self.fall_frame is None else self.fall_frame / self.fps

    @property
    def fallen(self) -> np.ndarray:
        """Frames at or after the fall, bool (T,)."""
        out = np.zeros(self.n_frames, dtype=bool)
        if self.fall_frame is not None:
            out[self.fall_frame:] = True
        return out

    @property
    def steps_per_s(self) -> float:
        return self.steps / self.wall_s if self.wall_s > 0 else math.inf

    def summary(self, part: slice | None = None) -> dict:
        """Figures over a part of the motion (all frames by default), JSON-ready.

        The tracking error is over the frames before the fall and divergence (``error_*``)
        and over all frames of the part that were simulated (``error_all_*``);
        ``reachable_error_deg_rms`` is the error to the reference clamped into the joint
        ranges, before the fall (the servos' own accuracy, without the targets they cannot
        reach).
        """
        index = np.arange(self.n_frames)[part if part is not None else slice(None)]
        simulated = index if self.diverged_frame is None else index[index < self.diverged_frame]
        standing = simulated[~self.fallen[simulated]]
        err = self.error_deg
        out = {
            "frames": int(index.size),
            "fell": bool(self.fall_frame is not None and self.fall_frame in set(index)),
            "error_deg_rms": _rms(self.dof_error_deg[standing]),
            "error_deg_peak": _round(err[standing].max()) if standing.size else None,
            "error_all_deg_rms": _rms(self.dof_error_deg[simulated]),
            "reachable_error_deg_rms": _rms(self.dof_reachable_error_deg[standing]),
            "limit_active_frames": int((self.limit_rows[simulated] > 0).sum()),
            "limit_active_pct": (round(100 * float((self.limit_rows[simulated] > 0).mean()),
                                       2) if simulated.size else None),
            "self_collision_frames": int((self.self_depth_m[simulated]
                                          > SELF_COLLISION_DEPTH_M).sum()),
            "self_contact_frames": int((self.self_contacts[simulated] > 0).sum()),
            "torque_peak_nm": (_round(self.torque_peak_nm[simulated].max())
                               if simulated.size else None),
        }
        return out

    def run_summary(self) -> dict:
        """Whole-run figures (steps, fall, warnings, speed), JSON-ready."""
        return {
            "mode": self.mode,
            "timestep_s": self.timestep_s,
            "steps": self.steps,
            "steps_per_s": round(self.steps_per_s, 1),
            "fell": self.fell,
            "fall_frame": self.fall_frame,
            "fall_time_s": None if self.fall_time_s is None else round(self.fall_time_s, 4),
            "fall_rule": (f"pelvis or head below {FALL_FRACTION:g} x standing height "
                          f"({FALL_FRACTION * self.standing_pelvis_m:.3f} m, "
                          f"{FALL_FRACTION * self.standing_head_m:.3f} m) while the "
                          "reference's is not"),
            "diverged_frame": self.diverged_frame,
            "warnings": dict(self.warnings),
            "warning_messages": list(self.messages),
            "limit_active_steps_pct": round(100 * self.limit_steps / max(self.steps, 1), 2),
            "limit_joint_frames": dict(self.limit_joint_frames),
            **self.summary(),
        }


def physics_substeps(fps: float, max_step_s: float = MAX_STEP_S) -> int:
    """Physics steps per frame: the fewest whose step is no longer than ``max_step_s``."""
    return max(1, math.ceil(1.0 / (fps * max_step_s) - 1e-9))


def track(model, motion, mode: str = "free", lead: bool = True) -> Tracking:
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

    Returns
    -------
    Tracking
    """
    from controller.qpos import to_qpos

    if motion.n_frames < 2:
        raise ValueError("tracking needs a motion of at least 2 frames")
    return track_qpos(model, to_qpos(model, motion), motion.fps, mode, lead)


@dataclass(frozen=True, eq=False)
class TrackingPlan:
    """What a tracking simulation feeds MuJoCo, step by step.

    Attributes
    ----------
    model : mujoco.MjModel
        A copy of the humanoid with the physics step set (``opt.timestep``).
    mode : str
    fps : float
    substeps : int
        Physics steps per frame.
    reference_qpos : ndarray, shape (T, nq)
        The reference, hinges unwrapped.
    start_qpos, start_qvel : ndarray, shape (nq,), (nv,)
        The first state.
    ctrl : ndarray, shape ((T-1) * substeps, nu)
        Servo targets of every step.
    root_qpos : ndarray, shape ((T-1) * substeps, 7), or None
        ``"driven"``: the free joint's state set before every step (else None).
    root_qvel : ndarray, shape ((T-1) * substeps, 6), or None
    """

    model: object
    mode: str
    fps: float
    substeps: int
    reference_qpos: np.ndarray
    start_qpos: np.ndarray
    start_qvel: np.ndarray
    ctrl: np.ndarray
    root_qpos: np.ndarray | None
    root_qvel: np.ndarray | None

    @property
    def steps(self) -> int:
        return self.ctrl.shape[0]

    def start_data(self):
        """A fresh ``MjData`` in the first state, first targets set, forward computed."""
        import mujoco

        data = mujoco.MjData(self.model)
        data.qpos[:] = self.start_qpos
        data.qvel[:] = self.start_qvel
        data.ctrl[:] = self.ctrl[0]
        mujoco.mj_forward(self.model, data)
        return data


def plan_tracking(model, reference_qpos, fps: float, mode: str = "free",
                  lead: bool = True) -> TrackingPlan:
    """The step-by-step inputs of a tracking simulation (see the module docstring).

    Parameters
    ----------
    model : mujoco.MjModel
        Not modified (the plan holds a copy).
    reference_qpos : array_like, shape (T, nq), T >= 2
    fps : float
    mode : str
        ``"free"`` or ``"driven"``.
    lead : bool
        Take servo targets :func:`servo_lead_s` ahead of the reference (else at it).

    Returns
    -------
    TrackingPlan
    """
    import mujoco

    from controller.dynamics import unwrap_hinges
    from controller.qpos import joint_layout

    if mode not in MODES:
        raise ValueError(f"unknown tracking mode {mode!r} (modes: {', '.join(MODES)})")
    ref = unwrap_hinges(model, reference_qpos)
    if ref.shape[0] < 2:
        raise ValueError("tracking needs at least 2 frames")
    layout = joint_layout(model)
    sim = copy.copy(model)
    substeps = physics_substeps(fps, min(MAX_STEP_S, float(model.opt.timestep)))
    sim.opt.timestep = 1.0 / (fps * substeps)
    free_q = slice(layout.free_qpos, layout.free_qpos + 7)
    free_v = slice(layout.free_dof, layout.free_dof + 6)
    half_vel = half_step_velocities(sim, ref, fps)  # (T-1, nv)
    ctrl = _actuator_targets(sim, ref, substeps, servo_lead_s(sim) * fps * float(lead))
    driven = mode == "driven"
    start = ref[0].copy()
    if not driven:
        start[layout.free_qpos + 2] += floor_depth(sim, mujoco.MjData(sim), start)
    return TrackingPlan(
        model=sim, mode=mode, fps=float(fps), substeps=substeps, reference_qpos=ref,
        start_qpos=start, start_qvel=half_vel[0].copy(), ctrl=ctrl,
        root_qpos=_root_path(ref[:, free_q], substeps) if driven else None,
        root_qvel=np.repeat(half_vel[:, free_v], substeps, axis=0) if driven else None,
    )


def track_qpos(model, reference_qpos, fps: float, mode: str = "free",
               lead: bool = True) -> Tracking:
    """:func:`track` on a reference given as ``qpos``, shape (T, nq), at ``fps``."""
    import mujoco

    from controller.body import body_figures
    from controller.qpos import joint_layout

    plan = plan_tracking(model, reference_qpos, fps, mode, lead)
    sim, ref, substeps = plan.model, plan.reference_qpos, plan.substeps
    ctrl, root_q, root_v = plan.ctrl, plan.root_qpos, plan.root_qvel
    n_frames = ref.shape[0]
    layout = joint_layout(model)
    hinge_q = layout.qpos_address
    free_q = slice(layout.free_qpos, layout.free_qpos + 7)
    free_v = slice(layout.free_dof, layout.free_dof + 6)
    figures = body_figures(model)
    data = plan.start_data()

    limit_type = int(mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT)
    joint_names = [mujoco.mj_id2name(sim, mujoco.mjtObj.mjOBJ_JOINT, j) or ""
                   for j in range(sim.njnt)]
    root_body = _root_body(sim)
    head_site = mujoco.mj_name2id(sim, mujoco.mjtObj.mjOBJ_SITE, "head_end")
    geom_body = sim.geom_bodyid
    fatal = [int(getattr(mujoco.mjtWarning, w)) for w in _FATAL_WARNINGS]

    qpos = np.full((n_frames, sim.nq), np.nan)
    limit_rows = np.zeros(n_frames, dtype=int)
    self_contacts = np.zeros(n_frames, dtype=int)
    self_depth = np.zeros(n_frames)
    torque_peak = np.full(n_frames, np.nan)
    pelvis = np.full(n_frames, np.nan)
    head = np.full(n_frames, np.nan)
    joint_frames = np.zeros(sim.njnt, dtype=int)
    limit_steps = 0
    diverged = None

    def sample(t: int) -> None:
        qpos[t] = data.qpos
        ncon = data.ncon
        if ncon:
            bodies = geom_body[np.asarray(data.contact.geom[:ncon])]
            inner = (bodies[:, 0] != 0) & (bodies[:, 1] != 0)
            self_contacts[t] = int(inner.sum())
            if inner.any():
                self_depth[t] = max(0.0, float(-np.asarray(data.contact.dist[:ncon])[inner].min()))
        rows = data.efc_type[:data.nefc] == limit_type
        limit_rows[t] = int(np.count_nonzero(rows))
        joint_frames[data.efc_id[:data.nefc][rows]] += 1
        torque_peak[t] = float(np.abs(data.actuator_force).max(initial=0.0))
        pelvis[t] = data.xpos[root_body, 2]
        head[t] = data.site_xpos[head_site, 2]

    sample(0)
    steps = 0
    messages: list[str] = []
    previous_handler = mujoco.get_mju_user_warning()
    # MuJoCo's own handler prints and appends to MUJOCO_LOG.TXT in the working directory;
    # the messages go into the result instead.
    mujoco.set_mju_user_warning(lambda text: messages.append(" ".join(str(text).split())))
    clock = time.perf_counter()
    try:
        for t in range(1, n_frames):
            for k in range((t - 1) * substeps, t * substeps):
                data.ctrl[:] = ctrl[k]
                if root_q is not None:
                    data.qpos[free_q] = root_q[k]
                    data.qvel[free_v] = root_v[k]
                mujoco.mj_step(sim, data)
                steps += 1
                if data.nl:
                    limit_steps += 1
            bad = any(data.warning[w].number for w in fatal)
            if bad or not np.all(np.isfinite(data.qpos)):
                diverged = t
                break
            sample(t)
    finally:
        mujoco.set_mju_user_warning(previous_handler)
    wall = time.perf_counter() - clock

    ref_pelvis, ref_head = _reference_heights(sim, ref, root_body, head_site)
    error = np.full((n_frames, hinge_q.size), np.nan)
    simulated = np.isfinite(qpos[:, 0])
    error[simulated] = _wrap_rad(qpos[simulated][:, hinge_q] - ref[simulated][:, hinge_q])
    low, high = np.deg2rad(layout.range_deg.T)
    reachable = np.full_like(error, np.nan)
    reachable[simulated] = (qpos[simulated][:, hinge_q]
                            - np.clip(_wrap_rad(ref[simulated][:, hinge_q]), low, high))
    warnings = {name: int(data.warning[int(getattr(mujoco.mjtWarning, name))].number)
                for name in mujoco.mjtWarning.__members__ if name != "mjNWARNING"}
    order = np.argsort(-joint_frames, kind="stable")
    return Tracking(
        mode=mode, fps=float(fps), timestep_s=float(sim.opt.timestep), steps=steps,
        wall_s=wall, hinge_names=layout.names, qpos=qpos,
        dof_error_deg=np.rad2deg(error), dof_reachable_error_deg=np.rad2deg(reachable),
        limit_rows=limit_rows, limit_steps=limit_steps,
        limit_joint_frames={joint_names[j].replace("_", ".", 1): int(joint_frames[j])
                            for j in order if joint_frames[j] > 0},
        self_contacts=self_contacts, self_depth_m=self_depth, torque_peak_nm=torque_peak,
        pelvis_height_m=pelvis, head_height_m=head, reference_pelvis_height_m=ref_pelvis,
        reference_head_height_m=ref_head, standing_pelvis_m=figures.pelvis_height_m,
        standing_head_m=figures.head_height_m,
        fall_frame=_fall_frame(pelvis, head, ref_pelvis, ref_head, figures),
        diverged_frame=diverged,
        warnings={k: v for k, v in warnings.items() if v},
        messages=tuple(dict.fromkeys(messages))[:10],
    )


def _root_body(model) -> int:
    import mujoco

    free = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_FREE)
    return int(model.jnt_bodyid[free[0]])


def _wrap_rad(x):
    return np.mod(x + np.pi, 2 * np.pi) - np.pi


def servo_lead_s(model) -> np.ndarray:
    """How far ahead of the reference each servo's target is taken, ``kv / kp`` seconds,
    shape (nu,).

    A position servo pushes ``kp (target - q) - kv qdot``; with the target taken ``kv/kp``
    ahead, ``kp (q_ref(t + kv/kp) - q) - kv qdot ~ kp (q_ref - q) + kv (qdot_ref - qdot)``
    to first order: the damping then acts on the velocity error, not on the velocity, and
    the servo does not lag (53 ms for the servos whose gains come from the inertia they
    move, 6 Hz critically damped; a few ms for the stiffer joints that carry the body)."""
    kp = -model.actuator_biasprm[:, 1]
    kv = -model.actuator_biasprm[:, 2]
    return np.where(kp > 0, kv / np.where(kp > 0, kp, 1.0), 0.0)


def _actuator_targets(model, qpos, substeps: int, lead_frames) -> np.ndarray:
    """Servo targets at every physics step, shape ((T-1) * substeps, nu) radians: the
    (unwrapped) hinge angles interpolated linearly, ``lead_frames`` (nu,) ahead of the
    end of the step (held at the last frame), wrapped to [-pi, pi)."""
    joints = model.actuator_trnid[:, 0]
    columns = model.jnt_qposadr[joints]
    angles = qpos[:, columns]
    n = qpos.shape[0]
    s = np.arange(1, (n - 1) * substeps + 1) / substeps
    s = np.minimum(s[:, None] + np.asarray(lead_frames)[None, :], n - 1)  # (S, nu)
    lo = np.minimum(np.floor(s).astype(int), n - 2)
    w = s - lo
    cols = np.arange(angles.shape[1])[None, :]
    targets = (1 - w) * angles[lo, cols] + w * angles[lo + 1, cols]
    return _wrap_rad(targets)


def _root_path(free_qpos, substeps: int) -> np.ndarray:
    """The free joint's qpos at the start of every physics step, shape
    ((T-1) * substeps, 7): positions interpolated linearly, quaternions by normalised
    linear interpolation on the same hemisphere."""
    n = free_qpos.shape[0]
    s = np.arange((n - 1) * substeps) / substeps
    i = np.floor(s).astype(int)
    w = (s - i)[:, None]
    a, b = free_qpos[i], free_qpos[i + 1]
    pos = (1 - w) * a[:, :3] + w * b[:, :3]
    qb = b[:, 3:] * np.where(np.sum(a[:, 3:] * b[:, 3:], axis=1) < 0, -1.0, 1.0)[:, None]
    quat = (1 - w) * a[:, 3:] + w * qb
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    return np.concatenate([pos, quat], axis=1)


def floor_depth(model, data, qpos) -> float:
    """Deepest penetration of any geom into the floor in state ``qpos``, metres."""
    from controller.contacts import collide

    collide(model, data, qpos)
    n = data.ncon
    if not n:
        return 0.0
    bodies = model.geom_bodyid[np.asarray(data.contact.geom[:n])]
    floor = (bodies[:, 0] == 0) | (bodies[:, 1] == 0)
    return max(0.0, float(-np.asarray(data.contact.dist[:n])[floor].min(initial=0.0)))


def _reference_heights(model, qpos, root_body: int, head_site: int):
    import mujoco

    data = mujoco.MjData(model)
    pelvis = np.empty(qpos.shape[0])
    head = np.empty(qpos.shape[0])
    for t in range(qpos.shape[0]):
        data.qpos[:] = qpos[t]
        mujoco.mj_kinematics(model, data)
        pelvis[t] = data.xpos[root_body, 2]
        head[t] = data.site_xpos[head_site, 2]
    return pelvis, head


def _fall_frame(pelvis, head, ref_pelvis, ref_head, figures) -> int | None:
    low_p = FALL_FRACTION * figures.pelvis_height_m
    low_h = FALL_FRACTION * figures.head_height_m
    with np.errstate(invalid="ignore"):
        fallen = (((pelvis < low_p) & (ref_pelvis >= low_p))
                  | ((head < low_h) & (ref_head >= low_h)))
    hits = np.flatnonzero(fallen)
    return int(hits[0]) if hits.size else None


def _rms(x) -> float | None:
    x = np.asarray(x)
    return _round(np.sqrt(np.mean(x ** 2))) if x.size else None


def _round(x, digits: int = 4) -> float:
    return round(float(x), digits)
