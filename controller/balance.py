"""A free-root character that keeps its balance while following a reference motion.

At every physics step (``mj_step1``, control, ``mj_step2``) the controller

1. takes the reference at the step's time: marker dropouts filled
   (:mod:`controller.dropouts`: 16_15's left arm reads zero for its first 2 frames, then
   jumps by 76 degrees), then low-passed at 12 Hz (mocap glitches are not targets),
   re-anchored in height so that its first frame's lowest point is 1 mm into the floor
   (mocap feet hover by centimetres); hinges and root position interpolated linearly
   between frames, the root quaternion by normalised linear interpolation, velocities and
   accelerations from central differences (:func:`controller.dynamics.finite_differences`);
2. moves the swing foot (:mod:`controller.placement`): by the swing hip, towards where
   the capture offset says it should land, and, by hip and knee, no lower than the
   reference's swing ankle (a swing foot that scrapes the floor is lifted); turns a foot
   in the air by its ankle to the reference's tilt (:mod:`controller.foot_tilt`: the hip
   and knee changes would tilt the sole with them); lets a toe pressed on the floor lie
   flat (:meth:`_Control._flatten_toes`); then keeps every hinge
   target 2 degrees inside its joint's range (the limits' forces are not in the plan);
3. asks for ``qdd_des = qdd_ref + kp e + kd (qd_ref - qd)`` (clipped to
   :data:`MAX_ACCELERATION`) with ``e`` the difference between the target and the state
   (``mj_differentiatePos``): the hinges and the root's orientation and height stiffly, the
   root's horizontal position not at all, only its velocity (the character may drift from
   the reference's path: the drift is reported as ``root_drift_m`` rather than fought);
4. solves whole-body inverse dynamics with the step's floor contacts in friction pyramids,
   no force on the root and each joint's torque range (:class:`controller.wbc.WholeBodyID`);
5. applies the joint torques through torque actuators: the model is used with its position
   servos turned into torque motors of the same strength (:func:`torque_model`). The root
   has no actuator and ``xfrc_applied`` is never written.

Every :data:`SELECT_EVERY_S` the foot-placement gain is chosen among
:data:`SELECT_GAINS` by rolling the same controller out :data:`LOOKAHEAD_S` ahead from a
copy of the state (``mj_copyData``) and keeping the gain whose pelvis stays nearest the
reference's height and upright; the chosen gain's rollout is the run's next frames, which
are taken from it rather than simulated again, and with ``processes=2`` the rollouts run
side by side (:mod:`controller.lookahead`: the same run either way). Where the character
still gets into trouble (pelvis or head well below the reference's, or tilted), a
backtracking search (:class:`_Search`, after SAMCON) runs the last segments again in other
:data:`MODES` (placement gain, swing clearance, which swing-foot contacts the plan leans
on) from their saved states; with ``processes=2`` the helper simulates the attempt the
search would make next while this process runs the current one
(:mod:`controller.search_ahead`: the same run either way). The controller's balance is
thin (which walks it gets through changes with these choices), and the search buys
robustness where it is needed, at the cost of the segments it runs again
(``simulated_steps``).

The applied torques of every step are recorded (``BalanceRun.ctrl``): :func:`replay`
runs them open-loop from the same start and reproduces the run. The controller has no
randomness: the ``seed`` is recorded, and the same inputs give the same run.

Per-frame figures (``BalanceRun``):

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
  heading error is steered back, slowly; see :mod:`controller.placement`);
- ``com_height_error_m``: simulated minus reference centre-of-mass height;
- ``contact_force_n``: total normal force of the floor on the body;
- ``torque_nm``, ``torque_saturated``: applied torque per actuator at the frame's last
  step, and whether the controller asked for the joint's whole strength or more (the QP
  keeps its torques within the strength, so a bound it leans on is met to rounding:
  within :data:`controller.wbc.AT_BOUND` of the strength counts as at it, the share the
  QP's warm start also reads a bound from).

The character has **fallen** when its pelvis or head is below half its standing height
while the reference's is not (:mod:`controller.falls`); the simulation then
runs :data:`AFTER_FALL_S` more and stops (later frames are NaN).
"""

from __future__ import annotations

import contextlib
import copy
import math
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from controller.contacts import floor_contacts
from controller.foot_tilt import SwingFootTilt
from controller.kernels import (
    clip_targets,
    clip_torques,
    desired_acceleration,
    reference_at,
)

#: Seconds simulated after a fall before the run stops.
AFTER_FALL_S = 1.0
#: The start's lowest point is this far into the floor (a contact from the first step).
START_DEPTH_M = 0.001
#: Natural frequencies of the tracking (Hz) and damping ratio.
JOINT_HZ = 5.0
ROOT_ROTATION_HZ = 3.0
ROOT_HEIGHT_HZ = 2.0
ROOT_HORIZONTAL_DAMPING = 10.0
DAMPING_RATIO = 1.0
#: Largest desired acceleration, rad/s^2 or m/s^2: a glitch in the reference (16_15 jumps
#: by 30 degrees for 2 frames at its start) must not ask for more than the body can do.
MAX_ACCELERATION = 300.0
#: Targets are kept this far inside each hinge's range, degrees.
LIMIT_MARGIN_DEG = 2.0


class Mode(NamedTuple):
    """One way of running the controller (see :data:`MODES`)."""

    placement_gain: float
    swing_contacts_excluded: str
    swing_clearance_m: float


class SearchTrouble(NamedTuple):
    """One trouble the search worked on (:class:`_Search`): where the character first got
    into it, why, what the search spent on it, and how it ended.

    Attributes
    ----------
    frame : int
        The frame the first attempt got into trouble at.
    time_s : float
        Its time from the run's start.
    cause : tuple of str
        What the search's test found there (:func:`trouble_rule`): any of ``"pelvis
        low"``, ``"head low"``, ``"tilted"``, or ``"simulation failed"``.
    retries : int
        Segments the search ran again for it (the replay of its best attempt included).
    rerun_s : float
        Simulated seconds those retries ran again (from each restart to the frame the
        attempt before it got into trouble at).
    outcome : str
        ``"got past"`` (an attempt went on beyond the segment in trouble), ``"budget
        spent"`` or ``"no mode within reach"`` (the search gave up and the run went on
        from the attempt that got furthest).
    """

    frame: int
    time_s: float
    cause: tuple
    retries: int
    rerun_s: float
    outcome: str


#: The controller's modes, tried in this order where the default leads to trouble: the
#: foot-placement gain, which floor contacts of the foot the reference has in the air are
#: not planned as support ("none"; "swing toes": a swing toe that scrapes the floor is not
#: pinned to it; "foot": no contact of that foot), the swing ankle's clearance above the
#: reference's, metres (:mod:`controller.placement`). The first is the default. In every
#: mode a toe pressed on the floor lies flat (:meth:`_Control._flatten_toes`).
MODES = (Mode(0.3, "none", 0.0), Mode(0.3, "none", 0.04), Mode(0.6, "none", 0.02),
         Mode(0.3, "swing toes", 0.04), Mode(0.6, "swing toes", 0.04), Mode(0.3, "foot", 0.04))
#: Foot-placement gains chosen among by short rollouts for the default mode ...
SELECT_GAINS = (0.3, 0.6)
#: ... every this many seconds ...
SELECT_EVERY_S = 0.5
#: ... each rolled out this far ahead.
LOOKAHEAD_S = 1.0
#: The search: each segment of this many seconds runs in one mode ...
SEGMENT_S = 0.25
#: ... a segment in trouble (pelvis this far below the reference's, or its up axis this
#: far from vertical, or the head this far below the reference's: bent over at the waist
#: with the pelvis still up) is run again in the next mode, then its predecessors, up to
#: this many segments back (4 s: on 16_15 -> 16_15 the attempt that stands differs from
#: the one that falls in a segment 3.5 s before the trouble; 10 s made the same runs) ...
TROUBLE_DROP_M = 0.12
TROUBLE_UP = 0.8
TROUBLE_HEAD_DROP_M = 0.25
MAX_BACKTRACK = 16
#: ... and the segments after a changed one keep its mode for this long ...
STICKY_S = 2.0
#: ... within this many times the reference's physics steps in all (30, not 15: on issue
#: 10's rows every exact reference stands, the 02 walk sequence with `upm` windows too,
#: which falls at 15 with the budget spent; offset seeds 11-20, not looked at when 30 was
#: chosen, fall 11 times in 110 against 25, with the search before its sweep; only runs
#: that spend more than 15 cost more).
SEARCH_BUDGET = 30.0
#: A toe hinge that turns the toe's axis up or down slower than this (per radian, near a
#: vertical hinge) is not flattened.
MIN_TOE_PITCH_RATE = 0.2
#: Correct the swing foot's placement (:mod:`controller.placement`).
PLACEMENT = True
#: Keep a foot in the air at the reference's tilt (:mod:`controller.foot_tilt`).
SWING_FOOT_TILT = True

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
        Frames the run went on from in trouble by the search's test (:func:`trouble_rule`):
        the search had spent its budget, had no mode left within reach, or was resting
        after running again the attempt that got furthest.
    warnings : dict of str to int
        MuJoCo's warning counters that are not zero.
    external_force_peak : float
        The largest ``|xfrc_applied|`` component seen at any frame (zero: nothing but
        the joints' torques, gravity and contacts moved the body).
    weight_n : float
        The body's weight.
    wall_s : float
        Wall-clock seconds of the stepping loop (from after the set-up, which includes
        loading the compiled kernels once per process).
    sim_s : float
        Simulated seconds.
    raw_step_s : float
        Wall seconds of one raw ``mj_step`` of the same model, timed in the same run.
    segment_modes : ndarray of int, shape (segments,)
        The index in :data:`MODES` each :data:`SEGMENT_S` segment ran in.
    retries : int
        Segments run again by the search.
    simulated_steps : int
        Physics steps taken in all, the search's included (``steps`` of them are the
        run's own), counting those taken from a recorded rollout.
    lookahead_steps : int
        Physics steps the rollouts ahead simulated (both processes): the foot-placement
        gain's lookahead and, on two processes, the search's guessed next attempts
        (:mod:`controller.search_ahead`).
    reused_steps : int
        Of ``simulated_steps``, those taken from a recorded rollout instead of simulated
        again (all but the last step of each frame taken: that one is taken again to
        restore the frame). The physics steps simulated in all are ``simulated_steps -
        reused_steps + lookahead_steps``.
    troubles : tuple of SearchTrouble
        Every trouble the search worked on, in the order it met them.
    actuator_names : tuple of str
        The actuators (the columns of ``torque_nm`` and ``torque_saturated``).
    torque_range_nm : ndarray, shape (nu, 2)
        Each actuator's strength: the least and the largest torque it can apply, N m (a
        joint is stronger one way than the other).
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


def _torque_range(model) -> np.ndarray:
    """Each actuator's torque range, shape (nu, 2) (``forcerange``; unlimited: inf)."""
    limited = model.actuator_forcelimited.astype(bool)[:, None]
    return np.where(limited, model.actuator_forcerange, np.array([-np.inf, np.inf]))


def follow(model, reference_qpos, fps: float, *, seed: int = 0,
           progress: bool = False, search_budget: float | None = None,
           processes: int = 1) -> BalanceRun:
    """Simulate the free-root humanoid balancing while it follows a reference.

    Parameters
    ----------
    model : mujoco.MjModel
        A humanoid made by :mod:`humanoid_xml` (not modified).
    reference_qpos : array_like, shape (T, nq), T >= 2
        From :func:`controller.to_qpos`.
    fps : float
        Frames per second of the reference.
    seed : int
        Recorded; the controller is deterministic.
    progress : bool
        Show a progress bar (tqdm, off when not a terminal).
    search_budget : float, optional
        The search's budget in multiples of the reference's physics steps (default
        :data:`SEARCH_BUDGET`; 0: no search).
    processes : int
        1 or 2: the foot-placement gain's lookahead rollouts run one after the other, or
        side by side in this process and a forked helper (:mod:`controller.lookahead`),
        which also simulates the search's next attempt ahead while the search runs
        (:mod:`controller.search_ahead`). The run is the same either way; 2 costs less
        wall time where 2 cores are free (not inside a pool that already keeps every
        core busy).

    Returns
    -------
    BalanceRun
    """
    import mujoco

    from controller.body import body_figures
    from controller.dropouts import fill_dropouts
    from controller.dynamics import finite_differences, lowpass_qpos, unwrap_hinges
    from controller.falls import fallen, reference_heights
    from controller.grounding import floor_clearance, ground_reference
    from controller.lookahead import restore_frame
    from controller.mjwarnings import collected_warnings, fatal, warning_counts
    from controller.placement import FootPlacement
    from controller.pose_error import reference_errors
    from controller.qpos import free_joint, joint_layout
    from controller.search_ahead import SearchAhead
    from controller.tracking import MAX_STEP_S, physics_substeps
    from controller.wbc import WholeBodyID
    from upm.progress import progress as progress_bar

    ref = unwrap_hinges(model, fill_dropouts(model, reference_qpos)[0])
    n_frames = ref.shape[0]
    if n_frames < 2:
        raise ValueError("following needs a reference of at least 2 frames")
    if not np.all(np.isfinite(ref)):
        raise ValueError("the reference has non-finite values")
    sim = torque_model(model)
    substeps = physics_substeps(fps, min(MAX_STEP_S, float(model.opt.timestep)))
    dt = 1.0 / (fps * substeps)
    sim.opt.timestep = dt
    nu = sim.nu
    joint_dofs = sim.jnt_dofadr[sim.actuator_trnid[:, 0]]
    torque_range = _torque_range(sim)
    low_nm, high_nm = torque_range.T
    solver = WholeBodyID(sim, joint_dofs, torque_range)
    at_bound_nm = solver.at_bound[solver.hinge_row]  # per actuator

    layout = joint_layout(sim)
    margin = np.deg2rad(LIMIT_MARGIN_DEG)
    low, high = np.deg2rad(layout.range_deg.T)
    low, high = low + margin, high - margin
    # Targets come from the low-passed reference (mocap glitches are not targets).
    smooth = lowpass_qpos(sim, ref, fps)
    data = mujoco.MjData(sim)
    # Start with the lowest point on the floor (mocap feet hover or sink by centimetres),
    # and re-anchor the reference's height by the same shift.
    height_shift = -floor_clearance(sim, data, smooth[0]) - START_DEPTH_M
    ref[:, 2] += height_shift
    smooth[:, 2] += height_shift
    # and every standing frame on the floor (controller.grounding)
    down = FootPlacement(sim, ref, fps).ref_down
    smooth, ground_shift = ground_reference(sim, smooth, fps, down)
    ref[:, 2] += ground_shift
    ref_qvel, ref_qacc = finite_differences(sim, smooth, fps)
    start = smooth[0].copy()
    start_qvel = ref_qvel[0].copy()
    data.qpos[:] = start
    data.qvel[:] = start_qvel
    mujoco.mj_forward(sim, data)

    placement = FootPlacement(sim, ref, fps)
    control = _Control(sim, smooth, ref_qvel, ref_qacc, substeps, solver, placement,
                       (low, high), torque_range)
    pelvis_body = int(sim.jnt_bodyid[free_joint(sim)])
    head_site = mujoco.mj_name2id(sim, mujoco.mjtObj.mjOBJ_SITE, "head_end")
    figures = body_figures(model)
    ref_pelvis, ref_head = reference_heights(sim, ref, pelvis_body, head_site)

    total = (n_frames - 1) * substeps
    ctrl = np.zeros((total, nu))
    qpos = np.full((n_frames, sim.nq), np.nan)
    contact = np.full(n_frames, np.nan)
    torque = np.full((n_frames, nu), np.nan)
    saturated = np.zeros((n_frames, nu), dtype=bool)
    limit_rows = np.zeros(n_frames, dtype=int)
    self_contacts = np.zeros(n_frames, dtype=int)
    trouble = np.zeros(n_frames, dtype=bool)
    limit_type = int(mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT)
    qpos[0] = data.qpos
    contact[0] = _floor_normal_force(sim, data)
    torque[0] = 0.0
    fall = None
    stop_frame = n_frames
    diverged = None
    steps = 0
    reused = 0
    external = 0.0
    budget = SEARCH_BUDGET if search_budget is None else float(search_budget)
    if not (math.isfinite(budget) and budget >= 0):
        raise ValueError(f"the search budget must be a number >= 0, not {search_budget!r}")
    # The compiled kernels load from numba's cache on their first call (a fraction of a
    # second, once per process): a step from a scratch copy of the start loads them before
    # the clock starts and before the helper process is forked (it inherits them).
    scratch = mujoco.MjData(sim)
    mujoco.mj_copyData(scratch, sim, data)
    control.step(scratch, 0, MODES[0])
    del scratch
    search = _Search(sim, n_frames, fps, substeps, (ref_pelvis, ref_head),
                     (pelvis_body, head_site), budget)
    if processes not in (1, 2):
        raise ValueError(f"the balance controller runs on 1 or 2 processes, not {processes!r}")
    selector = (_GainSelector(control, ref_pelvis, pelvis_body, fps, n_frames, processes,
                              stop=search.troubled)
                if len(SELECT_GAINS) > 1 and PLACEMENT else None)
    ahead = (SearchAhead(selector.lookahead, sim, search.every, substeps, n_frames, MODES)
             if selector is not None and processes == 2 and budget > 0 else None)

    def restarted(back: int) -> None:
        if ahead is not None:
            segment = (back - 1) // search.every
            ahead.restarted(search, segment, search.mode(back), search.quiet_until == 0)

    selected = {}
    bar = progress_bar(total=n_frames - 1, desc="balance", unit="frame",
                       disable=None if progress else True)
    clock = time.perf_counter()
    helper = contextlib.closing(selector) if selector else contextlib.nullcontext()
    with collected_warnings(), bar, helper:
        t = 1
        while t < n_frames:
            if (search.enter(data, t) and ahead is not None and t > search.quiet_until
                    and search.mode(t) > 0):
                ahead.entered(search, t)
            mode = MODES[search.mode(t)]
            gain = mode.placement_gain
            recorded = None
            if selector is not None and search.mode(t) == 0:
                # the default mode's gain, chosen by lookahead (once per start frame)
                first = (t - 1) - (t - 1) % selector.every_frames
                if first not in selected:
                    selected[first] = selector.choose(data, first) if first == t - 1 else gain
                gain = selected[first]
                recorded = selector.recorded(t, gain)
            elif selector is not None:
                selector.forget()
            if recorded is None and ahead is not None:
                recorded = ahead.frame(t)
            if recorded is not None:
                # a rollout ahead simulated this frame already, from the same state
                state, ctrl[(t - 1) * substeps:t * substeps], tau, userdata = recorded
                restore_frame(sim, data, state, ctrl[t * substeps - 1], userdata)
                steps += substeps
                reused += substeps - 1  # the frame's last step is taken again
            else:
                for k in range((t - 1) * substeps, t * substeps):
                    applied, tau = control.step(data, k, mode, gain)
                    ctrl[k] = applied
                    steps += 1
            saturated[t] = (tau <= low_nm + at_bound_nm) | (tau >= high_nm - at_bound_nm)
            if t > bar.n:  # the furthest frame reached (the search goes back); tqdm
                bar.update(t - bar.n)  # redraws at most every 0.1 s
            if fatal(data) or not np.all(np.isfinite(data.qpos)):
                back = search.retry(data, t, steps, failed=True)
                if back is not None:
                    t, fall, stop_frame = back, None, n_frames
                    if selector is not None:
                        selector.forget()
                    restarted(back)
                    continue
                diverged = t
                stop_frame = t
                break
            if search.in_trouble(data, t):
                back = search.retry(data, t, steps)
                if back is not None:
                    t, fall, stop_frame = back, None, n_frames
                    for first in [f for f in selected if f >= back - 1]:
                        del selected[first]
                    if selector is not None:
                        selector.forget()
                    restarted(back)
                    continue
            qpos[t] = data.qpos
            trouble[t] = search.troubled(data, t)
            contact[t] = _floor_normal_force(sim, data)
            torque[t] = data.actuator_force
            external = max(external, float(np.abs(data.xfrc_applied).max()))
            limit_rows[t] = int(np.count_nonzero(data.efc_type[:data.nefc] == limit_type))
            if data.ncon:
                pairs = sim.geom_bodyid[np.asarray(data.contact.geom[:data.ncon])]
                self_contacts[t] = int(np.count_nonzero((pairs[:, 0] != 0) & (pairs[:, 1] != 0)))
            if fall is None:
                if fallen(data.xpos[pelvis_body, 2], data.site_xpos[head_site, 2],
                          ref_pelvis[t], ref_head[t], figures):
                    fall = t
                    stop_frame = min(n_frames, t + 1 + int(round(AFTER_FALL_S * fps)))
            if t + 1 >= stop_frame:
                break
            t += 1
    stop_frame = min(stop_frame, t + 1)
    qpos[stop_frame:] = np.nan
    contact[stop_frame:] = np.nan
    torque[stop_frame:] = np.nan
    ctrl_steps = (stop_frame - 1) * substeps
    wall = time.perf_counter() - clock
    ctrl = ctrl[:ctrl_steps]
    saturated[stop_frame:] = False
    limit_rows[stop_frame:] = 0
    self_contacts[stop_frame:] = 0
    trouble[stop_frame:] = False

    joint_err, body_err, drift, heading_err, com_err = reference_errors(sim, qpos, ref)
    return BalanceRun(
        fps=float(fps), timestep_s=dt, substeps=substeps, seed=int(seed),
        start_qpos=start, start_qvel=start_qvel, qpos=qpos, ctrl=ctrl,
        fell=fall is not None, fall_frame=fall,
        fall_time_s=None if fall is None else fall / float(fps), diverged_frame=diverged,
        joint_error_deg=joint_err, body_error_mm=body_err, root_drift_m=drift,
        heading_error_deg=heading_err,
        com_height_error_m=com_err, contact_force_n=contact, torque_nm=torque,
        torque_saturated=saturated, limit_rows=limit_rows, self_contacts=self_contacts,
        trouble=trouble, warnings=warning_counts(data),
        external_force_peak=external, weight_n=figures.weight_n, wall_s=wall,
        sim_s=ctrl_steps * dt, raw_step_s=raw_step_seconds(model, start, start_qvel),
        segment_modes=search.modes(), retries=search.retries, simulated_steps=steps,
        lookahead_steps=selector.lookahead.steps if selector is not None else 0,
        reused_steps=reused, troubles=search.troubles(),
        actuator_names=tuple(mujoco.mj_id2name(sim, mujoco.mjtObj.mjOBJ_ACTUATOR, i)
                             for i in range(nu)),
        torque_range_nm=torque_range,
    )


class _Control:
    """One physics step of the controller: targets, foot placement, QP, torques."""

    def __init__(self, sim, smooth, ref_qvel, ref_qacc, substeps, solver, placement,
                 target_range, torque_range):
        import mujoco

        from controller.qpos import joint_layout

        self.sim, self.smooth = sim, smooth
        self._mj_step1, self._mj_step2 = mujoco.mj_step1, mujoco.mj_step2
        self._mj_differentiatePos = mujoco.mj_differentiatePos
        self.ref_qvel, self.ref_qacc = ref_qvel, ref_qacc
        self.substeps, self.solver, self.placement = substeps, solver, placement
        self.n_frames = smooth.shape[0]
        self.kp, self.kd = _gains(sim.nv)
        layout = joint_layout(sim)
        self.hinge_q, self.hinge_v = layout.qpos_address, layout.dof_address
        self.low, self.high = target_range
        self.low_nm, self.high_nm = (np.ascontiguousarray(a) for a in np.asarray(torque_range).T)
        self.q_ref = np.empty(sim.nq)
        self.qd_ref = np.empty(sim.nv)
        self.qdd_ref = np.empty(sim.nv)
        self.qdd_des = np.empty(sim.nv)
        self.err = np.zeros(sim.nv)
        self.foot_tilt = (SwingFootTilt(sim, smooth, placement.ankle) if SWING_FOOT_TILT
                          else None)
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
        """The bodies whose floor contacts the plan does not lean on (see :data:`MODES`)."""
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
        if PLACEMENT:
            gain = mode.placement_gain if gain is None else gain
            self.placement.adjust(data, frame, q_ref, gain, mode.swing_clearance_m,
                                  floor_bodies)
        if self.foot_tilt is not None:
            self.foot_tilt.adjust(data, frame, q_ref, self.placement.touching(floor_bodies))
        self._flatten_toes(data, q_ref, floor_bodies)
        # targets inside the joint ranges: the limits' forces are not in the plan
        clip_targets(q_ref, qd_ref, qdd_ref, self.hinge_q, self.hinge_v, self.low, self.high)
        self._mj_differentiatePos(sim, self.err, 1.0, data.qpos, q_ref)
        desired_acceleration(qdd_ref, self.kp, self.err, self.kd, qd_ref, data.qvel,
                             MAX_ACCELERATION, self.qdd_des)
        tau = self.solver.torques(
            data, self.qdd_des, exclude=self._excluded(mode.swing_contacts_excluded, frame),
            floor=floor)
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
            if abs(rate) >= MIN_TOE_PITCH_RATE:
                q_ref[qadr] = data.qpos[qadr] - dz / rate


class _GainSelector:
    """Every :data:`SELECT_EVERY_S`, the foot-placement gain of :data:`SELECT_GAINS` whose
    :data:`LOOKAHEAD_S` rollout (the same controller, from a copy of the state) keeps the
    pelvis nearest the reference's height and upright, and the pace nearest the
    reference's (:func:`controller.lookahead.rollout_cost`); the first on ties. The rollouts
    run on ``processes`` processes (:class:`controller.lookahead.Lookahead`)."""

    def __init__(self, control, ref_pelvis, pelvis_body: int, fps: float, n_frames: int,
                 processes: int = 1, stop=None):
        """``stop``: where a rollout run ahead for the search ends
        (:meth:`controller.lookahead.Lookahead.send`)."""
        from controller.lookahead import Lookahead, Recording

        self.n_frames = n_frames
        self.every_frames = max(1, int(round(SELECT_EVERY_S * fps)))
        self.lookahead_frames = max(1, int(round(LOOKAHEAD_S * fps)))
        self.lookahead = Lookahead(control, ref_pelvis, pelvis_body, processes, stop)
        # on one process the chosen rollout is recorded whole: the next choice goes on
        # from its second half instead of simulating it again
        self.resumes = processes == 1
        capacity = (self.lookahead_frames if self.resumes
                    else min(self.every_frames, self.lookahead_frames))
        self.recordings = [Recording(control.sim, capacity, control.substeps)
                           for _ in SELECT_GAINS]
        self.chain = None
        self.last_choice = 0
        self.last_cost = math.inf

    def choose(self, data, frame: int) -> float:
        """The gain from frame ``frame`` on (``data``: the state after it). Every gain's
        rollout is recorded for :meth:`recorded` (on two processes, the one expected to
        win, the gain chosen last time, runs in this process)."""
        last = min(self.n_frames - 1, frame + self.lookahead_frames)
        resume = self._resumable(frame)
        self.forget(keep=resume)
        costs = self.lookahead.costs(data, frame, last, SELECT_GAINS, MODES[0],
                                     self.recordings, here=self.last_choice, resume=resume)
        self.chain = frame
        best, best_cost = 0, math.inf
        for i, cost in enumerate(costs):
            if cost < best_cost:
                best, best_cost = i, cost
        self.last_choice, self.last_cost = best, best_cost
        return SELECT_GAINS[best]

    def _resumable(self, frame: int) -> int | None:
        """The last choice's gain, if its rollout can go on from ``frame`` (one process,
        the run took every frame up to ``frame`` from it, and it recorded every frame it
        simulated, finite): its recording is moved on to start after ``frame``."""
        if not self.resumes or self.chain != frame:
            return None
        recording = self.recordings[self.last_choice]
        start = recording.start_frame
        ended = min(self.n_frames - 1, start + self.lookahead_frames)
        if (start < 0 or recording.gain != SELECT_GAINS[self.last_choice] or ended <= frame
                or recording.frames != ended - start or not math.isfinite(self.last_cost)):
            return None
        recording.advance(frame - start)
        return self.last_choice

    def recorded(self, t: int, gain: float):
        """Frame ``t`` as the last choice's rollout simulated it, if the run is still on
        that rollout (every frame since the choice taken from it, with its gain in the
        default mode): :meth:`controller.lookahead.Recording.frame`'s tuple, for
        :func:`controller.lookahead.restore_frame`, else None."""
        if self.chain != t - 1:
            self.chain = None
            return None
        out = None
        for recording in self.recordings:
            out = out or recording.frame(t, gain)
        self.chain = t if out is not None else None
        return out

    def forget(self, keep: int | None = None) -> None:
        """The run went back: nothing recorded is its future any more (but gain
        ``keep``'s recording, which goes on)."""
        for i, recording in enumerate(self.recordings):
            if i != keep:
                recording.clear()
        self.chain = None

    def close(self) -> None:
        self.lookahead.close()


class _Search:
    """Backtracking over the controller's :data:`MODES`, segment by segment.

    The run is cut into segments of :data:`SEGMENT_S`; each runs in one mode, the first
    by default. When the character gets into trouble (pelvis :data:`TROUBLE_DROP_M`
    below the reference's, or its up axis tilted below :data:`TROUBLE_UP`, or the head
    :data:`TROUBLE_HEAD_DROP_M` below the reference's, or the simulation fails), the
    segment is run again from its saved start state in the next mode; the segments after
    a changed one keep its mode for :data:`STICKY_S`. The search first *sweeps* back: for
    one trouble (until an attempt gets into trouble further on) it changes one segment at a
    time, each in its next modes, then the one before it (up to :data:`MAX_BACKTRACK`
    back), the later ones back on the modes they had before; a sweep that finds nothing
    goes back to the choices before it and tries the combinations, nearest first: when a
    segment has no modes left, the one before it, and the segments after it start again
    (the search before the sweep, which spent most of its budget re-running the nearest
    segments' combinations: over seeds 0-20 of issue 10's rows the sweep made 12 falls of
    231 against 25, 5 against 11 on seeds 11-20, not looked at when it was chosen, with
    60 % fewer segments run again). When the search has spent :data:`SEARCH_BUDGET` times the
    reference's physics steps, or has tried every mode within reach, the attempt that got
    furthest is run again and the run goes on from it (a fall is a fall). SAMCON (Liu et
    al. 2010) searches the same way, with sampled target offsets instead of a few discrete
    modes.
    """

    def __init__(self, sim, n_frames: int, fps: float, substeps: int, ref_heights_m,
                 watched: tuple[int, int], budget: float = SEARCH_BUDGET):
        """``ref_heights_m``: the reference's pelvis and head heights, (T,) each;
        ``watched``: the pelvis body and the head site."""
        self.sim, self.n_frames = sim, n_frames
        self.every = max(1, int(round(SEGMENT_S * fps)))
        self.sticky = int(round(STICKY_S / SEGMENT_S))
        self.ref_pelvis, self.ref_head = ref_heights_m
        self.pelvis_body, self.head_site = watched
        self.budget_steps = budget * (n_frames - 1) * substeps
        self.choice: dict[int, int] = {}
        self.saved: dict[int, object] = {}
        self.quiet_until = 0
        self.retries = 0
        self.restart = 1
        self.best: tuple[int, dict] | None = None
        self.trouble: _Trouble | None = None
        self.fps = float(fps)
        self._records: list[dict] = []  # SearchTrouble's fields, the last one open

    def _segment(self, t: int) -> int:
        return (t - 1) // self.every

    def enter(self, data, t: int) -> bool:
        """Save the state at the start of a segment (before frame ``t``'s steps); returns
        whether it was saved now (a segment entered for the first time since the run was
        last restarted before it)."""
        import mujoco

        if (t - 1) % self.every == 0:
            i = self._segment(t)
            if i not in self.saved:
                copy_ = mujoco.MjData(self.sim)
                mujoco.mj_copyData(copy_, self.sim, data)
                self.saved[i] = copy_
                return True
        return False

    def _mode_of(self, i: int, choice: dict | None = None) -> int:
        """Segment ``i``'s mode: its own choice, else that of the latest segment before
        it with one, within :data:`STICKY_S`, else the default."""
        choice = self.choice if choice is None else choice
        for j in range(i, max(-1, i - self.sticky - 1), -1):
            if j in choice:
                return choice[j]
        return 0

    def mode(self, t: int) -> int:
        """The index in :data:`MODES` of frame ``t``'s segment."""
        return self._mode_of(self._segment(t))

    def modes(self) -> np.ndarray:
        """The mode of every segment, int array (segments,)."""
        n = self._segment(self.n_frames - 1) + 1
        return np.array([self._mode_of(i) for i in range(n)], dtype=int)

    def in_trouble(self, data, t: int) -> bool:
        """Whether the search acts on trouble at frame ``t`` (it is not resting)."""
        return t > self.quiet_until and self.troubled(data, t)

    def troubled(self, data, t: int) -> bool:
        """Whether the character is in trouble at frame ``t`` (quiet or not)."""
        return bool(self.causes(data, t))

    def causes(self, data, t: int) -> tuple:
        """What puts the character in trouble at frame ``t``: any of ``"pelvis low"``,
        ``"head low"``, ``"tilted"`` (empty: not in trouble)."""
        low = self.ref_pelvis[t] - data.xpos[self.pelvis_body, 2] > TROUBLE_DROP_M
        bent = self.ref_head[t] - data.site_xpos[self.head_site, 2] > TROUBLE_HEAD_DROP_M
        tilted = data.xmat[self.pelvis_body, 8] < TROUBLE_UP
        return tuple(name for name, on in (("pelvis low", low), ("head low", bent),
                                           ("tilted", tilted)) if on)

    def troubles(self) -> tuple:
        """Every trouble the search worked on, :class:`SearchTrouble` each (the last one
        got past if the search did not give up on it)."""
        return tuple(SearchTrouble(**{"outcome": "got past", **r}) for r in self._records)

    def retry(self, data, t: int, steps: int, failed: bool = False) -> int | None:
        """Restore the state for the next attempt; returns the frame to run from, or
        None (go on as it is). ``failed``: the simulation failed at frame ``t``.

        When the budget is spent or no mode is left within reach, the attempt that got
        furthest before its trouble is run again, if it is not this one, and the search
        rests until past that point.
        """
        if self.best is None or t > self.best[0]:
            self.best = (t, dict(self.choice))
        spent = steps >= self.budget_steps
        i = self._segment(t)
        if self.trouble is None or i > self.trouble.segment:  # a new trouble
            if self._records and "outcome" not in self._records[-1]:
                self._records[-1]["outcome"] = "got past"
            cause = ("simulation failed",) if failed else self.causes(data, t)
            self._records.append(dict(frame=int(t), time_s=t / self.fps, cause=cause,
                                      retries=0, rerun_s=0.0))
            if not spent:
                self.trouble = _Trouble(i, i, dict(self.choice))
        back = self._back(t)
        if not spent and back is None and self.trouble is not None and self.trouble.sweeping:
            # the sweep found nothing: the choices before it again, then the combinations
            self.trouble.sweeping = False
            before = self.trouble.choice_before
            differ = [j for j in range(i + 1) if self._mode_of(j) != self._mode_of(j, before)]
            if differ and differ[0] in self.saved:
                return self._restart(data, differ[0], before, t)
            back = self._back(t)
        if spent or back is None:
            return self._give_up(data, t, spent)
        if self.trouble is not None:
            self.trouble.changed = back
        choice = dict(self.choice)
        choice[back] = self._mode_of(back) + 1
        return self._restart(data, back, {j: m for j, m in choice.items() if j <= back}, t)

    def _back(self, t: int) -> int | None:
        """The segment a retry at frame ``t`` goes back to (in its next mode), or None
        (no mode left within reach)."""
        i = self._segment(t)
        back = i
        if self.trouble is not None and self.trouble.sweeping and i <= self.trouble.segment:
            back = min(i, self.trouble.changed)  # sweeping: nothing after the last changed
        while back >= 0 and i - back <= MAX_BACKTRACK:
            if self._mode_of(back) + 1 < len(MODES):
                break
            back -= 1
        if back < 0 or i - back > MAX_BACKTRACK or back not in self.saved:
            return None
        return back

    def next_attempt(self, t: int):
        """The attempt a retry at frame ``t`` would start, if the budget is not spent by
        then: ``(segment, its mode, its saved start state)``, or None."""
        back = self._back(t)
        if back is None:
            return None
        return back, self._mode_of(back) + 1, self.saved[back]

    def _give_up(self, data, t: int, spent: bool) -> int | None:
        best_t, best_choice = self.best
        self.best = None
        self.trouble = None
        self._records[-1]["outcome"] = "budget spent" if spent else "no mode within reach"
        self.quiet_until = self.n_frames if spent else max(t, best_t) + self.every
        if best_t <= t:
            return None
        differ = [j for j in range(self._segment(best_t) + 1)
                  if self._mode_of(j) != self._mode_of(j, best_choice)]
        first = differ[0] if differ else self._segment(t)
        if first not in self.saved:
            return None
        return self._restart(data, first, best_choice, t, quiet=self.quiet_until)

    def _restart(self, data, segment: int, choice: dict, t: int, quiet: int = 0) -> int:
        """Run again from ``segment``'s saved start with ``choice``, the attempt before
        having got to frame ``t``; returns the frame to run from."""
        import mujoco

        record = self._records[-1]
        record["retries"] += 1
        record["rerun_s"] += (t - segment * self.every) / self.fps
        self.choice = choice
        for j in [j for j in self.saved if j > segment]:
            del self.saved[j]
        mujoco.mj_copyData(data, self.sim, self.saved[segment])
        self.quiet_until = quiet
        self.retries += 1
        self.restart = segment * self.every + 1
        return self.restart


@dataclass(eq=False)
class _Trouble:
    """The trouble the search is working on: the furthest segment an attempt got into
    trouble in, the latest segment changed for it, the choices (segment to mode) before,
    and whether the search is still sweeping back (:class:`_Search`)."""

    segment: int
    changed: int
    choice_before: dict
    sweeping: bool = True


def replay(model, run: BalanceRun) -> np.ndarray:
    """Run a :class:`BalanceRun`'s recorded torques open-loop from its start.

    Returns
    -------
    ndarray, shape (T, nq)
        The state at every frame (NaN where the run had stopped).
    """
    import mujoco

    sim = torque_model(model)
    sim.opt.timestep = run.timestep_s
    data = mujoco.MjData(sim)
    data.qpos[:] = run.start_qpos
    data.qvel[:] = run.start_qvel
    mujoco.mj_forward(sim, data)
    out = np.full_like(run.qpos, np.nan)
    out[0] = data.qpos
    for k in range(run.steps):
        mujoco.mj_step1(sim, data)
        data.ctrl[:] = run.ctrl[k]
        mujoco.mj_step2(sim, data)
        if (k + 1) % run.substeps == 0:
            out[(k + 1) // run.substeps] = data.qpos
    return out


def raw_step_seconds(model, qpos, qvel, steps: int = 300) -> float:
    """Wall seconds of one plain ``mj_step`` of the model from a state (servos holding
    the state's pose), the unit of the controller's cost."""
    import mujoco

    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    data.qvel[:] = qvel
    data.ctrl[:] = qpos[model.jnt_qposadr[model.actuator_trnid[:, 0]]]
    clock = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    return (time.perf_counter() - clock) / steps


def window_summary(run: BalanceRun, start_frame: int, stop_frame: int) -> dict[str, float]:
    """Figures of frames ``start_frame`` to ``stop_frame - 1`` of a run.

    Errors, drift and forces are over the frames of the window before the fall (NaN when
    there are none); ``fell`` is 1.0 when the character fell at or before the window's
    last frame. ``trouble_time_s`` is the time of those frames the character spent in
    trouble (:func:`trouble_rule`) and ``ends_in_trouble`` 1.0 when the last of them is
    in trouble (it did not fall, but was going down where the window or the run ended).

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

    def stat(values, how):
        values = np.asarray(values, dtype=float)
        values = values[np.isfinite(values)]
        return float(how(values)) if values.size else math.nan

    return {
        "fell": 1.0 if fell else 0.0,
        "fall_time_s": run.fall_time_s if fell else math.nan,
        "joint_error_deg_rms": stat(run.joint_error_deg[up] ** 2,
                                    lambda v: np.sqrt(np.mean(v))),
        "body_error_mm_mean": stat(run.body_error_mm[up], np.mean),
        "body_error_mm_peak": stat(run.body_error_mm[up], np.max),
        "root_drift_m": stat(run.root_drift_m[up], np.max),
        "heading_error_deg_peak": stat(np.abs(run.heading_error_deg[up]), np.max),
        "com_height_error_m": stat(np.abs(run.com_height_error_m[up]), np.mean),
        "torque_saturation_share": stat(run.torque_saturated[up].ravel(), np.mean),
        "contact_force_peak_bw": stat(run.contact_force_n[up] / run.weight_n, np.max),
        "torque_peak_nm": stat(np.abs(run.torque_nm[up]).ravel(), np.max),
        "trouble_time_s": float(np.count_nonzero(run.trouble[up])) / run.fps,
        "ends_in_trouble": float(run.trouble[up[-1]]) if up.size else math.nan,
        "wall_s_per_sim_s": run.wall_s_per_sim_s,
    }


def trouble_rule() -> str:
    """The search's test for trouble (:meth:`_Search.troubled`) in words."""
    tilt_deg = math.degrees(math.acos(TROUBLE_UP))
    return (f"in trouble: the pelvis more than {100 * TROUBLE_DROP_M:.0f} cm below the "
            f"reference's, or the head more than {100 * TROUBLE_HEAD_DROP_M:.0f} cm below "
            f"the reference's, or the pelvis's up axis more than {tilt_deg:.0f} deg from "
            "vertical")


def _gains(nv: int):
    def pd(hz):
        w = 2 * math.pi * hz
        return w * w, 2 * DAMPING_RATIO * w

    kp = np.empty(nv)
    kd = np.empty(nv)
    kp[6:], kd[6:] = pd(JOINT_HZ)
    kp[3:6], kd[3:6] = pd(ROOT_ROTATION_HZ)
    kp[2], kd[2] = pd(ROOT_HEIGHT_HZ)
    kp[:2], kd[:2] = 0.0, ROOT_HORIZONTAL_DAMPING
    return kp, kd


def _floor_normal_force(model, data) -> float:
    """Total normal force of the floor on the body, N."""
    import mujoco

    total = 0.0
    force = np.zeros(6)
    geom_body = model.geom_bodyid
    for i in range(data.ncon):
        g = data.contact.geom[i]
        if (geom_body[g[0]] == 0) != (geom_body[g[1]] == 0):
            mujoco.mj_contactForce(model, data, i, force)
            total += force[0]
    return total
