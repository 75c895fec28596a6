"""A free-root character that keeps its balance while following a reference motion.

At every physics step the controller (:class:`controller.balance.control.BalanceControl`)
takes the reference at the step's time, moves the swing foot towards where the capture
offset says it should land, asks for the reference's accelerations plus a PD correction,
solves whole-body inverse dynamics with the floor contacts in friction pyramids and no
force on the root, and applies the joint torques through torque actuators: the root has
no actuator and ``xfrc_applied`` is never written. Before the run, :func:`follow` prepares
the reference (:func:`prepared_reference`): marker dropouts filled
(:mod:`controller.dropouts`: 16_15's left arm reads zero for its first 2 frames, then
jumps by 76 degrees), low-passed at 12 Hz (mocap glitches are not targets), re-anchored in
height so that its first frame's lowest point is 1 mm (``reference.start_depth_m``) into
the floor (mocap feet hover by centimetres), and every standing frame grounded
(:mod:`controller.grounding`).

Every 0.5 s (0.25 s after a choice whose rollout strays) the foot-placement gain is chosen
by rolling the same controller out 1 s ahead from a copy of the state (``mj_copyData``)
with each gain and keeping the one whose pelvis stays nearest the reference's height and
upright (:mod:`controller.balance.gain_selection`); the chosen gain's rollout is the run's next
frames, which are taken from it rather than simulated again, and with ``processes=2`` the
rollouts run side by side (:mod:`controller.balance.lookahead`: the same run either way). Where
the character still gets into trouble (pelvis or head well below the reference's, or
tilted), a backtracking search (:mod:`controller.balance.search`, after SAMCON) runs the
last segments again in other modes (:attr:`controller.config.ControllerConfig.modes`:
placement gain, swing clearance, which swing-foot contacts the plan leans on) from their
saved states. The controller's balance is thin (which walks it gets through changes with these
choices), and the search buys robustness where it is needed, at the cost of the segments
it runs again (``simulated_steps``).

The run is a :class:`controller.balance.run.BalanceRun`: the simulated state and figures
frame by frame, and the torques applied at every step, which
:func:`controller.balance.run.replay` runs open-loop from the same start to the same
motion. The controller has no randomness: the ``seed`` is recorded, and the same inputs
give the same run. Every tuning constant is a field of the
:class:`controller.config.ControllerConfig` the run is given (and records): the same
configuration and reference give the same run.

The character has **fallen** when its pelvis or head is below half its standing height
while the reference's is not, and more than a tenth of that height below the reference's
(:mod:`controller.falls`); the simulation then runs ``falls.after_fall_s`` (1 s) more and
stops (later frames are NaN).
"""

from __future__ import annotations

import contextlib
import time

import numpy as np

from controller.balance.control import BalanceControl, actuator_torque_range, torque_model
from controller.balance.gain_selection import GainSelector
from controller.balance.run import BalanceRun, FrameLog
from controller.balance.search import Search, up_axis_z
from controller.config import DEFAULT, ControllerConfig


def follow(model, reference_qpos, fps: float, *, config: ControllerConfig = DEFAULT,
           seed: int = 0, progress: bool = False, processes: int = 1) -> BalanceRun:
    """Simulate the free-root humanoid balancing while it follows a reference.

    Parameters
    ----------
    model : mujoco.MjModel
        A humanoid made by :mod:`humanoid_xml` (not modified).
    reference_qpos : array_like, shape (T, nq), T >= 2
        From :func:`controller.to_qpos`.
    fps : float
        Frames per second of the reference.
    config : controller.config.ControllerConfig
        Every tuning constant (the search's budget ``search.budget``, in multiples of the
        reference's physics steps: 0, no search); recorded in the run.
    seed : int
        Recorded; the controller is deterministic.
    progress : bool
        Show a progress bar (tqdm, off when not a terminal).
    processes : int
        1 or 2: the foot-placement gain's lookahead rollouts run one after the other, or
        side by side in this process and a forked helper (:mod:`controller.balance.lookahead`).
        The run is the same either way; 2 costs less wall time where 2 cores are free
        (not inside a pool that already keeps every core busy).

    Returns
    -------
    BalanceRun
    """
    import mujoco

    from controller.balance.lookahead import restore_frame
    from controller.balance.placement import FootPlacement
    from controller.balance.wbc import WholeBodyID
    from controller.body import body_figures
    from controller.falls import fallen, reference_heights
    from controller.mjwarnings import collected_warnings, fatal, warning_counts
    from controller.pose_error import reference_errors
    from controller.qpos import free_joint
    from controller.raw_clock import RawStepClock
    from controller.tracking.servo import physics_substeps
    from upm.core.progress import progress as progress_bar

    if processes not in (1, 2):
        raise ValueError(f"the balance controller runs on 1 or 2 processes, not {processes!r}")
    sim = torque_model(model)
    substeps = physics_substeps(fps, min(config.step.max_step_s, float(model.opt.timestep)))
    dt = 1.0 / (fps * substeps)
    sim.opt.timestep = dt
    data = mujoco.MjData(sim)
    ref, smooth, ref_qvel, ref_qacc = prepared_reference(sim, reference_qpos, fps, data,
                                                         config)
    n_frames = ref.shape[0]
    start = smooth[0].copy()
    start_qvel = ref_qvel[0].copy()
    data.qpos[:] = start
    data.qvel[:] = start_qvel
    mujoco.mj_forward(sim, data)

    torque_range_nm = actuator_torque_range(sim)
    joint_dofs = sim.jnt_dofadr[sim.actuator_trnid[:, 0]]
    solver = WholeBodyID(sim, joint_dofs, torque_range_nm, config)
    placement = FootPlacement(sim, ref, fps, config)
    control = BalanceControl(sim, smooth, ref_qvel, ref_qacc, substeps, solver, placement,
                             torque_range_nm, config)
    pelvis_body = int(sim.jnt_bodyid[free_joint(sim)])
    head_site = mujoco.mj_name2id(sim, mujoco.mjtObj.mjOBJ_SITE, "head_end")
    figures = body_figures(model)
    ref_pelvis, ref_head = reference_heights(sim, ref, pelvis_body, head_site)

    total = (n_frames - 1) * substeps
    ctrl = np.zeros((total, sim.nu))
    log = FrameLog(sim, n_frames, torque_range_nm, solver.at_bound[solver.hinge_row])
    log.start(data)
    fall = None
    stop_frame = n_frames
    diverged = None
    steps = 0
    reused = 0
    # The compiled kernels load from numba's cache on their first call (a fraction of a
    # second, once per process): a step from a scratch copy of the start loads them before
    # the clock starts and before the helper process is forked (it inherits them).
    scratch = mujoco.MjData(sim)
    mujoco.mj_copyData(scratch, sim, data)
    control.step(scratch, 0, config.modes[0])
    del scratch
    root_q = int(sim.jnt_qposadr[free_joint(sim)])
    search = Search(sim, n_frames, fps, substeps, (ref_pelvis, ref_head),
                    (pelvis_body, head_site), ref_up_z=up_axis_z(ref[:, root_q + 3:root_q + 7]),
                    config=config)
    selector = (GainSelector(control, ref_pelvis, pelvis_body, fps, n_frames, processes,
                             config)
                if len(config.gains) > 1 and config.placement.enabled else None)
    modes = config.modes

    bar = progress_bar(total=n_frames - 1, desc="balance", unit="frame",
                       disable=None if progress else True)
    clock = time.perf_counter()
    raw = RawStepClock(model, start, start_qvel)
    helper = contextlib.closing(selector) if selector else contextlib.nullcontext()
    with collected_warnings(), bar, helper:
        t = 1
        while t < n_frames:
            raw.tick()
            search.enter(data, t)
            mode = modes[search.mode(t)]
            gain = config.mode_gain(mode)
            recorded = None
            if selector is not None and search.mode(t) == 0:
                gain = selector.gain_at(data, t, gain)  # chosen by lookahead
                recorded = selector.recorded(t, gain)
            elif selector is not None:
                selector.forget()
            if recorded is not None:
                # a rollout ahead simulated this frame already, from the same state
                state, ctrl[(t - 1) * substeps:t * substeps], tau, userdata = recorded
                restore_frame(sim, data, state, ctrl[t * substeps - 1], userdata)
                steps += substeps
                reused += substeps - 1  # the frame's last step is taken again
            else:
                for k in range((t - 1) * substeps, t * substeps):
                    ctrl[k], tau = control.step(data, k, mode, gain)
                    steps += 1
            log.planned(t, tau)
            if t > bar.n:  # the furthest frame reached (the search goes back); tqdm
                bar.update(t - bar.n)  # redraws at most every 0.1 s
            failed = fatal(data) or not np.all(np.isfinite(data.qpos))
            if failed or search.in_trouble(data, t):
                back = search.retry(data, t, steps, failed=failed)
                if back is not None:
                    t, fall, stop_frame = back, None, n_frames
                    if selector is not None:
                        selector.went_back(back)
                    continue
                if failed:
                    diverged = stop_frame = t
                    break
            log.record(data, t, search.troubled(data, t))
            if fall is None and fallen(data.xpos[pelvis_body, 2], data.site_xpos[head_site, 2],
                                       ref_pelvis[t], ref_head[t], figures, config.falls):
                fall = t
                stop_frame = min(n_frames, t + 1 + int(round(config.falls.after_fall_s * fps)))
            if t + 1 >= stop_frame:
                break
            t += 1
    wall = time.perf_counter() - clock - raw.spent_s
    stop_frame = min(stop_frame, t + 1)
    log.stop(stop_frame)
    ctrl = ctrl[:(stop_frame - 1) * substeps]

    joint_err, body_err, drift, heading_err, com_err = reference_errors(sim, log.qpos, ref)
    return BalanceRun(
        fps=float(fps), timestep_s=dt, substeps=substeps, seed=int(seed),
        start_qpos=start, start_qvel=start_qvel, qpos=log.qpos, ctrl=ctrl,
        fell=fall is not None, fall_frame=fall,
        fall_time_s=None if fall is None else fall / float(fps), diverged_frame=diverged,
        joint_error_deg=joint_err, body_error_mm=body_err, root_drift_m=drift,
        heading_error_deg=heading_err, com_height_error_m=com_err,
        contact_force_n=log.contact_force_n, torque_nm=log.torque_nm,
        torque_saturated=log.torque_saturated, limit_rows=log.limit_rows,
        self_contacts=log.self_contacts, trouble=log.trouble, warnings=warning_counts(data),
        external_force_peak=log.external_force_peak, weight_n=figures.weight_n, wall_s=wall,
        sim_s=ctrl.shape[0] * dt, raw_step_s=raw.step_s(),
        segment_modes=search.modes(), retries=search.retries, simulated_steps=steps,
        lookahead_steps=selector.lookahead.steps if selector is not None else 0,
        reused_steps=reused, troubles=search.troubles(),
        actuator_names=tuple(mujoco.mj_id2name(sim, mujoco.mjtObj.mjOBJ_ACTUATOR, i)
                             for i in range(sim.nu)),
        torque_range_nm=torque_range_nm,
        actuator_velocity=log.actuator_velocity, config=config,
    )


def prepared_reference(sim, reference_qpos, fps: float, data,
                       config: ControllerConfig = DEFAULT):
    """The reference as the controller follows it.

    Marker dropouts filled (``dropouts``), hinges unwrapped, low-passed (the targets, at
    ``reference.lowpass_hz``), shifted in height so that the first frame's lowest point is
    ``reference.start_depth_m`` into the floor, and every standing frame grounded
    (:func:`controller.grounding.ground_reference`, ``grounding``; the feet down by
    ``placement``'s test).

    Parameters
    ----------
    sim : mujoco.MjModel
        The torque model (:func:`controller.balance.control.torque_model`).
    reference_qpos : array_like, shape (T, nq), T >= 2
    fps : float
    data : mujoco.MjData
        Scratch data of ``sim`` (its state is overwritten).
    config : controller.config.ControllerConfig

    Returns
    -------
    ref, smooth : ndarray, shape (T, nq)
        The reference (unsmoothed; errors are measured against it) and its low-passed
        version (the targets), both shifted and grounded.
    ref_qvel, ref_qacc : ndarray, shape (T, nv)
        The targets' velocities and accelerations (central differences).
    """
    from controller.balance.placement import FootPlacement
    from controller.checks.dynamics import finite_differences, lowpass_qpos, unwrap_hinges
    from controller.dropouts import fill_dropouts
    from controller.grounding import floor_clearance, ground_reference

    ref = unwrap_hinges(sim, fill_dropouts(sim, reference_qpos, config.dropouts)[0])
    if ref.shape[0] < 2:
        raise ValueError("following needs a reference of at least 2 frames")
    if not np.all(np.isfinite(ref)):
        raise ValueError("the reference has non-finite values")
    smooth = lowpass_qpos(sim, ref, fps, config.reference.lowpass_hz)
    # Start with the lowest point on the floor (mocap feet hover or sink by centimetres),
    # and re-anchor the reference's height by the same shift ...
    height_shift = -floor_clearance(sim, data, smooth[0]) - config.reference.start_depth_m
    ref[:, 2] += height_shift
    smooth[:, 2] += height_shift
    # ... and every standing frame on the floor
    down = FootPlacement(sim, ref, fps, config).ref_down
    smooth, ground_shift = ground_reference(sim, smooth, fps, down, config.grounding)
    ref[:, 2] += ground_shift
    ref_qvel, ref_qacc = finite_differences(sim, smooth, fps)
    return ref, smooth, ref_qvel, ref_qacc
