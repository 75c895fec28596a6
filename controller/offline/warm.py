"""The offline search's warm start: the real-time balance controller's run as servo targets.

The search (:mod:`controller.offline.samcon`) samples corrections around a plan's servo
targets. Taken at the reference (:func:`controller.tracking.plan.plan_tracking`), they
know nothing of balance: a step that goes wrong shows only once the body is going down.
The real-time controller (:func:`controller.balance.follow`) places its feet from the
capture point and holds its balance through whole-body inverse dynamics; where it stays
up, its torques are a way to perform the motion. :func:`warm_plan` turns them into the
targets of position servos: a servo without damping pushes ``kp (target - q)``, so the
target ``q + tau / kp`` at each physics step, with ``q`` the real-time run's joint angle at
the step's start and ``tau`` its torque, gives its torque exactly, and the servos replay
the real-time run step for step (to rounding), while away from it each servo's stiffness
pulls back towards the real-time run's path. The search then corrects the open loop
where a correction costs less.

The warm plan's model is the humanoid with its servos' damping taken out (the real-time
run's torques hold its damping already; the humanoid is integrated ``implicitfast``, where
a servo's damping acts on the velocity the step ends with, so no target of a damped servo
gives the torque exactly) and targets allowed beyond a joint's range (``ctrllimited``
off); the force each servo can push stays its ``forcerange``, the torque motors' range. It
starts from the real-time run's start (its prepared reference's first frame).

Where the real-time run falls, its path is no start for a search that must stay up (the
servos without damping cannot follow the reference on their own): the plan is kept as it
was, and the search starts from the reference's targets.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace

import numpy as np

from controller.config import DEFAULT, ControllerConfig


@dataclass(frozen=True)
class WarmStart:
    """What the warm start took from the real-time run.

    Attributes
    ----------
    plan : controller.tracking.plan.TrackingPlan
        The search's plan: the real-time run's targets, start and model (the plan given,
        where the real-time run fell).
    used_frames : int
        Frames (from the start) whose targets are the real-time run's (0 where it fell).
    realtime_fell : bool
    realtime_run : controller.balance.run.BalanceRun
        The real-time controller's run itself (its figures are the real-time effort's on
        the same reference: the study reports them beside the offline effort's).
    """

    plan: object
    used_frames: int
    realtime_fell: bool
    realtime_run: object = None


def warm_plan(model, plan, config: ControllerConfig = DEFAULT) -> WarmStart:
    """The plan ``plan`` with the real-time controller's run as its servo targets.

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid (not modified).
    plan : controller.tracking.plan.TrackingPlan
        A ``"free"`` plan of the reference (:func:`controller.tracking.plan.plan_tracking`).
    config : controller.config.ControllerConfig
        The real-time controller's sections.

    Returns
    -------
    WarmStart
    """
    from controller.balance.follow import follow
    from controller.balance.run import replay

    run = follow(model, plan.reference_qpos, plan.fps, config=config)
    if run.fell or run.diverged_frame is not None:
        return WarmStart(plan=plan, used_frames=0, realtime_fell=True, realtime_run=run)
    if abs(run.timestep_s - float(plan.model.opt.timestep)) > 1e-12 \
            or run.substeps != plan.substeps:
        raise ValueError("the real-time run's physics step is not the plan's")
    sim = copy.deepcopy(plan.model)
    kp = sim.actuator_gainprm[:, 0]
    if np.any(kp <= 0):
        raise ValueError("the warm start needs position servos (kp > 0) on every actuator")
    sim.actuator_biasprm[:, 2] = 0.0  # no damping: the real-time torques hold it
    sim.actuator_ctrllimited[:] = 0
    joints = sim.actuator_trnid[:, 0]
    angles = replay(model, run, every_step=True)[:, sim.jnt_qposadr[joints]]  # (S, nu)
    ctrl = plan.ctrl.copy()
    steps = min(ctrl.shape[0], run.ctrl.shape[0])
    ctrl[:steps] = angles[:steps] + run.ctrl[:steps] / kp
    warm = replace(plan, model=sim, ctrl=ctrl, start_qpos=run.start_qpos.copy(),
                   start_qvel=run.start_qvel.copy())
    return WarmStart(plan=warm, used_frames=steps // plan.substeps + 1, realtime_fell=False,
                     realtime_run=run)
