"""What a servo tracking simulation feeds MuJoCo, step by step: the physics step, the
servo targets of every step (the reference's hinge angles interpolated, taken ahead by
each servo's lead), the start state, and for the driven root its path."""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from controller.checks.dynamics import half_step_velocities
from controller.config import DEFAULT, ControllerConfig
from controller.qpos import wrap_rad

#: The tracking modes.
MODES = ("free", "driven")


def physics_substeps(fps: float, max_step_s: float = DEFAULT.step.max_step_s) -> int:
    """Physics steps per frame: the fewest whose step is no longer than ``max_step_s``."""
    return max(1, math.ceil(1.0 / (fps * max_step_s) - 1e-9))


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
        The reference, hinges unwrapped; ``"free"``: shifted in height so that its first
        frame's lowest point is ``reference.start_depth_m`` into the floor (the start).
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
                  lead: bool = True, config: ControllerConfig = DEFAULT) -> TrackingPlan:
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
    config : controller.config.ControllerConfig
        Its ``step.max_step_s``: the longest physics step.

    Returns
    -------
    TrackingPlan
    """
    import mujoco

    from controller.checks.dynamics import unwrap_hinges
    from controller.qpos import joint_layout

    if mode not in MODES:
        raise ValueError(f"unknown tracking mode {mode!r} (modes: {', '.join(MODES)})")
    ref = unwrap_hinges(model, reference_qpos)
    if ref.shape[0] < 2:
        raise ValueError("tracking needs at least 2 frames")
    layout = joint_layout(model)
    sim = copy.copy(model)
    substeps = physics_substeps(fps, min(config.step.max_step_s, float(model.opt.timestep)))
    sim.opt.timestep = 1.0 / (fps * substeps)
    free_q = slice(layout.free_qpos, layout.free_qpos + 7)
    free_v = slice(layout.free_dof, layout.free_dof + 6)
    half_vel = half_step_velocities(sim, ref, fps)  # (T-1, nv)
    ctrl = _actuator_targets(sim, ref, substeps, servo_lead_s(sim) * fps * float(lead))
    driven = mode == "driven"
    if not driven:
        # the first frame's lowest point on the floor (mocap feet hover or sink, a window
        # may begin in the air or on a box), the whole reference shifted with it, so that
        # the heights the falls and the search judge by are the ones the body can reach
        from controller.grounding import floor_clearance

        z = layout.free_qpos + 2
        ref = ref.copy()
        ref[:, z] -= floor_clearance(sim, mujoco.MjData(sim), ref[0]) \
            + config.reference.start_depth_m
    start = ref[0].copy()
    return TrackingPlan(
        model=sim, mode=mode, fps=float(fps), substeps=substeps, reference_qpos=ref,
        start_qpos=start, start_qvel=half_vel[0].copy(), ctrl=ctrl,
        root_qpos=_root_path(ref[:, free_q], substeps) if driven else None,
        root_qvel=np.repeat(half_vel[:, free_v], substeps, axis=0) if driven else None,
    )


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
    return wrap_rad(targets)


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
