"""The humanoid's kinematic checks: poses per second of ``mj_kinematics`` +
``mj_collision`` (what the self-collision and floor checks run per frame), next to
``mj_kinematics`` alone and ``mj_step`` measured in the same run on the same model, and
the whole batched contact query (:func:`controller.checks.contacts.contacts_over_frames`, with
its Python loop) per frame."""

from __future__ import annotations

import time

from eval.bench import BenchContext, clip_on_humanoid, timeit_best

NAME = "humanoid"


def run(context: BenchContext) -> dict:
    import mujoco

    from controller import to_qpos
    from controller.checks.contacts import contacts_over_frames
    from humanoid_xml import build_mjcf

    motion, model = clip_on_humanoid(context, "02_07", quick_frames=200)
    clip = motion.name
    build_s = timeit_best(lambda: build_mjcf(motion.skeleton), repeat=1 if context.quick else 3)
    data = mujoco.MjData(model)
    qpos = to_qpos(model, motion)
    n = len(qpos)

    def kinematics_only():
        for q in qpos:
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)

    def kinematics_collision():
        for q in qpos:
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_collision(model, data)

    def steps():
        mujoco.mj_resetData(model, data)
        data.ctrl[:] = 0.0
        for _ in range(n):
            mujoco.mj_step(model, data)

    repeat = 2 if context.quick else 5
    kin_s = timeit_best(kinematics_only, repeat=repeat)
    col_s = timeit_best(kinematics_collision, repeat=repeat)
    step_s = timeit_best(steps, repeat=repeat)
    start = time.perf_counter()
    table = contacts_over_frames(model, qpos)
    query_s = time.perf_counter() - start
    return {
        "clip": clip,
        "frames": n,
        "model": {"nq": int(model.nq), "nv": int(model.nv), "nu": int(model.nu),
                  "ngeom": int(model.ngeom)},
        "build_mjcf_s": build_s,
        "kinematics_collision_poses_per_s": n / col_s,
        "reference_kinematics_poses_per_s": n / kin_s,
        "reference_mj_step_per_s": n / step_s,
        "kinematics_collision_ratio_to_kinematics": kin_s / col_s,
        "kinematics_collision_ratio_to_mj_step": step_s / col_s,
        "contacts_over_frames_poses_per_s": n / query_s,
        "contacts_over_frames_ratio_to_kinematics_collision": col_s / query_s,
        "self_contact_frames": int(table.in_self_collision().sum()),
    }
