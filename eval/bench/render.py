"""Rendering a video: wall seconds per simulated second of ``upm simulate --video`` at its
default size (480 x 360, 30 frames per simulated second, .mp4), through
:func:`controller.render.write_video` on a real clip (05_01's first 4.8 s; 1.2 s with
``--quick``) on its subject's humanoid.

The reference, timed interleaved with it (alternating rounds, medians), is one raw offscreen
``mujoco.Renderer.render`` call of the same clip's frames at the same size with the model's
own visual settings (its 4096 shadow map, 4 samples per pixel; reflection off, as the
renderer always had it): the per-frame work before the renderer's settings and processes
were chosen (:mod:`controller.render_pool`). It runs in a forked process of its own, so that
this process never holds an OpenGL context and the video's workers can fork from it.

``targets``: issue 63's 1 wall s per simulated s (on two cores), and the same as a ratio to the
reference: the old renderer took 4.17 s per simulated s (20 s for a 4.8 s clip) at
:data:`RATIO_BEFORE` raw renders' time per simulated s, so 1 s is ``RATIO_BEFORE / 4.17``.
"""

from __future__ import annotations

import multiprocessing
import resource
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from eval.bench import BenchContext, clip_on_humanoid, target

NAME = "render"

CLIP = "05_01"
SECONDS, QUICK_SECONDS = 4.8, 1.2
WIDTH, HEIGHT = 480, 360
#: Issue 63's target, wall s per simulated s, and where the old renderer stood against the
#: reference: its video cost this many raw renders per simulated s (the median of 8 of its
#: videos of this clip, each interleaved with the reference, on this 2-core machine under a
#: load of 7-14: 20-35), when it took 4.17 wall s per simulated s.
TARGET_S_PER_S = 1.0
RATIO_BEFORE = 30.5
S_PER_S_BEFORE = 20.0 / 4.8


def _cpu_s() -> float:
    own, children = (resource.getrusage(w) for w in (resource.RUSAGE_SELF,
                                                     resource.RUSAGE_CHILDREN))
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def _raw_renders(connection, model, qpos, view) -> None:
    """In a forked process: seconds of each of ``len(qpos)`` raw ``Renderer.render`` calls
    (after two untimed ones), sent through ``connection``."""
    import mujoco

    renderer = mujoco.Renderer(model, height=HEIGHT, width=WIDTH)
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
    data = mujoco.MjData(model)
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FREE
    camera.azimuth, camera.elevation = view.azimuth_deg, view.elevation_deg
    camera.distance = view.distance_m
    out = np.zeros((HEIGHT, WIDTH, 3), dtype=np.uint8)
    seconds = []
    for i, q in enumerate(np.concatenate([qpos[:2], qpos])):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_camlight(model, data)
        camera.lookat[:] = (q[0], q[1], view.height_m)
        renderer.update_scene(data, camera=camera)
        start = time.perf_counter()
        renderer.render(out=out)
        if i >= 2:
            seconds.append(time.perf_counter() - start)
    renderer.close()
    connection.send(seconds)


def _reference_s(model, qpos, view) -> float:
    """Median seconds of one raw render (:func:`_raw_renders`, in a forked process)."""
    context = multiprocessing.get_context("fork")
    ours, theirs = context.Pipe()
    process = context.Process(target=_raw_renders, args=(theirs, model, qpos, view))
    process.start()
    seconds = ours.recv()
    process.join()
    return statistics.median(seconds)


def run(context: BenchContext) -> dict:
    from controller import to_qpos
    from controller.render import offscreen_gl, side_view, write_video
    from controller.render_pool import VIDEO, fork_is_safe, planned_processes

    offscreen_gl()
    motion, model = clip_on_humanoid(context, CLIP, quick_frames=10_000)
    seconds = QUICK_SECONDS if context.quick else SECONDS
    motion = motion.frames(0, round(seconds * motion.fps))
    simulated_s = motion.n_frames / motion.fps
    qpos = to_qpos(model, motion)
    view = side_view(model, qpos)
    step = max(1, round(motion.fps / 30.0))
    video_frames = len(range(0, len(qpos), step))
    reference_frames = qpos[::step][:8 if context.quick else 24]
    rounds = 1 if context.quick else 3

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.mp4"
        workers = planned_processes(video_frames, VIDEO) if fork_is_safe() else 0
        figure, cpu, reference = [], [], []
        for i in range(rounds):
            if i % 2:
                reference.append(_reference_s(model, reference_frames, view))
            start_cpu, start = _cpu_s(), time.perf_counter()
            write_video(model, qpos, motion.fps, path, windows=[slice(100, 200)])
            figure.append((time.perf_counter() - start) / simulated_s)
            cpu.append((_cpu_s() - start_cpu) / simulated_s)
            if not i % 2:
                reference.append(_reference_s(model, reference_frames, view))
        size = path.stat().st_size
    ratios = [f / r for f, r in zip(figure, reference, strict=True)]
    s_per_s, ratio = statistics.median(figure), statistics.median(ratios)
    return {
        "clip": f"{motion.name or CLIP}@0:{motion.n_frames}",
        "simulated_s": simulated_s,
        "video": f"{WIDTH}x{HEIGHT}, {video_frames} frames, .mp4 ({size} bytes)",
        "worker_processes": workers,
        "settings": {"shadow_size": VIDEO.shadow_size, "multisamples": VIDEO.multisamples,
                     "slices": VIDEO.slices, "stacks": VIDEO.stacks,
                     "x264_preset": VIDEO.x264_preset},
        "wall_s_per_simulated_s": s_per_s,
        "cpu_s_per_simulated_s": statistics.median(cpu),
        "reference_raw_render_s": statistics.median(reference),
        "ratio_to_reference": ratio,
        "ratio_range": [min(ratios), max(ratios)],
        "wall_s_per_simulated_s_before": S_PER_S_BEFORE,
        "timing": f"medians of {rounds} videos, each interleaved with {len(reference_frames)} "
                  "raw renders (their median)",
        "targets": {"wall_s_per_simulated_s": target(
            s_per_s, TARGET_S_PER_S, ratio, RATIO_BEFORE * TARGET_S_PER_S / S_PER_S_BEFORE)},
    }
