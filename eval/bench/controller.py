"""The physical checks' speed, each against raw MuJoCo on the same model in the same run:

- kinematic checks (:func:`controller.checks.validity.check_motion`: limits, self-collision,
  floor, per frame) against a bare loop of ``mj_kinematics`` + ``mj_collision`` over the
  same states;
- the inverse-dynamics residual (:func:`controller.checks.dynamics.root_residual`: filter,
  finite differences, ``mj_inverse``, floor support by NNLS) against a bare loop of
  ``mj_inverse`` over the same states;
- tracking (:func:`controller.tracking.track`, both modes) in physics steps per second
  against a bare loop that feeds ``mj_step`` the same inputs (the plan's targets, and the
  driven root's state) with none of the per-step bookkeeping (limit rows, samples,
  warnings) — the same physics, so the ratio is the cost of the measuring;
- the balance controller (:func:`controller.balance.follow`, root free) in simulated
  seconds per wall second, against a bare ``mj_step`` loop replaying the torques it
  applied on the same torque-actuated model (the same physics without the control): the
  ratio is what the whole-body QP costs, in raw ``mj_step`` equivalents per step; on one
  process, and (keys ``..._2proc_``) with its lookahead rollouts on two (the same run);
- (full run only) the kinematic checks of every frame of every clip, reading included.
"""

from __future__ import annotations

import time

import numpy as np

from eval.bench import BenchContext, clip_on_humanoid, timeit_best

NAME = "controller"


def run(context: BenchContext) -> dict:
    import mujoco

    from controller import to_qpos
    from controller.checks.dynamics import root_residual
    from controller.checks.validity import check_motion
    from controller.tracking.servo import plan_tracking, track

    motion, model = clip_on_humanoid(context, "02_01", quick_frames=120)
    clip = motion.name
    data = mujoco.MjData(model)
    qpos = to_qpos(model, motion)
    n = len(qpos)
    repeat = 2 if context.quick else 5

    def raw_kinematics_collision():
        for q in qpos:
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_collision(model, data)

    raw_kin_s = timeit_best(raw_kinematics_collision, repeat=repeat)
    check_s = timeit_best(lambda: check_motion(model, motion), repeat=repeat)

    def raw_inverse():
        for q in qpos:
            data.qpos[:] = q
            mujoco.mj_inverse(model, data)

    raw_inv_s = timeit_best(raw_inverse, repeat=repeat)
    residual_s = timeit_best(lambda: root_residual(model, qpos, motion.fps), repeat=repeat)

    out = {
        "clip": clip,
        "frames": n,
        "kinematic_check_frames_per_s": n / check_s,
        "reference_kinematics_collision_per_s": n / raw_kin_s,
        "kinematic_check_ratio_to_raw": raw_kin_s / check_s,
        "residual_frames_per_s": n / residual_s,
        "reference_mj_inverse_per_s": n / raw_inv_s,
        "residual_ratio_to_raw": raw_inv_s / residual_s,
    }
    for mode in ("driven", "free"):
        result = max((track(model, motion, mode) for _ in range(repeat)),
                     key=lambda r: r.steps_per_s)
        plan = plan_tracking(model, qpos, motion.fps, mode)
        sim, sim_data = plan.model, plan.start_data()

        def raw_steps(plan=plan, sim=sim, sim_data=sim_data, free=(slice(0, 7), slice(0, 6))):
            if plan.root_qpos is None:
                for k in range(plan.steps):
                    sim_data.ctrl[:] = plan.ctrl[k]
                    mujoco.mj_step(sim, sim_data)
            else:
                for k in range(plan.steps):
                    sim_data.ctrl[:] = plan.ctrl[k]
                    sim_data.qpos[free[0]] = plan.root_qpos[k]
                    sim_data.qvel[free[1]] = plan.root_qvel[k]
                    mujoco.mj_step(sim, sim_data)

        raw_s = timeit_best(lambda f=raw_steps, p=plan, d=sim_data: (_reset(p, d), f()),
                            repeat=repeat)
        out[f"tracking_{mode}_steps"] = result.steps
        out[f"tracking_{mode}_steps_per_s"] = result.steps_per_s
        out[f"reference_mj_step_{mode}_per_s"] = plan.steps / raw_s
        out[f"tracking_{mode}_ratio_to_raw"] = result.steps_per_s / (plan.steps / raw_s)
    out.update(_balance(model, qpos, motion.fps, repeat=2 if context.quick else 3))
    if not context.quick:
        # a walk on which the controller needs its search (16_15: about 3 times the
        # steps, modes changed for 2.25 s)
        hard, hard_model = clip_on_humanoid(context, "16_15", quick_frames=120)
        out.update(_balance(hard_model, to_qpos(hard_model, hard), hard.fps, repeat=1,
                            prefix="balance_16_15_"))
        from controller.checks.calibration import calibrate
        from upm.motion.catalog import Catalog

        start = time.perf_counter()
        calibration = calibrate(Catalog(context.data_dir))
        seconds = time.perf_counter() - start
        frames = calibration.totals()["frames"]
        out["calibration_all_clips_s"] = seconds
        out["calibration_frames"] = frames
        out["calibration_frames_per_s"] = frames / seconds
    return out


def _balance(model, qpos, fps: float, repeat: int, prefix: str = "balance_") -> dict:
    """The balance controller's speed against raw ``mj_step`` on the same steps (the
    run's own; the search's extra steps count in its wall time), on one process and on
    two. ``raw_steps_per_step`` is in each run's own unit, raw ``mj_step`` timed in bursts
    while it ran (:mod:`controller.raw_clock`); the replay of the run's torques, timed
    after the runs, gives ``reference_mj_step_..._per_s`` and ``ratio_to_raw``."""
    import mujoco

    from controller.balance.control import torque_model
    from controller.balance.follow import follow

    run = min((follow(model, qpos, fps) for _ in range(repeat)), key=lambda r: r.wall_s)
    two = min((follow(model, qpos, fps, processes=2) for _ in range(repeat)),
              key=lambda r: r.wall_s)
    sim = torque_model(model)
    sim.opt.timestep = run.timestep_s
    data = mujoco.MjData(sim)

    def raw_steps():
        mujoco.mj_resetData(sim, data)
        data.qpos[:] = run.start_qpos
        data.qvel[:] = run.start_qvel
        for k in range(run.steps):
            data.ctrl[:] = run.ctrl[k]
            mujoco.mj_step(sim, data)

    raw_s = timeit_best(raw_steps, repeat=repeat)
    return {
        f"{prefix}steps": run.steps,
        f"{prefix}fell": run.fell,
        f"{prefix}search_retries": run.retries,
        f"{prefix}simulated_steps_per_step": run.simulated_steps / max(run.steps, 1),
        # physics steps simulated in all (search, lookahead, less those reused) per step:
        # the controller's work, free of the machine's noise
        f"{prefix}physics_steps_per_step": (run.simulated_steps - run.reused_steps
                                            + run.lookahead_steps) / max(run.steps, 1),
        f"{prefix}sim_s_per_wall_s": run.sim_s / run.wall_s,
        f"{prefix}wall_s_per_sim_s": run.wall_s / run.sim_s,
        f"reference_mj_step_{prefix}per_s": run.steps / raw_s,
        f"{prefix}ratio_to_raw": (run.sim_s / run.wall_s) / (run.sim_s / raw_s),
        f"{prefix}raw_steps_per_step": run.raw_steps_per_step,
        f"{prefix}2proc_wall_s_per_sim_s": two.wall_s / two.sim_s,
        f"{prefix}2proc_raw_steps_per_step": two.raw_steps_per_step,
        f"{prefix}2proc_same_run": bool(np.array_equal(two.ctrl, run.ctrl)),
    }


def _reset(plan, data) -> None:
    """Put ``data`` back in the plan's first state."""
    import mujoco

    mujoco.mj_resetData(plan.model, data)
    data.qpos[:] = plan.start_qpos
    data.qvel[:] = plan.start_qvel
    data.ctrl[:] = plan.ctrl[0]
    mujoco.mj_forward(plan.model, data)
