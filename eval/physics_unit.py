"""The figures of the study's free-root test (:mod:`eval.physics`), and one run of it: the
free-root body follows a unit's motion in either effort, and the figures of its window by
the names of :data:`PHYSICS_METRICS`."""

from __future__ import annotations

import math
from dataclasses import dataclass

from controller.config import DEFAULT, ControllerConfig


@dataclass(frozen=True)
class PhysicsMetric:
    """One figure of the free-root test.

    Attributes
    ----------
    name, unit, label : str
    better : str
        ``"lower"`` (every figure here: fewer falls, smaller errors).
    description : str
    """

    name: str
    unit: str
    label: str
    description: str
    better: str = "lower"


_METRICS = (
    PhysicsMetric("fell", "share", "falls %",
                  "1 if the character fell during the run (before, in or after the window)"),
    PhysicsMetric("ends_in_trouble", "share", "ends going down %",
                  "1 if the character did not fall but was in trouble at the run's last "
                  "frame (controller.balance.search.trouble_rule: pelvis or head well below the "
                  "motion's, or the pelvis tilted well beyond the motion's): going down where the "
                  "run ends"),
    PhysicsMetric("fell_or_going_down", "share", "falls or going down %",
                  "1 if the character fell or ended going down: the run did not end with "
                  "the character up and out of trouble"),
    PhysicsMetric("fall_after_window_start_s", "s", "fall time s",
                  "when it fell, seconds after the window's first frame (negative: "
                  "before the window); NaN if it did not"),
    PhysicsMetric("joint_error_deg_rms", "deg", "joint error °",
                  "RMS over the window's frames before any fall of the hinges' error"),
    PhysicsMetric("body_error_mm_mean", "mm", "body error mm",
                  "mean joint-centre position error relative to the pelvis, heading "
                  "removed (controller.balance.follow)"),
    PhysicsMetric("body_error_mm_peak", "mm", "body error peak mm",
                  "peak of the same over the window"),
    PhysicsMetric("root_drift_m", "m", "root drift m",
                  "largest horizontal pelvis distance from the motion's, since the run's start"),
    PhysicsMetric("heading_error_deg_peak", "deg", "heading error peak °",
                  "largest difference of the pelvis's heading from the motion's over the "
                  "window's frames before any fall (the turn the drift comes from)"),
    PhysicsMetric("torque_saturation_share", "share", "torque saturated %",
                  "share of joint x frame samples where the controller asked for more "
                  "than the joint's strength"),
    PhysicsMetric("contact_force_peak_bw", "bw", "floor force peak bw",
                  "peak total normal floor force, body weights"),
    PhysicsMetric("realtime_fell", "share", "real time: falls %",
                  "fell, for the real-time balance controller on the same motion: in the "
                  "offline effort the run its search started from (the warm start; NaN "
                  "without one), in the real-time effort the run itself"),
    PhysicsMetric("realtime_fell_or_going_down", "share", "real time: falls or going down %",
                  "fell_or_going_down, for the real-time balance controller on the same "
                  "motion (as realtime_fell)"),
    PhysicsMetric("realtime_joint_error_deg_rms", "deg", "real time: joint error °",
                  "joint_error_deg_rms, for the real-time balance controller on the same "
                  "motion (as realtime_fell)"),
)
#: The free-root figures, by name: the one registry every writer reads.
PHYSICS_METRICS = {m.name: m for m in _METRICS}
#: Shares shown as percentages in the tables.
PERCENT = frozenset({"fell", "ends_in_trouble", "fell_or_going_down",
                     "torque_saturation_share", "realtime_fell",
                     "realtime_fell_or_going_down"})


#: The free-root body's efforts (:data:`controller.analysis.EFFORTS`): the real-time
#: balance controller, or the offline effort's sampling search.
EFFORTS = ("realtime", "offline")
#: The study's free-root test's effort unless told (issue 61: the physics column asks
#: whether a body can perform the window at all, not whether one real-time controller
#: happens to carry it; the real-time controller's figures come from the same runs).
DEFAULT_EFFORT = "offline"
#: The figures of the whole run, not taken from the window's summary as they are.
_RUN_FIGURES = ("fell", "ends_in_trouble", "fell_or_going_down", "fall_after_window_start_s")


#: The real-time controller's figures reported in either effort, by the name they take.
REALTIME_FIGURES = {"realtime_fell": "fell",
                    "realtime_fell_or_going_down": "fell_or_going_down",
                    "realtime_joint_error_deg_rms": "joint_error_deg_rms"}


def _figures(summary: dict, whole_run, fall_frame, start: int, fps: float) -> dict:
    """A run's figures by the names of :data:`PHYSICS_METRICS` (the real-time ones
    aside): ``summary`` those of its window, ``whole_run()`` those of the whole run."""
    fell = fall_frame is not None
    going_down = 0.0 if fell else whole_run()["ends_in_trouble"]
    return {
        "fell": 1.0 if fell else 0.0,
        "ends_in_trouble": going_down,
        "fell_or_going_down": 1.0 if fell or going_down == 1.0 else 0.0,
        "fall_after_window_start_s": (fall_frame - start) / fps if fell else math.nan,
        **{name: summary[name] for name in PHYSICS_METRICS
           if name not in _RUN_FIGURES and name not in REALTIME_FIGURES},
    }


def _realtime_figures(run, start: int, stop: int, fps: float) -> dict:
    """The figures of a real-time controller's run (:class:`controller.balance.run.BalanceRun`)."""
    from controller.balance.run import window_summary

    return _figures(window_summary(run, start, stop),
                    lambda: window_summary(run, 0, run.n_frames), run.fall_frame, start, fps)


def simulate_unit(model, motion, start: int, stop: int,
                  config: ControllerConfig = DEFAULT,
                  effort: str = "realtime") -> dict[str, float]:
    """Run the free-root body over ``motion`` with ``config`` and the figures of its
    window: the real-time balance controller (``effort="realtime"``) or the offline
    effort's sampling search (``"offline"``, :func:`controller.offline.perform`).

    The real-time controller's figures on the same motion come with either effort
    (:data:`REALTIME_FIGURES`): the offline effort's search starts from its run (the warm
    start), so that the study reports both efforts from one run.
    """
    from controller import to_qpos

    qpos = to_qpos(model, motion)
    if effort == "offline":
        from controller.offline import perform
        from controller.offline.window import window_figures

        result = perform(model, qpos, motion.fps, config)
        n_frames = result.tracking.n_frames
        out = _figures(window_figures(model, result, qpos, start, stop, config),
                       lambda: window_figures(model, result, qpos, 0, n_frames, config),
                       result.tracking.fall_frame, start, motion.fps)
        realtime = (_realtime_figures(result.realtime, start, stop, motion.fps)
                    if result.realtime is not None else None)
    elif effort == "realtime":
        from controller.balance.follow import follow

        out = realtime = _realtime_figures(follow(model, qpos, motion.fps, config=config),
                                           start, stop, motion.fps)
    else:
        raise ValueError(f"unknown effort {effort!r} (efforts: {', '.join(EFFORTS)})")
    return {**out, **{name: realtime[figure] if realtime is not None else math.nan
                      for name, figure in REALTIME_FIGURES.items()}}
