"""The offline effort's speed (:func:`controller.offline.perform`: the sampling search over
the servos' targets, its rollouts on ``offline.threads`` threads, and the replay) in wall
seconds per simulated second, against a bare ``mj_step`` loop on one thread feeding the
same model the plan's servo targets, measured in the same run: the ratio is the search's
cost in raw ``mj_step`` equivalents per simulated step (about ``samples`` x the passes it
makes, over the threads, plus the cost's kinematics); and one transition of the method
``performed`` (following ``linear``, 02_01@200 -> 02_03@20, 20 frames, 0.5 s of context
each side), in seconds (the transitions bench has the other methods' microseconds). Quick
mode: 0.4 s of the clip and 24 samples, not 1 s and the configuration's 240."""

from __future__ import annotations

import time

from eval.bench import BenchContext, clip_on_humanoid, target, timeit_best

NAME = "offline"

#: Issue 61's target: at most this many wall s per simulated s on two cores ...
TARGET_S_PER_S = 20.0
#: ... which was this ratio to a bare mj_step loop when it was set (17,300 raw steps/s of
#: the 02 humanoid on one core, 600 steps per simulated s: 20 s/s is 577 raw steps per
#: simulated step).
TARGET_RATIO = 577.0


def run(context: BenchContext) -> dict:
    import mujoco

    from controller import to_qpos
    from controller.config import DEFAULT
    from controller.offline import perform
    from controller.tracking.plan import plan_tracking

    motion, model = clip_on_humanoid(context, "02_01", quick_frames=48)
    if not context.quick:
        motion = motion.frames(0, min(motion.n_frames, 121))
    qpos = to_qpos(model, motion)
    config = (DEFAULT.updated({"offline": {"samples": 24, "keep": 4}}) if context.quick
              else DEFAULT)
    plan = plan_tracking(model, qpos, motion.fps, "free", True, config)
    data = mujoco.MjData(plan.model)

    def raw_steps():
        data.qpos[:] = plan.start_qpos
        data.qvel[:] = plan.start_qvel
        for k in range(plan.steps):
            data.ctrl[:] = plan.ctrl[k]
            mujoco.mj_step(plan.model, data)

    raw_s = timeit_best(raw_steps, repeat=2 if context.quick else 3)
    clock = time.perf_counter()
    result = perform(model, qpos, motion.fps, config)
    wall = time.perf_counter() - clock
    simulated_s = (motion.n_frames - 1) / motion.fps
    performed_s = _performed_transition_s(context, config)
    per_s = wall / simulated_s
    ratio = wall / raw_s
    return {
        "clip": motion.name,
        "frames": motion.n_frames,
        "simulated_s": simulated_s,
        "samples": config.offline.samples,
        "threads": config.offline.threads,
        "rollouts": result.samples,
        "passes": result.outcome.passes,
        "fell": result.fell,
        "error_deg_rms": result.summary()["error_deg_rms"],
        "wall_s": wall,
        "wall_s_per_sim_s": per_s,
        "reference_mj_step_per_s": plan.steps / raw_s,
        "ratio_to_mj_step": ratio,
        "performed_s_per_transition": performed_s,
        "targets": {"wall_s_per_sim_s": target(per_s, TARGET_S_PER_S, ratio, TARGET_RATIO)},
    }


def _performed_transition_s(context: BenchContext, config) -> float:
    """Wall seconds of one ``performed`` transition (following ``linear``)."""
    from controller.offline.performer import install
    from upm.motion.catalog import Catalog
    from upm.transitions import get_method, transition
    from upm.transitions.performed import PerformedKeys

    install()
    catalog = Catalog(context.data_dir)
    if "02_01" not in catalog or "02_03" not in catalog:
        return float("nan")
    before = catalog.load("02_01").frames(80, 201)
    after = catalog.load("02_03").frames(20, 140)
    clock = time.perf_counter()
    keys = PerformedKeys(get_method("linear"), config=config)
    transition("performed", before, after, 20, 0.5, keys)
    return time.perf_counter() - clock
