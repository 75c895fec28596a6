"""Rendering many frames fast with software OpenGL: the settings that decide what a frame
costs, and the forked worker processes that render frames side by side.

Where the time goes (OSMesa, Mesa 22's llvmpipe, 480 x 360, the generated humanoid on its
infinite floor, 05_01; CPU milliseconds per frame in one thread, on a loaded machine, so
rough): with the model's own settings (a 4096 x 4096 shadow map, 4 samples per pixel,
capsules of 28 slices x 16 stacks) 170-230. A 1024 shadow map leaves the pictures as they
were (0.013 of 255 per channel apart on average) for a third less; multisampling costs
about 1.4 times the rest of the frame; without it, the shadow's two extra passes over the
scene are 40, the floor (MuJoCo draws an infinite plane as 200 x 200 quads, in every pass)
25 and the capsules 30. With :data:`VIDEO` -- shadow map 512, no multisampling, capsules of
16 x 10, the floor left out of the shadow map (:func:`_floor_casts_no_shadow`: the same
pictures) -- a frame is 35, 5-6 times less in the same run, its pictures 0.27 of 255 per
channel from the model's own on average (0.17 % of the pixels more than 32 apart: edges that
stair by a pixel, a shadow's outline a pixel coarser). Encoding H.264 adds 11 (x264's
``medium``) or 5 (``veryfast``, files a fifth larger); a worker's start (context, textures,
shaders, its first frame) about 0.35 s. A video (:func:`controller.render.write_video`)
renders with :data:`VIDEO` on two processes; a filmstrip, a figure of a dozen panels, keeps
smooth edges and round capsules (:data:`FIGURE`).

Forking and OpenGL: a process forked from one that has rendered with llvmpipe inherits the
renderer's state without its threads (its rasterizers, its shader-cache writer) and hangs at
its first picture. So the frames are rendered in forked workers only while this process has
no such thread (:func:`fork_is_safe`), and the workers do all the OpenGL work: this process
never makes a context of its own on that path, so it stays safe to fork. Otherwise (no
``fork``, OpenGL already used here, or a daemonic process) the frames are rendered here,
one after another. Either way the pictures are the same (a worker that starts mid-video
draws its first frame twice: :func:`render_into`).
"""

from __future__ import annotations

import mmap
import multiprocessing
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class RenderSettings:
    """How offscreen frames are made.

    Attributes
    ----------
    shadow_size : int
        Pixels of the square shadow map (the models ask for 4096, which costs a third of a
        frame and looks the same as 1024 at these sizes; 512 outlines a shadow a pixel
        coarser).
    multisamples : int
        Samples per pixel for anti-aliasing (0: none; MuJoCo's default is 4, which costs
        llvmpipe about 1.4 times the rest of the frame).
    slices, stacks : int
        The tessellation of capsules, spheres and cylinders (MuJoCo's defaults: 28, 16).
    processes : int or None
        Worker processes rendering frames side by side; None: two where there are two
        cores or more and ``fork`` (else one).
    min_frames_per_process : int
        Fewer frames than this per process use fewer processes (a worker's start, its
        OpenGL context and shaders, costs about as much as a few frames).
    x264_preset : str
        x264's speed preset for ``.mp4`` (``veryfast``: half the CPU of ``medium`` at the
        same quality setting, files about a fifth larger).
    """

    shadow_size: int = 512
    multisamples: int = 0
    slices: int = 16
    stacks: int = 10
    processes: int | None = None
    min_frames_per_process: int = 12
    x264_preset: str = "veryfast"

    def with_processes(self, processes: int | None) -> RenderSettings:
        return replace(self, processes=processes)


#: Videos: speed first (at 30 frames per simulated second).
VIDEO = RenderSettings()
#: Figures (filmstrips): a dozen panels, anti-aliased, MuJoCo's round capsules.
FIGURE = RenderSettings(shadow_size=1024, multisamples=4, slices=28, stacks=16)


def default_processes() -> int:
    """Two where there are two cores or more and ``fork`` exists, else one."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return 2 if (cores or 1) >= 2 and "fork" in multiprocessing.get_all_start_methods() else 1


def planned_processes(n_frames: int, settings: RenderSettings) -> int:
    """The worker processes that render ``n_frames`` frames with ``settings`` (where
    :func:`fork_is_safe`; else they are rendered in this process): ``settings.processes``
    (or :func:`default_processes`), fewer for few frames, at least one."""
    wanted = settings.processes if settings.processes is not None else default_processes()
    return max(1, min(wanted, n_frames // max(1, settings.min_frames_per_process)))


def fork_is_safe() -> bool:
    """Whether a process forked from this one can render: ``fork`` exists and this process
    runs none of Mesa's software-OpenGL threads (llvmpipe's rasterizers, the shader-cache
    writer), which a forked child would lack. Where the threads cannot be listed (no
    ``/proc``), no."""
    if "fork" not in multiprocessing.get_all_start_methods():
        return False
    tasks = Path("/proc/self/task")
    try:
        names = [(task / "comm").read_text() for task in tasks.iterdir()]
    except OSError:
        return False
    return not any("llvmpipe" in name or "disk$" in name for name in names)


def _context(model, width: int, height: int, settings: RenderSettings):
    """A ``mujoco.Renderer`` for ``width`` x ``height`` with ``settings``' shadow map,
    samples and tessellation (read by MuJoCo when it makes the context; the model is left
    as it was)."""
    import mujoco

    quality, buffer = model.vis.quality, model.vis.global_
    fields = ((quality, "shadowsize", settings.shadow_size),
              (quality, "offsamples", settings.multisamples),
              (quality, "numslices", settings.slices), (quality, "numstacks", settings.stacks),
              # the offscreen buffer as large as the pictures (the models ask for 1280 x 720)
              (buffer, "offwidth", max(width, 1)), (buffer, "offheight", max(height, 1)))
    saved = [getattr(owner, name) for owner, name, _ in fields]
    for owner, name, value in fields:
        setattr(owner, name, value)
    try:
        renderer = mujoco.Renderer(model, height=height, width=width)
    finally:
        for (owner, name, _), value in zip(fields, saved, strict=True):
            setattr(owner, name, value)
    # The floor's reflection costs a quarter of the (software) rendering time.
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
    return renderer


def _floor_casts_no_shadow(scene) -> None:
    """Leave upward-facing planes out of the shadow maps when every shadow-casting light
    shines downwards: such a floor shadows nothing (what it would shadow lies below it), and
    drawing it into the map is a tenth of a frame. MuJoCo skips "decor" geoms there and
    nowhere else, so the pictures are the same to the last bit."""
    import mujoco

    lights = [scene.lights[i] for i in range(scene.nlight)]
    if any(light.castshadow and light.dir[2] >= 0.0 for light in lights):
        return
    for i in range(scene.ngeom):
        geom = scene.geoms[i]
        if geom.type == mujoco.mjtGeom.mjGEOM_PLANE and geom.mat[2, 2] > 0.999:
            geom.category = mujoco.mjtCatBit.mjCAT_DECOR


def render_into(out, model, qpos, centres, view, settings: RenderSettings,
                warm_up: bool = False) -> None:
    """Render each state of ``qpos`` (N, nq) into ``out`` (N, H, W, 3), the camera looking
    at ``centres`` (N, 2) (horizontal positions) from ``view``. ``warm_up``: draw the first
    state once more before, unkept -- a context's first picture differs from the ones after
    it by a level in a few pixels, so a worker taking up the frames in the middle of a
    video warms up and the video is the same whatever the number of workers."""
    import mujoco

    data = mujoco.MjData(model)
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FREE
    camera.azimuth, camera.elevation = view.azimuth_deg, view.elevation_deg
    camera.distance = view.distance_m
    renderer = _context(model, out.shape[2], out.shape[1], settings)
    try:
        for i, q in ([(0, qpos[0])] if warm_up else []) + list(enumerate(qpos)):
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_camlight(model, data)
            camera.lookat[:] = (centres[i, 0], centres[i, 1], view.height_m)
            renderer.update_scene(data, camera=camera)
            _floor_casts_no_shadow(renderer.scene)
            renderer.render(out=out[i])
    finally:
        renderer.close()


def _worker(out, model, qpos, centres, view, settings, threads: str | None,
            warm_up: bool) -> None:
    if threads is not None:  # read when this process makes its first OpenGL context
        os.environ.setdefault("LP_NUM_THREADS", threads)
    render_into(out, model, qpos, centres, view, settings, warm_up)


def render_frames_parallel(model, qpos, centres, view, width: int, height: int,
                           settings: RenderSettings) -> np.ndarray:
    """Pictures of each state (N, height, width, 3) uint8, rendered by forked workers where
    that is safe (:func:`fork_is_safe`), else here; see :func:`render_into`."""
    n = qpos.shape[0]
    processes = planned_processes(n, settings)
    # (a daemonic process, e.g. a pool's worker, may not start processes of its own)
    if n == 0 or not fork_is_safe() or multiprocessing.current_process().daemon:
        out = np.zeros((n, height, width, 3), dtype=np.uint8)
        if n:
            render_into(out, model, qpos, centres, view, settings)
        return out
    # Anonymous shared memory: the workers write their frames straight into it.
    shared = mmap.mmap(-1, n * height * width * 3)
    out = np.frombuffer(shared, dtype=np.uint8).reshape(n, height, width, 3)
    context = multiprocessing.get_context("fork")
    # Several workers share the cores: each rasterizes in its own thread (llvmpipe's
    # LP_NUM_THREADS=0), without handing tiles to threads of its own.
    threads = "0" if processes > 1 else None
    workers = []
    try:
        for part in np.array_split(np.arange(n), processes):
            workers.append(context.Process(
                target=_worker, daemon=True,
                args=(out[part[0]:part[-1] + 1], model, qpos[part], centres[part], view,
                      settings, threads, part[0] > 0)))
            workers[-1].start()
        for worker in workers:
            worker.join()
    finally:
        for worker in workers:
            if worker.is_alive():
                worker.terminate()
                worker.join()
    failed = [w.exitcode for w in workers if w.exitcode != 0]
    if failed:
        raise RuntimeError(f"a rendering process failed (exit code {failed[0]}; its error "
                           "is above)")
    return out
