"""A robustness row performed in the offline effort (:mod:`eval.robustness`): the sampling
search's run as the same figures, by the same names, as the real-time controller's."""

from __future__ import annotations

from controller.config import ControllerConfig


def offline_figures(model, qpos, fps: float, config: ControllerConfig, fields) -> dict:
    """One run of the offline effort (:func:`controller.offline.perform`) as a row's
    figures: those of ``fields`` (:data:`eval.robustness.RUN_FIELDS`) it has (the
    real-time search's retries, modes and raw steps are None), ``ends_in_trouble`` by the
    real-time search's test at the last frame before any fall
    (:func:`controller.offline.window.trouble_frames`), and the search's
    ``search_rollouts`` and ``search_backtracks``."""
    from controller.offline import perform
    from controller.offline.window import window_figures

    result = perform(model, qpos, fps, config)
    summary = result.run_summary()
    whole = window_figures(model, result, qpos, 0, result.tracking.n_frames, config)
    out = dict.fromkeys(fields)
    out.update(fell=summary["fell"], fall_time_s=summary["fall_time_s"],
               ends_in_trouble=whole["ends_in_trouble"] == 1.0,
               error_deg_rms=summary["error_deg_rms"],
               body_error_mm_mean=summary["body_error_mm_mean"],
               root_drift_m=summary["root_drift_m"],
               heading_error_deg_peak=summary["heading_error_deg_peak"],
               wall_s_per_sim_s=summary["wall_s_per_sim_s"],
               search_rollouts=summary["search_rollouts"],
               search_backtracks=summary["search_backtracks"],
               search_gave_up=[], search_by_mode=None, wall_s=round(result.wall_s, 3))
    return out
