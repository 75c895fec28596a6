"""A balance-controller run (:class:`controller.balance.run.BalanceRun`) in the validity
report's tracking section: the figures of :func:`controller.balance.run.window_summary` per
part, and the old tracking fields (``fell``, ``fall_time_s``, ``error_deg_rms``) kept
under their names."""

from __future__ import annotations

import math

import numpy as np

from controller.config import DEFAULT, ControllerConfig

#: The figures of a part of a balance run in the report (besides ``frames``).
PART_FIELDS = ("fell", "fall_time_s", "error_deg_rms", "body_error_mm_mean",
               "body_error_mm_peak", "root_drift_m", "heading_error_deg_peak",
               "com_height_error_m", "contact_force_peak_bw", "contact_force_mean_bw",
               "torque_peak_nm", "torque_mean_nm", "torque_saturation_share",
               "trouble_time_s", "ends_in_trouble", "wall_s_per_sim_s", "raw_steps_per_step")


class BalanceTracking:
    """The report's view of a balance run (the interface of
    :class:`controller.tracking.Tracking` that :mod:`controller.report` reads).

    Parameters
    ----------
    run : controller.balance.run.BalanceRun
    fall_rule : str
        The fall rule in words, for the report.
    """

    mode = "free"
    controller = "balance"

    def __init__(self, run, fall_rule: str = ""):
        self.run = run
        self.fall_rule = fall_rule

    @property
    def qpos(self) -> np.ndarray:
        return self.run.qpos

    @property
    def diverged_frame(self):
        return self.run.diverged_frame

    @property
    def warnings(self) -> dict:
        return self.run.warnings

    @property
    def error_deg(self) -> np.ndarray:
        return self.run.joint_error_deg

    @property
    def limit_rows(self) -> np.ndarray:
        return self.run.limit_rows

    @property
    def self_contacts(self) -> np.ndarray:
        return self.run.self_contacts

    @property
    def trouble(self) -> np.ndarray:
        return self.run.trouble

    @property
    def fallen(self) -> np.ndarray:
        out = np.zeros(self.run.n_frames, dtype=bool)
        if self.run.fall_frame is not None:
            out[self.run.fall_frame:] = True
        return out

    def summary(self, part: slice | None = None) -> dict:
        """Figures over the frames of ``part`` (all by default), JSON-ready."""
        from controller.balance.run import window_summary

        start, stop, _ = (part or slice(None)).indices(self.run.n_frames)
        if stop <= start:
            return {"frames": 0}
        w = window_summary(self.run, start, stop)
        run = self.run
        index = np.arange(start, stop)
        up = index[np.isfinite(run.qpos[index, 0])]
        if run.fall_frame is not None:
            up = up[up < run.fall_frame]
        contact = run.contact_force_n[up] / run.weight_n
        torque = np.abs(run.torque_nm[up])
        out = {
            "frames": int(stop - start),
            "fell": bool(w["fell"]),
            "fall_time_s": w["fall_time_s"],
            "error_deg_rms": w["joint_error_deg_rms"],
            "body_error_mm_mean": w["body_error_mm_mean"],
            "body_error_mm_peak": w["body_error_mm_peak"],
            "root_drift_m": w["root_drift_m"],
            "heading_error_deg_peak": w["heading_error_deg_peak"],
            "com_height_error_m": w["com_height_error_m"],
            "contact_force_peak_bw": w["contact_force_peak_bw"],
            "contact_force_mean_bw": float(np.mean(contact)) if up.size else math.nan,
            "torque_peak_nm": w["torque_peak_nm"],
            "torque_mean_nm": float(np.mean(torque)) if up.size else math.nan,
            "torque_saturation_share": w["torque_saturation_share"],
            "trouble_time_s": w["trouble_time_s"],
            "ends_in_trouble": (bool(w["ends_in_trouble"]) if math.isfinite(w["ends_in_trouble"])
                                else None),
            "wall_s_per_sim_s": w["wall_s_per_sim_s"],
            "raw_steps_per_step": run.raw_steps_per_step,
        }
        out.update(self._by_search(up))
        out = {k: (round(v, 5) if isinstance(v, float) and math.isfinite(v) else v)
               for k, v in out.items()}
        out["torque_by_actuator"] = self._by_actuator(up)
        return out

    def _by_search(self, up) -> dict:
        """The share of frames ``up`` run in a mode the search changed (not the default:
        :func:`controller.balance.search.frame_modes`), and the joint and body errors over
        the frames run in the default mode and over those the search changed (NaN where
        there are none): where a part's error comes from."""
        from controller.balance.run import finite_stat, root_mean
        from controller.balance.search import frame_modes

        run = self.run
        searched = frame_modes(run.segment_modes, run.n_frames, run.fps,
                               run.config.search.segment_s)[up] != 0
        joint, body = run.joint_error_deg[up], run.body_error_mm[up]
        out = {"search_mode_share": finite_stat(searched, np.mean)}
        for name, frames in (("default_mode", ~searched), ("search_modes", searched)):
            out[f"error_deg_rms_{name}"] = finite_stat(joint[frames] ** 2, root_mean)
            out[f"body_error_mm_mean_{name}"] = finite_stat(body[frames], np.mean)
        return out

    def _by_actuator(self, up) -> dict:
        """Each actuator's torque over frames ``up``: its peak and mean magnitude, its
        range (its strength either way), the share of the frames it was at either end,
        and of those the share at which the joint turned the way the torque pushed
        (``saturated_concentric_share``: positive work, concentric, the muscles across it
        shortening; None when never at either end or not recorded). JSON-ready; empty for
        a run without actuator names."""
        run = self.run
        if not run.actuator_names or not up.size:
            return {}
        torque = np.abs(run.torque_nm[up])
        peak, mean = torque.max(axis=0), torque.mean(axis=0)
        saturated = run.torque_saturated[up]
        share = saturated.mean(axis=0)
        concentric = [None] * len(run.actuator_names)
        if run.actuator_velocity is not None:
            positive = run.torque_nm[up] * run.actuator_velocity[up] > 0.0
            frames = saturated.sum(axis=0)
            shares = (positive & saturated).sum(axis=0) / np.maximum(frames, 1)
            concentric = [round(float(c), 5) if n else None
                          for c, n in zip(shares, frames, strict=True)]
        return {name: {"peak_nm": round(float(peak[i]), 3), "mean_nm": round(float(mean[i]), 3),
                       "range_nm": [round(float(x), 3) for x in run.torque_range_nm[i]],
                       "saturation_share": round(float(share[i]), 5),
                       "saturated_concentric_share": concentric[i]}
                for i, name in enumerate(run.actuator_names)}

    def run_summary(self) -> dict:
        """Whole-run figures, JSON-ready."""
        from controller.balance.search import trouble_rule

        run = self.run
        return {
            "mode": self.mode,
            "controller": self.controller,
            "timestep_s": run.timestep_s,
            "steps": run.steps,
            "seed": run.seed,
            "fall_frame": run.fall_frame,
            "fall_rule": self.fall_rule,
            "trouble_rule": trouble_rule(run.config.search),
            "diverged_frame": run.diverged_frame,
            "warnings": dict(run.warnings),
            "limit_active_frames": int((run.limit_rows > 0).sum()),
            "self_contact_frames": int((run.self_contacts > 0).sum()),
            "raw_step_s": run.raw_step_s,
            "search_retries": run.retries,
            "simulated_steps": run.simulated_steps,
            "lookahead_steps": run.lookahead_steps,
            "reused_steps": run.reused_steps,
            "segment_modes": run.segment_modes.tolist(),
            "search_troubles": [
                {"frame": r.frame, "time_s": round(r.time_s, 5), "cause": list(r.cause),
                 "retries": r.retries, "rerun_s": round(r.rerun_s, 5), "outcome": r.outcome,
                 "restarts_by_mode": list(r.restarts_by_mode),
                 "rerun_s_by_mode": [round(x, 5) for x in r.rerun_s_by_mode],
                 "last_mode": r.last_mode}
                for r in run.troubles],
            **self.summary(),
        }


def balance_tracking(model, reference_qpos, fps: float, *,
                     config: ControllerConfig = DEFAULT, seed: int = 0,
                     progress: bool = False, processes: int = 1) -> BalanceTracking:
    """Run :func:`controller.balance.follow` with ``config`` and wrap it for the report."""
    from controller.balance.follow import follow
    from controller.body import body_figures
    from controller.falls import fall_rule

    run = follow(model, reference_qpos, fps, config=config, seed=seed, progress=progress,
                 processes=processes)
    return BalanceTracking(run, fall_rule(body_figures(model), config.falls))
