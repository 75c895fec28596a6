"""What a run of the balance controller did (:func:`controller.balance.follow`), frame by
frame, and its figures over a window.

Per-frame figures (:class:`BalanceRun`):

- ``joint_error_deg``: RMS over the hinges of the simulated minus the reference angle,
  wrapped to [-180, 180);
- ``body_error_mm``: mean over the bodies (every joint centre: the proximal end of each
  bone, the distal end of its parent) of the distance between the simulated and the
  reference position, each taken relative to its own root (pelvis) position and turned
  about the vertical by its own root heading: pose error, without the root's drift or
  heading drift (tilt counts);
- ``root_drift_m``: horizontal distance between the simulated and the reference pelvis;
- ``heading_error_deg``: the simulated pelvis's heading (its x axis in the floor plane)
  minus the reference's, wrapped to [-180, 180): the turn that, over a walk, becomes the
  drift (the foot placement's capture offsets are compared in the world frame, so a
  heading error is steered back, slowly; see :mod:`controller.balance.placement`);
- ``com_height_error_m``: simulated minus reference centre-of-mass height;
- ``contact_force_n``: total normal force of the floor on the body;
- ``torque_nm``, ``torque_saturated``: applied torque per actuator at the frame's last
  step, and whether the controller asked for the joint's whole strength or more (the QP
  keeps its torques within the strength, so a bound it leans on is met to rounding:
  within ``solver.at_bound_share`` of the strength counts as at it, the share the QP's
  warm start also reads a bound from);
- ``actuator_velocity``: each actuator's joint velocity at the same step, rad/s: a
  torque that has the velocity's sign does positive work (the joint turns the way it is
  pushed: a muscle across it shortens, where a real one holds less than its isometric
  peak, the strength tables' figure), one against it negative work (the muscle
  lengthens, where it holds more).

The applied torques of every step are recorded (``BalanceRun.ctrl``): :func:`replay`
runs them open-loop from the same start and reproduces the run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controller.balance.control import torque_model
from controller.body import floor_normal_force
from controller.config import DEFAULT, ControllerConfig

WINDOW_KEYS = ("fell", "fall_time_s", "joint_error_deg_rms", "body_error_mm_mean",
               "body_error_mm_peak", "root_drift_m", "heading_error_deg_peak",
               "com_height_error_m", "torque_saturation_share", "contact_force_peak_bw",
               "torque_peak_nm", "trouble_time_s", "ends_in_trouble", "wall_s_per_sim_s")


@dataclass(frozen=True, eq=False)
class BalanceRun:
    """One free-root run of the balance controller.

    Attributes
    ----------
    fps : float
    timestep_s : float
        The physics step.
    substeps : int
        Physics steps per frame.
    seed : int
    start_qpos, start_qvel : ndarray, shape (nq,), (nv,)
        The first state.
    qpos : ndarray, shape (T, nq)
        The simulated state at each frame (NaN after the run stopped).
    ctrl : ndarray, shape (S, nu)
        The torque applied at every physics step (actuator order), N m.
    fell : bool
    fall_frame : int or None
    fall_time_s : float or None
        From the run's start.
    diverged_frame : int or None
        Frame at which the state became non-finite (the run stopped).
    joint_error_deg, body_error_mm, root_drift_m, heading_error_deg : ndarray, shape (T,)
    com_height_error_m, contact_force_n : ndarray, shape (T,)
    torque_nm : ndarray, shape (T, nu)
    torque_saturated : ndarray of bool, shape (T, nu)
    limit_rows, self_contacts : ndarray of int, shape (T,)
        Active joint-limit constraint rows and self-contacts at each frame.
    trouble : ndarray of bool, shape (T,)
        Frames the run went on from in trouble by the search's test
        (:func:`controller.balance.search.trouble_rule`): the search had spent its budget,
        had no mode left within reach, or was resting after running again the attempt
        that got furthest.
    warnings : dict of str to int
        MuJoCo's warning counters that are not zero.
    external_force_peak : float
        The largest ``|xfrc_applied|`` component seen at any frame (zero: nothing but
        the joints' torques, gravity and contacts moved the body).
    weight_n : float
        The body's weight.
    wall_s : float
        Wall-clock seconds of the stepping loop (from after the set-up, which includes
        loading the compiled kernels once per process; the raw bursts' time taken off).
    sim_s : float
        Simulated seconds.
    raw_step_s : float
        Wall seconds of one raw ``mj_step`` of the same model, timed in bursts while the
        run went on (:class:`controller.raw_clock.RawStepClock`).
    segment_modes : ndarray of int, shape (segments,)
        The index in ``config.modes`` each ``config.search.segment_s`` segment ran in.
    retries : int
        Segments run again by the search.
    simulated_steps : int
        Physics steps taken in all, the search's included (``steps`` of them are the
        run's own), counting those taken from a recorded rollout.
    lookahead_steps : int
        Physics steps the foot-placement gain's lookahead rollouts simulated (both
        processes).
    reused_steps : int
        Of ``simulated_steps``, those taken from a recorded rollout instead of simulated
        again (all but the last step of each frame taken: that one is taken again to
        restore the frame). The physics steps simulated in all are ``simulated_steps -
        reused_steps + lookahead_steps``.
    troubles : tuple of controller.balance.search.SearchTrouble
        Every trouble the search worked on, in the order it met them.
    actuator_names : tuple of str
        The actuators (the columns of ``torque_nm`` and ``torque_saturated``).
    torque_range_nm : ndarray, shape (nu, 2)
        Each actuator's strength: the least and the largest torque it can apply, N m (a
        joint is stronger one way than the other).
    actuator_velocity : ndarray, shape (T, nu)
        Each actuator's joint velocity at the step of ``torque_nm``, rad/s (0 at the
        first frame, NaN after the run stopped); None where not recorded.
    config : controller.config.ControllerConfig
        The tuning constants the run was made with.
    """

    fps: float
    timestep_s: float
    substeps: int
    seed: int
    start_qpos: np.ndarray
    start_qvel: np.ndarray
    qpos: np.ndarray
    ctrl: np.ndarray
    fell: bool
    fall_frame: int | None
    fall_time_s: float | None
    diverged_frame: int | None
    joint_error_deg: np.ndarray
    body_error_mm: np.ndarray
    root_drift_m: np.ndarray
    heading_error_deg: np.ndarray
    com_height_error_m: np.ndarray
    contact_force_n: np.ndarray
    torque_nm: np.ndarray
    torque_saturated: np.ndarray
    limit_rows: np.ndarray
    self_contacts: np.ndarray
    trouble: np.ndarray
    warnings: dict
    external_force_peak: float
    weight_n: float
    wall_s: float
    sim_s: float
    raw_step_s: float
    segment_modes: np.ndarray
    retries: int
    simulated_steps: int
    lookahead_steps: int = 0
    reused_steps: int = 0
    troubles: tuple = ()
    actuator_names: tuple = ()
    torque_range_nm: np.ndarray | None = None
    actuator_velocity: np.ndarray | None = None
    config: ControllerConfig = DEFAULT

    @property
    def steps(self) -> int:
        return self.ctrl.shape[0]

    @property
    def n_frames(self) -> int:
        return self.qpos.shape[0]

    @property
    def wall_s_per_sim_s(self) -> float:
        return self.wall_s / self.sim_s if self.sim_s > 0 else math.nan

    @property
    def raw_steps_per_step(self) -> float:
        """The controller's cost per physics step in raw ``mj_step`` equivalents."""
        return (self.wall_s / self.steps / self.raw_step_s
                if self.steps and self.raw_step_s > 0 else math.nan)


def replay(model, run: BalanceRun, every_step: bool = False) -> np.ndarray:
    """Run a :class:`BalanceRun`'s recorded torques open-loop from its start.

    Parameters
    ----------
    every_step : bool
        Return the state at the start of every physics step instead of every frame.

    Returns
    -------
    ndarray, shape (T, nq), or (S, nq) with ``every_step``
        The state at every frame (NaN where the run had stopped), or at the start of each
        of the run's ``S`` physics steps.
    """
    import mujoco

    sim = torque_model(model)
    sim.opt.timestep = run.timestep_s
    data = mujoco.MjData(sim)
    data.qpos[:] = run.start_qpos
    data.qvel[:] = run.start_qvel
    mujoco.mj_forward(sim, data)
    frames = np.full_like(run.qpos, np.nan)
    frames[0] = data.qpos
    steps = np.empty((run.steps, sim.nq)) if every_step else None
    for k in range(run.steps):
        if steps is not None:
            steps[k] = data.qpos
        mujoco.mj_step1(sim, data)
        data.ctrl[:] = run.ctrl[k]
        mujoco.mj_step2(sim, data)
        if (k + 1) % run.substeps == 0:
            frames[(k + 1) // run.substeps] = data.qpos
    return steps if every_step else frames


def finite_stat(values, how) -> float:
    """``how`` (a reduction of an array to a number) of the finite ``values``, as a float;
    NaN when none is finite."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    return float(how(values)) if values.size else math.nan


def root_mean(squares) -> float:
    """The square root of the mean of ``squares`` (RMS, given the squares)."""
    return np.sqrt(np.mean(squares))


def window_summary(run: BalanceRun, start_frame: int, stop_frame: int) -> dict[str, float]:
    """Figures of frames ``start_frame`` to ``stop_frame - 1`` of a run.

    Errors, drift and forces are over the frames of the window before the fall (NaN when
    there are none); ``fell`` is 1.0 when the character fell at or before the window's
    last frame. ``trouble_time_s`` is the time of those frames the character spent in
    trouble (:func:`controller.balance.search.trouble_rule`) and ``ends_in_trouble`` 1.0
    when the last of them is in trouble (it did not fall, but was going down where the
    window or the run ended).

    Returns
    -------
    dict of str to float
        The keys of :data:`WINDOW_KEYS`.
    """
    n = run.n_frames
    start, stop = max(0, int(start_frame)), min(n, int(stop_frame))
    if stop <= start:
        raise ValueError(f"empty window {start_frame}:{stop_frame} of a {n}-frame run")
    index = np.arange(start, stop)
    up = index[np.isfinite(run.qpos[index, 0])]
    if run.fall_frame is not None:
        up = up[up < run.fall_frame]
    fell = run.fall_frame is not None and run.fall_frame <= stop - 1

    return {
        "fell": 1.0 if fell else 0.0,
        "fall_time_s": run.fall_time_s if fell else math.nan,
        "joint_error_deg_rms": finite_stat(run.joint_error_deg[up] ** 2, root_mean),
        "body_error_mm_mean": finite_stat(run.body_error_mm[up], np.mean),
        "body_error_mm_peak": finite_stat(run.body_error_mm[up], np.max),
        "root_drift_m": finite_stat(run.root_drift_m[up], np.max),
        "heading_error_deg_peak": finite_stat(np.abs(run.heading_error_deg[up]), np.max),
        "com_height_error_m": finite_stat(np.abs(run.com_height_error_m[up]), np.mean),
        "torque_saturation_share": finite_stat(run.torque_saturated[up].ravel(), np.mean),
        "contact_force_peak_bw": finite_stat(run.contact_force_n[up] / run.weight_n, np.max),
        "torque_peak_nm": finite_stat(np.abs(run.torque_nm[up]).ravel(), np.max),
        "trouble_time_s": float(np.count_nonzero(run.trouble[up])) / run.fps,
        "ends_in_trouble": float(run.trouble[up[-1]]) if up.size else math.nan,
        "wall_s_per_sim_s": run.wall_s_per_sim_s,
    }



class FrameLog:
    """A run's per-frame figures as it goes, for :class:`BalanceRun` (a frame the search
    runs again is written over).

    Parameters
    ----------
    sim : mujoco.MjModel
        The torque model the run steps.
    n_frames : int
    torque_range_nm, at_bound_nm : ndarray, shape (nu, 2), (nu,)
        Each actuator's strength, and how near a torque counts as at it.
    """

    def __init__(self, sim, n_frames: int, torque_range_nm, at_bound_nm):
        import mujoco

        self.sim = sim
        self.low_nm, self.high_nm = np.asarray(torque_range_nm).T
        self.at_bound_nm = at_bound_nm
        self.qpos = np.full((n_frames, sim.nq), np.nan)
        self.contact_force_n = np.full(n_frames, np.nan)
        self.torque_nm = np.full((n_frames, sim.nu), np.nan)
        self.actuator_velocity = np.full((n_frames, sim.nu), np.nan)
        self.torque_saturated = np.zeros((n_frames, sim.nu), dtype=bool)
        self.limit_rows = np.zeros(n_frames, dtype=int)
        self.self_contacts = np.zeros(n_frames, dtype=int)
        self.trouble = np.zeros(n_frames, dtype=bool)
        self.external_force_peak = 0.0
        self._limit_type = int(mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT)

    def start(self, data) -> None:
        """Frame 0: the start state."""
        self.qpos[0] = data.qpos
        self.contact_force_n[0] = floor_normal_force(self.sim, data)
        self.torque_nm[0] = 0.0
        self.actuator_velocity[0] = 0.0

    def planned(self, t: int, tau_nm: np.ndarray) -> None:
        """The torques the QP planned at frame ``t``'s last step, (nu,)."""
        self.torque_saturated[t] = ((tau_nm <= self.low_nm + self.at_bound_nm)
                                    | (tau_nm >= self.high_nm - self.at_bound_nm))

    def record(self, data, t: int, troubled: bool) -> None:
        """The state after frame ``t``'s steps (``troubled``: by the search's test)."""
        sim = self.sim
        self.qpos[t] = data.qpos
        self.trouble[t] = troubled
        self.contact_force_n[t] = floor_normal_force(sim, data)
        self.torque_nm[t] = data.actuator_force
        # from the last step's forward pass, as actuator_force is
        self.actuator_velocity[t] = data.actuator_velocity
        self.external_force_peak = max(self.external_force_peak,
                                       float(np.abs(data.xfrc_applied).max()))
        self.limit_rows[t] = int(np.count_nonzero(data.efc_type[:data.nefc] == self._limit_type))
        if data.ncon:
            pairs = sim.geom_bodyid[np.asarray(data.contact.geom[:data.ncon])]
            self.self_contacts[t] = int(np.count_nonzero((pairs[:, 0] != 0) & (pairs[:, 1] != 0)))

    def stop(self, stop_frame: int) -> None:
        """The run stopped before frame ``stop_frame``: later frames are cleared."""
        self.qpos[stop_frame:] = np.nan
        self.contact_force_n[stop_frame:] = np.nan
        self.torque_nm[stop_frame:] = np.nan
        self.actuator_velocity[stop_frame:] = np.nan
        self.torque_saturated[stop_frame:] = False
        self.limit_rows[stop_frame:] = 0
        self.self_contacts[stop_frame:] = 0
        self.trouble[stop_frame:] = False
