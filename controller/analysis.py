"""Every physical check of one motion in one call: the kinematic checks per frame, the
inverse-dynamics residual, and the tracking simulations, assembled into a report
(:mod:`controller.report`). ``upm check`` and ``upm simulate`` are thin layers on this.
Every tuning constant comes from the :class:`controller.config.ControllerConfig` given
(the residual check's ``residual``, the simulations' and the window runs'
``window_runs``), and the report's settings record it whole (``controller_config``)."""

from __future__ import annotations

from pathlib import Path

from controller.config import DEFAULT, ControllerConfig

#: Free-root controllers: the balance controller, or the position servos alone.
CONTROLLERS = ("balance", "servo")
#: Efforts of the free-root runs: the real-time controller (``controller``), or the offline
#: search over the servos' targets (:mod:`controller.offline`).
EFFORTS = ("realtime", "offline")


def settings(tracking_modes=(), controller: str = "balance", processes: int = 1,
             strength: float = 1.0, config: ControllerConfig = DEFAULT,
             effort: str = "realtime") -> dict:
    """The thresholds and methods of the checks, JSON-ready (units in the names), and
    the whole configuration (``controller_config``: :meth:`ControllerConfig.as_dict`, which
    :meth:`ControllerConfig.from_dict` reads back). ``strength``: the multiple of the
    strength tables' torque limits the model was loaded with
    (:func:`humanoid_xml.models.load_model`)."""
    from controller.checks import tissue
    from upm.motion.limits import LIMIT_TOLERANCE_DEG

    out = {
        "limit_tolerance_deg": LIMIT_TOLERANCE_DEG,
        "limits": "human",
        "self_touch_mm": 1000 * tissue.TOUCH_M,
        "self_allowance_mm": {k: round(1000 * v, 1) for k, v in tissue.SELF_ALLOWANCE_M.items()},
        "floor_allowance_mm": {k: round(1000 * v, 1)
                               for k, v in tissue.FLOOR_ALLOWANCE_M.items()},
        "strength": strength,
        "dynamics": {
            "lowpass_hz": config.residual.lowpass_hz,
            "support_distance_m": config.residual.support_distance_m,
            "friction": config.residual.friction,
            "force_unit": "body weight",
            "torque_unit": "body weight x stature (torque about the root)",
        },
    }
    if tracking_modes:
        out["tracking"] = {
            "modes": list(tracking_modes),
            "max_step_s": config.step.max_step_s,
            "fall_fraction": config.falls.fraction,
            "servo_targets": "reference hinge angles, linearly interpolated, taken kv/kp "
                             "ahead (a velocity reference for the damping)",
            "driven_root": "free joint qpos/qvel set from the reference before every step",
            "free_controller": controller,
            "free_controller_method": (
                "reference with marker dropouts filled and standing frames on the "
                "floor; whole-body inverse-dynamics QP per physics step (floor contacts "
                "in friction pyramids, no root force, joint strength limits), torque "
                "actuators, swing-foot placement with its gain chosen by 1 s rollouts "
                "every 0.5 s (0.25 s where they stray), a backtracking search over "
                "controller modes where the character gets into trouble; "
                "controller.balance.follow"
                if controller == "balance" else "position servos alone (open loop)"),
            "body_error": "mean distance of the joint centres from the reference's, each "
                          "relative to its pelvis and heading (drift reported apart)",
            "search_budget": config.search.budget if controller == "balance" else None,
            "processes": processes if controller == "balance" else None,
            "window_free_lead_s": config.window_runs.lead_s,
            "window_free_tail_s": config.window_runs.tail_s,
            "effort": effort,
        }
        if effort == "offline":
            out["tracking"]["free_controller"] = "offline"
            out["tracking"]["free_controller_method"] = (
                "position servos, their targets corrected by a sampling search over "
                "segments (SAMCON-style: the best states kept, backtracking where all are "
                "in trouble), no root force; controller.offline")
            out["tracking"]["search_budget"] = config.offline.budget
            out["tracking"]["processes"] = None
    out["controller_config"] = config.as_dict()
    return out


def motion_description(model, motion, model_path=None) -> dict:
    """Name, frames, rate and body figures of a motion on its model, JSON-ready."""
    from controller.body import body_figures

    figures = body_figures(model)
    source = motion.skeleton.source.replace("\\", "/").rsplit("/", 1)[-1]
    return {
        "name": motion.name,
        "frames": motion.n_frames,
        "fps": motion.fps,
        "seconds": round(motion.duration_s, 4),
        "skeleton": source,
        "model": Path(model_path).name if model_path is not None else None,
        "mass_kg": round(figures.mass_kg, 3),
        "weight_n": round(figures.weight_n, 3),
        "stature_m": round(figures.stature_m, 4),
    }


def free_run(model, qpos, fps: float, controller: str = "balance", progress: bool = False,
             processes: int = 1, config: ControllerConfig = DEFAULT,
             effort: str = "realtime"):
    """A free-root simulation of a reference ``qpos`` (T, nq) by ``controller`` with
    ``config``: a :class:`controller.balance.report.BalanceTracking` or a
    :class:`controller.tracking.Tracking`. ``processes``: the balance controller's (1 or
    2, see :func:`controller.balance.follow`). ``effort="offline"``: the offline search
    instead (:func:`controller.offline.perform`, a
    :class:`controller.offline.OfflineResult`; ``controller`` unused)."""
    from controller.balance.report import balance_tracking
    from controller.tracking.servo import track_qpos

    if effort not in EFFORTS:
        raise ValueError(f"unknown effort {effort!r} (efforts: {', '.join(EFFORTS)})")
    if effort == "offline":
        from controller.offline import perform

        return perform(model, qpos, fps, config, progress)

    if controller not in CONTROLLERS:
        raise ValueError(f"unknown controller {controller!r} (controllers: "
                         f"{', '.join(CONTROLLERS)})")
    if controller == "balance":
        return balance_tracking(model, qpos, fps, config=config, progress=progress,
                                processes=processes)
    return track_qpos(model, qpos, fps, "free", config=config)


def window_free_runs(model, motion, windows, controller: str = "balance",
                     progress: bool = False, processes: int = 1,
                     config: ControllerConfig = DEFAULT, effort: str = "realtime"
                     ) -> list[dict]:
    """Per window, a free-root simulation from the reference state
    ``config.window_runs.lead_s`` before the window to ``tail_s`` after it: does the
    character get through it standing?

    Returns
    -------
    list of dict
        ``{"free_window": {"start", "stop", "fell", "fall_frame" (of the whole motion),
        "fall_in_window", "error_deg_rms" (window frames, before any fall), ...}}``.
    """
    from controller.qpos import to_qpos
    from upm.core.progress import progress as progress_bar

    qpos = to_qpos(model, motion)
    n = motion.n_frames
    lead_s, tail_s = config.window_runs.lead_s, config.window_runs.tail_s
    out = []
    for window in progress_bar(windows, desc="window runs", unit="window",
                               disable=None if progress else True):
        w0, w1, _ = window.indices(n)
        a = max(0, w0 - round(lead_s * motion.fps))
        b = min(n, w1 + round(tail_s * motion.fps))
        run = free_run(model, qpos[a:b], motion.fps, controller, processes=processes,
                       config=config, effort=effort)
        inside = slice(w0 - a, w1 - a)
        balance = controller == "balance" and effort == "realtime"
        fall_frame = run.run.fall_frame if balance else run.fall_frame
        fall = None if fall_frame is None else a + fall_frame
        summary = run.summary(inside)
        entry = {
            "start": a, "stop": b, "fell": fall is not None,
            "controller": controller if effort == "realtime" else "offline",
            "fall_frame": fall, "fall_in_window": fall is not None and fall < w1,
            "diverged_frame": None if run.diverged_frame is None else a + run.diverged_frame,
            "warnings": run.warnings,
        }
        entry.update({k: v for k, v in summary.items() if k not in ("frames", "fell")})
        out.append({"free_window": entry})
    return out


def analyse(model, motion, *, kind: str = "check", windows=(), window_meta=None, limits=None,
            pieces=None, dynamics: bool = True, tracking_modes=(), window_free: bool = False,
            model_path=None, controller: str = "balance", progress: bool = False,
            processes: int = 1, strength: float = 1.0, config: ControllerConfig = DEFAULT,
            effort: str = "realtime"):
    """Run the checks on a motion and build its report.

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid of the motion's skeleton.
    motion : upm.Motion
    kind : str
        The report's kind (``"check"``, ``"simulate"``).
    windows : sequence of slice
        Transition windows within the motion.
    window_meta : list of dict, optional
        Extra fields per window for the report.
    pieces : list of (str, slice), optional
    dynamics : bool
        Compute the inverse-dynamics residual.
    tracking_modes : sequence of str
        Tracking simulations of the whole motion (``"free"``, ``"driven"``).
    window_free : bool
        Also a free-root run around each window (:func:`window_free_runs`).
    model_path : path-like, optional
        For the report's description.
    controller : str
        The free-root controller (:data:`CONTROLLERS`): ``"balance"`` or ``"servo"``.
    progress : bool
        Progress bars for the simulations.
    processes : int
        The balance controller's processes, 1 or 2 (``controller.balance.follow``: the
        same runs, less wall time on 2 free cores).
    strength : float
        For the report: the multiple of the strength tables' torque limits ``model`` was
        loaded with (:func:`humanoid_xml.models.load_model`).
    config : controller.config.ControllerConfig
        The tuning constants of the residual check and the simulations (recorded in the
        report's settings as ``controller_config``).
    effort : str
        The free-root runs' effort (:data:`EFFORTS`): ``"realtime"`` (``controller``) or
        ``"offline"`` (:mod:`controller.offline`); recorded as the report's ``effort``.

    Returns
    -------
    report : dict
    results : dict
        ``validity``, ``residual`` (or None) and ``tracking`` (mode -> Tracking), for
        callers that want the arrays.
    """
    from controller.checks.dynamics import root_residual
    from controller.checks.validity import check_motion
    from controller.qpos import to_qpos
    from controller.report import build_report
    from controller.tracking.servo import track

    windows = tuple(windows)
    validity = check_motion(model, motion, windows, limits=limits)
    check = config.residual
    residual = (root_residual(model, to_qpos(model, motion), motion.fps,
                              check.support_distance_m, check.friction, check.lowpass_hz)
                if dynamics else None)
    tracking = {mode: (free_run(model, to_qpos(model, motion), motion.fps, controller,
                                progress, processes, config, effort)
                       if mode == "free" else track(model, motion, mode, config=config))
                for mode in tracking_modes}
    per_window = (window_free_runs(model, motion, windows, controller=controller,
                                   progress=progress, processes=processes, config=config,
                                   effort=effort)
                  if window_free and windows else None)
    report = build_report(kind, validity, motion=motion_description(model, motion, model_path),
                          settings=settings(tuple(tracking_modes), controller, processes,
                                            strength, config, effort),
                          residual=residual,
                          tracking=tracking, window_meta=window_meta,
                          window_tracking=per_window, pieces=pieces)
    report["effort"] = effort
    return report, {"validity": validity, "residual": residual, "tracking": tracking}
