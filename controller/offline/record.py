"""The offline effort's result (:class:`OfflineResult`): what the body performed, replayed
from the search's chosen servo targets, with its figures."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from controller.config import DEFAULT, ControllerConfig
from controller.offline.samcon import SearchOutcome, search
from controller.tracking.result import Tracking


@dataclass(frozen=True)
class OfflineResult:
    """A motion as the free-root humanoid performed it in the offline effort.

    Attributes
    ----------
    qpos : ndarray, shape (T, nq)
        The performed state at every frame (the replay of :attr:`outcome`'s targets).
    fell : bool
    fall_time_s : float or None
    error_deg : ndarray, shape (T,)
        RMS over the hinges of the joint error against the reference, degrees.
    body_error_mm, root_drift_m, heading_error_deg : ndarray, shape (T,)
        The body's error relative to its pelvis and heading (mean over the bodies), the
        pelvis's horizontal drift and the heading's error, as the balance controller's
        (:func:`controller.pose_error.reference_errors`).
    saturation_share : float or None
        Share of the actuators at their force limit over the frames before any fall.
    samples : int
        Rollouts the search simulated (of one segment each).
    wall_s : float
        Wall-clock seconds of the search and the replay.
    tracking : controller.tracking.Tracking
        The replay as a free-root tracking run (``mode="free"``): what the reports read.
    outcome : controller.offline.samcon.SearchOutcome
    realtime : controller.balance.run.BalanceRun or None
        The real-time controller's run the search started from (the warm start's: the
        real-time effort on the same reference); None without a warm start.
    """

    qpos: np.ndarray
    fell: bool
    fall_time_s: float | None
    error_deg: np.ndarray
    body_error_mm: np.ndarray
    root_drift_m: np.ndarray
    heading_error_deg: np.ndarray
    saturation_share: float | None
    samples: int
    wall_s: float
    tracking: Tracking
    outcome: SearchOutcome
    realtime: object = None

    def __getattr__(self, name):
        # the rest of a tracking run's figures (fallen, limit_rows, ...): the replay's, so
        # that a report takes this result where it takes a Tracking
        if name in ("tracking", "__setstate__"):
            raise AttributeError(name)
        return getattr(self.tracking, name)

    @property
    def seconds(self) -> float:
        """Simulated seconds (the motion's length)."""
        return (self.qpos.shape[0] - 1) / self.tracking.fps

    def summary(self, part: slice | None = None) -> dict:
        """The tracking figures of ``part`` with the offline effort's own, JSON-ready."""
        share = self.tracking.saturation_share(part)
        index = np.arange(self.qpos.shape[0])[part if part is not None else slice(None)]
        up = index[~self.tracking.fallen[index] & np.isfinite(self.body_error_mm[index])]

        def stat(x, how):
            return round(float(how(x[up])), 4) if up.size else None

        return {**self.tracking.summary(part), "effort": "offline",
                "fall_time_s": self.fall_time_s if self.tracking.fall_frame in set(index)
                else None,
                "body_error_mm_mean": stat(self.body_error_mm, np.mean),
                "body_error_mm_peak": stat(self.body_error_mm, np.max),
                "root_drift_m": stat(self.root_drift_m, np.max),
                "heading_error_deg_peak": stat(np.abs(self.heading_error_deg), np.max),
                "torque_saturation_share": None if share is None else round(share, 5)}

    def run_summary(self) -> dict:
        """Whole-run figures, JSON-ready: the tracking's and the search's."""
        out = self.outcome
        return {**self.tracking.run_summary(), **self.summary(), "effort": "offline",
                "controller": "offline",
                "torque_saturation_share": (None if self.saturation_share is None
                                            else round(self.saturation_share, 5)),
                "search_rollouts": out.rollouts, "search_steps": out.steps,
                "search_passes": round(out.passes, 3), "search_backtracks": out.backtracks,
                "search_segments": out.segments,
                "searched_segments": out.searched_segments,
                "wall_s": round(self.wall_s, 3),
                "wall_s_per_sim_s": (round(self.wall_s / self.seconds, 3)
                                     if self.seconds > 0 else None),
                "realtime": self.realtime_summary()}

    def realtime_summary(self) -> dict | None:
        """The real-time controller's run the search started from (:attr:`realtime`), its
        whole-run figures, JSON-ready: ``fell``, ``fall_time_s``, ``ends_in_trouble``,
        ``error_deg_rms``, ``body_error_mm_mean``; None without a warm start."""
        from controller.balance.run import window_summary

        if self.realtime is None:
            return None
        figures = window_summary(self.realtime, 0, self.realtime.n_frames)

        def finite(key, digits):
            value = figures[key]
            return None if not np.isfinite(value) else round(float(value), digits)

        return {"fell": bool(self.realtime.fell),
                "fall_time_s": (None if not self.realtime.fell
                                else round(float(self.realtime.fall_time_s), 4)),
                "ends_in_trouble": (not self.realtime.fell
                                    and figures["ends_in_trouble"] == 1.0),
                "error_deg_rms": finite("joint_error_deg_rms", 4),
                "body_error_mm_mean": finite("body_error_mm_mean", 2)}


def perform(model, qpos_ref, fps: float, config: ControllerConfig = DEFAULT,
            progress: bool = False) -> OfflineResult:
    """The reference as the free-root humanoid performs it in the offline effort.

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid (not modified).
    qpos_ref : array_like, shape (T, nq), T >= 2
        The reference.
    fps : float
    config : controller.config.ControllerConfig
        Its ``offline`` section (the search), ``step`` and ``falls``.
    progress : bool
        A progress bar on a terminal.

    Returns
    -------
    OfflineResult
    """
    from dataclasses import replace

    from controller.pose_error import reference_errors
    from controller.tracking.plan import plan_tracking
    from controller.tracking.servo import track_plan

    clock = time.perf_counter()
    plan = plan_tracking(model, np.asarray(qpos_ref, dtype=float), fps, "free", True, config)
    warmed, realtime = False, None
    if config.offline.warm_start:
        from controller.offline.warm import warm_plan

        warm = warm_plan(model, plan, config)
        plan, warmed, realtime = warm.plan, warm.used_frames > 0, warm.realtime_run
    outcome = search(model, plan, config, progress, keep_plan_path=warmed)
    run = track_plan(model, replace(plan, ctrl=outcome.ctrl), config)
    wall = time.perf_counter() - clock
    _, body, drift, heading, _ = reference_errors(plan.model, run.qpos, plan.reference_qpos)
    return OfflineResult(qpos=run.qpos, fell=run.fell, fall_time_s=run.fall_time_s,
                         error_deg=run.error_deg, body_error_mm=body, root_drift_m=drift,
                         heading_error_deg=heading,
                         saturation_share=run.saturation_share(),
                         samples=outcome.rollouts, wall_s=wall, tracking=run,
                         outcome=outcome, realtime=realtime)
