"""A window's figures of an offline-effort run (:class:`controller.offline.OfflineResult`),
the same figures, by the same names, as the real-time controller's
(:func:`controller.balance.run.window_summary`), so that the study's free-root test reads
either effort alike."""

from __future__ import annotations

import math

import numpy as np

from controller.config import DEFAULT, ControllerConfig


def trouble_frames(model, result, reference_qpos,
                   config: ControllerConfig = DEFAULT) -> np.ndarray:
    """Frames at which the performed body is in trouble by the real-time search's test
    (:func:`controller.balance.search.trouble_rule`: the pelvis or the head well below the
    reference's, or the pelvis tilted well beyond the reference's tilt).

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid the run was made on.
    result : controller.offline.OfflineResult
    reference_qpos : ndarray, shape (T, nq)
        The reference the run followed.
    config : controller.config.ControllerConfig
        Its ``search`` section (the thresholds).

    Returns
    -------
    ndarray of bool, shape (T,)
        False where the run has no state (after a divergence).
    """
    from controller.balance.search import in_trouble
    from controller.qpos import joint_layout

    run = result.tracking
    quat = slice(joint_layout(model).free_qpos + 3, joint_layout(model).free_qpos + 7)
    ref = np.asarray(reference_qpos, dtype=float)
    trouble = in_trouble(run.pelvis_height_m, run.head_height_m,
                         np.nan_to_num(result.qpos[:, quat], nan=1.0),
                         run.reference_pelvis_height_m, run.reference_head_height_m,
                         ref[:, quat], config.search)
    return trouble & np.isfinite(result.qpos[:, 0])


def _stat(values, how) -> float:
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    return float(how(values)) if values.size else math.nan


def window_figures(model, result, reference_qpos, start_frame: int, stop_frame: int,
                   config: ControllerConfig = DEFAULT) -> dict[str, float]:
    """Figures of frames ``start_frame`` to ``stop_frame - 1`` of an offline-effort run.

    Errors, drift, saturation and forces are over the window's frames before the fall
    (NaN when there are none); ``fell`` is 1.0 when the body fell at or before the
    window's last frame; ``ends_in_trouble`` 1.0 when the last of those frames is in
    trouble (:func:`trouble_frames`).

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid the run was made on (its weight).
    result : controller.offline.OfflineResult
    reference_qpos : ndarray, shape (T, nq)
    start_frame, stop_frame : int
    config : controller.config.ControllerConfig

    Returns
    -------
    dict of str to float
        ``fell``, ``fall_time_s``, ``joint_error_deg_rms``, ``body_error_mm_mean``,
        ``body_error_mm_peak``, ``root_drift_m``, ``heading_error_deg_peak``,
        ``torque_saturation_share``, ``contact_force_peak_bw``, ``trouble_time_s``,
        ``ends_in_trouble``.
    """
    from controller.body import body_figures

    run = result.tracking
    n = run.n_frames
    start, stop = max(0, int(start_frame)), min(n, int(stop_frame))
    if stop <= start:
        raise ValueError(f"empty window {start_frame}:{stop_frame} of a {n}-frame run")
    index = np.arange(start, stop)
    up = index[np.isfinite(result.qpos[index, 0])]
    if run.fall_frame is not None:
        up = up[up < run.fall_frame]
    fell = run.fall_frame is not None and run.fall_frame <= stop - 1
    trouble = trouble_frames(model, result, reference_qpos, config)
    weight_n = body_figures(model).weight_n
    floor = (run.floor_force_n if run.floor_force_n is not None
             else np.full(n, np.nan))
    saturated = (run.saturated_actuators if run.saturated_actuators is not None
                 else np.full(n, np.nan))
    return {
        "fell": 1.0 if fell else 0.0,
        "fall_time_s": run.fall_time_s if fell else math.nan,
        "joint_error_deg_rms": math.sqrt(_stat(result.error_deg[up] ** 2, np.mean)),
        "body_error_mm_mean": _stat(result.body_error_mm[up], np.mean),
        "body_error_mm_peak": _stat(result.body_error_mm[up], np.max),
        "root_drift_m": _stat(result.root_drift_m[up], np.max),
        "heading_error_deg_peak": _stat(np.abs(result.heading_error_deg[up]), np.max),
        "torque_saturation_share": _stat(saturated[up], np.mean),
        "contact_force_peak_bw": _stat(floor[up] / weight_n, np.max),
        "trouble_time_s": float(np.count_nonzero(trouble[up])) / run.fps,
        "ends_in_trouble": float(trouble[up[-1]]) if up.size else math.nan,
    }
