"""Offscreen pictures of the humanoid: frames, a filmstrip PNG (the paper's Fig. 11/12: the
character through a transition, frames side by side), and videos.

Rendering uses ``mujoco.Renderer``, closed explicitly after use. On Linux without a
display, OSMesa (software OpenGL, Debian's ``libosmesa6``) is used: ``MUJOCO_GL=osmesa``
is set before MuJoCo creates a context (:func:`offscreen_gl`), which needs no GPU. What a
frame costs there, the settings chosen for videos and figures, and the worker processes
that render frames side by side: :mod:`controller.render_pool`.

Formats, by the output's suffix (:func:`write_video`): ``.mp4`` (H.264, through the
ffmpeg binary that the ``imageio-ffmpeg`` wheel bundles — or ``$IMAGEIO_FFMPEG_EXE``),
``.gif`` (Pillow), ``.png`` (a filmstrip instead of a video).
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from controller.render_pool import FIGURE, VIDEO, RenderSettings, render_frames_parallel

#: Colour of the bar marking frames inside a transition window (RGB, 0-255).
WINDOW_COLOUR = (230, 120, 20)
VIDEO_SUFFIXES = (".mp4", ".gif", ".png")


def offscreen_gl() -> str:
    """Make offscreen rendering work here and say how: ``"osmesa"``, ``"egl"`` or the
    default (``"glfw"``, which needs a display).

    On Linux with no ``DISPLAY`` and no ``MUJOCO_GL``, sets ``MUJOCO_GL=osmesa``. If MuJoCo
    was imported before that (it reads ``MUJOCO_GL`` once, on import), its renderer is
    pointed at the OSMesa context instead.
    """
    headless = sys.platform.startswith("linux") and not os.environ.get("DISPLAY") \
        and not os.environ.get("WAYLAND_DISPLAY")
    if headless and not os.environ.get("MUJOCO_GL"):
        os.environ["MUJOCO_GL"] = "osmesa"
    backend = os.environ.get("MUJOCO_GL", "").lower() or "glfw"
    import mujoco  # noqa: F401 - reads MUJOCO_GL on first import

    if headless and backend in ("osmesa", "egl"):
        for module in _gl_context_modules():
            chosen = getattr(module, "_MUJOCO_GL", backend)
            if chosen not in ("osmesa", "egl"):
                from mujoco.osmesa import GLContext

                module.GLContext = GLContext
                backend = "osmesa"
    return backend


def _gl_context_modules():
    import importlib

    out = []
    for name in ("mujoco.rendering.classic.gl_context", "mujoco.gl_context"):
        try:
            out.append(importlib.import_module(name))
        except ImportError:
            continue
    return out


@dataclass(frozen=True)
class View:
    """A camera looking at the character from the side of its travel.

    Attributes
    ----------
    azimuth_deg : float
        MuJoCo free-camera azimuth (degrees about the vertical).
    elevation_deg : float
    distance_m : float
    height_m : float
        Height of the point looked at.
    """

    azimuth_deg: float
    elevation_deg: float = -8.0
    distance_m: float = 3.0
    height_m: float = 0.9


def side_view(model, qpos, root_qpos: int = 0) -> View:
    """A view from the side of the root's travel over ``qpos`` (T, nq) — or, when it
    travels less than 30 cm, from the side of the body's heading at the middle state —
    at a distance and height from the body's stature."""
    from controller.body import body_figures

    qpos = np.asarray(qpos)
    xy = qpos[:, root_qpos:root_qpos + 2]
    travel = xy[-1] - xy[0]
    if np.hypot(*travel) > 0.3:
        heading = math.atan2(travel[1], travel[0])
    else:
        w, x, y, z = qpos[len(qpos) // 2, root_qpos + 3:root_qpos + 7]
        # The body faces the ASF's +z, MuJoCo's -y, turned by the root's rotation R:
        # -R e_y; the camera looks along azimuth (cos, sin).
        heading = math.atan2(-(1 - 2 * (x * x + z * z)), -2 * (x * y - w * z))
    stature = body_figures(model).stature_m
    return View(azimuth_deg=math.degrees(heading) + 90.0, distance_m=1.9 * stature,
                height_m=0.55 * stature)


def render_frames(model, qpos, width: int = 240, height: int = 320, view: View | None = None,
                  follow: bool = True, settings: RenderSettings = VIDEO) -> np.ndarray:
    """Pictures of the humanoid in each state.

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : array_like, shape (N, nq)
    width, height : int
        Pixels.
    view : View, optional
        Default: :func:`side_view` of ``qpos``.
    follow : bool
        Centre every picture on the root's horizontal position (else on the first).
    settings : RenderSettings
        Shadow map, anti-aliasing and worker processes
        (:mod:`controller.render_pool`; default :data:`~controller.render_pool.VIDEO`).

    Returns
    -------
    ndarray of uint8, shape (N, height, width, 3)
    """
    offscreen_gl()
    qpos = np.atleast_2d(np.asarray(qpos, dtype=float))
    view = view or side_view(model, qpos)
    centres = qpos[:, :2] if follow else np.repeat(qpos[:1, :2], len(qpos), axis=0)
    return render_frames_parallel(model, qpos, centres, view, width, height, settings)


def mark_windows(images, in_window, thickness: int = 8) -> np.ndarray:
    """Images with a bar along the bottom of those inside a transition window.

    Parameters
    ----------
    images : ndarray of uint8, shape (N, H, W, 3)
    in_window : array_like of bool, shape (N,)

    Returns
    -------
    ndarray of uint8, shape (N, H, W, 3) (a copy)
    """
    out = np.array(images, copy=True)
    out[np.asarray(in_window, dtype=bool), -thickness:] = WINDOW_COLOUR
    return out


def filmstrip_frames(windows, n_frames: int, step: int = 5, margin: int = 2,
                     limit: int = 16) -> list[int]:
    """Frames for a filmstrip of transition windows: every ``step``-th frame from
    ``margin`` steps before each window to ``margin`` steps after it (at most ``limit``,
    evenly thinned), or evenly spread frames when there is no window."""
    frames: list[int] = []
    for window in windows:
        start, stop, _ = window.indices(n_frames)
        frames += range(max(0, start - margin * step), min(n_frames, stop + margin * step),
                        step)
    if not frames:
        frames = list(range(0, n_frames, max(1, n_frames // limit)))
    frames = sorted(set(frames))
    if len(frames) > limit:
        frames = [frames[round(i)] for i in np.linspace(0, len(frames) - 1, limit)]
    return frames


def filmstrip(model, rows, frames, path, *, fps: float | None = None, windows=(),
              width: int = 160, height: int = 240, title: str | None = None) -> Path:
    """A PNG of the humanoid at some frames, side by side, one row per trajectory.

    Parameters
    ----------
    model : mujoco.MjModel
    rows : list of (str, ndarray of shape (T, nq))
        Labelled trajectories (e.g. the reference and a simulation) of the same motion.
    frames : sequence of int
        The frames shown (e.g. every 5th frame of a window and a few around it).
    path : path-like
        The PNG written (atomically).
    fps : float, optional
        To label panels with times.
    windows : sequence of slice
        Frames inside a window get a coloured bar and a coloured label.
    width, height : int
        Pixels of each panel.
    title : str, optional

    Returns
    -------
    Path
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from upm.core.fileio import atomic_open

    frames = [int(f) for f in frames]
    if not frames or not rows:
        raise ValueError("a filmstrip needs at least one frame and one row")
    n_total = np.asarray(rows[0][1]).shape[0]
    in_window = np.zeros(n_total, dtype=bool)
    for window in windows:
        in_window[window] = True
    view = side_view(model, np.asarray(rows[0][1])[frames])
    dpi = 100
    fig = Figure(figsize=(len(frames) * width / dpi, len(rows) * (height + 40) / dpi + 0.4),
                 dpi=dpi)
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(rows), len(frames), squeeze=False)
    for r, (label, qpos) in enumerate(rows):
        images = render_frames(model, np.asarray(qpos)[frames], width, height, view,
                               settings=FIGURE)
        images = mark_windows(images, in_window[frames])
        for c, frame in enumerate(frames):
            ax = axes[r, c]
            ax.imshow(images[c])
            ax.set_xticks([])
            ax.set_yticks([])
            when = f"{frame / fps:.3f} s" if fps else f"frame {frame}"
            ax.set_title(when if c else f"{label}\n{when}", fontsize=8,
                         color=np.array(WINDOW_COLOUR) / 255 if in_window[frame] else "black")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.subplots_adjust(left=0.005, right=0.995, bottom=0.01, top=0.86 if title else 0.9,
                        wspace=0.02, hspace=0.25)
    path = Path(path)
    with atomic_open(path, "wb") as handle:
        fig.savefig(handle, format="png")
    return path


def write_video(model, qpos, fps: float, path, *, windows=(), video_fps: float = 30.0,
                width: int = 480, height: int = 360, settings: RenderSettings = VIDEO) -> Path:
    """Render a trajectory to a video (``.mp4``, ``.gif``) or a filmstrip (``.png``).

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : ndarray, shape (T, nq)
        The states at the motion's frames.
    fps : float
        The motion's frame rate.
    path : path-like
        Its suffix picks the format (:data:`VIDEO_SUFFIXES`).
    windows : sequence of slice
        Window frames get a coloured bar.
    video_fps : float
        Frames per second of the video (every ``round(fps / video_fps)``-th state is
        drawn, so the video plays in real time).
    width, height : int
    settings : RenderSettings
        How the frames are rendered and encoded (:mod:`controller.render_pool`; default
        :data:`~controller.render_pool.VIDEO`: two processes, no anti-aliasing).

    Returns
    -------
    Path

    Raises
    ------
    UsageError
        For an unknown suffix.
    """
    from upm.core.errors import UsageError

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        raise UsageError(f"{path}: unknown video format {suffix or '(none)'!r} "
                         f"(use {', '.join(VIDEO_SUFFIXES)})")
    qpos = np.asarray(qpos, dtype=float)
    finite = np.all(np.isfinite(qpos), axis=1)
    qpos = qpos[: int(np.argmin(finite)) if not finite.all() else len(qpos)]
    if suffix == ".png":
        step = max(1, len(qpos) // 12)
        return filmstrip(model, [("", qpos)], range(0, len(qpos), step), path, fps=fps,
                         windows=windows)
    step = max(1, round(fps / video_fps))
    frames = np.arange(0, len(qpos), step)
    in_window = np.zeros(len(qpos), dtype=bool)
    for window in windows:
        in_window[window] = True
    images = render_frames(model, qpos[frames], width, height, side_view(model, qpos),
                           settings=settings)
    images = mark_windows(images, in_window[frames])
    rate = fps / step
    if suffix == ".gif":
        _write_gif(images, rate, path)
    else:
        _write_mp4(images, rate, path, settings.x264_preset)
    return path


def _write_gif(images, rate: float, path: Path) -> None:
    from PIL import Image

    from upm.core.fileio import atomic_open

    pictures = [Image.fromarray(image) for image in images]
    with atomic_open(path, "wb") as handle:
        pictures[0].save(handle, format="GIF", save_all=True, append_images=pictures[1:],
                         duration=round(1000 / rate), loop=0)


def _write_mp4(images, rate: float, path: Path, preset: str) -> None:
    import imageio_ffmpeg

    from upm.core.fileio import atomic_path

    height, width = images.shape[1:3]
    with atomic_path(path) as tmp:
        writer = imageio_ffmpeg.write_frames(tmp, (width, height), fps=rate, codec="libx264",
                                             macro_block_size=8, ffmpeg_log_level="error",
                                             output_params=["-preset", preset])
        writer.send(None)
        for image in images:
            writer.send(np.ascontiguousarray(image))
        writer.close()


def has_display() -> bool:
    """Whether an interactive window can be opened here (macOS and Windows always; Linux
    with ``DISPLAY`` or ``WAYLAND_DISPLAY`` set)."""
    if not sys.platform.startswith("linux"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def play_in_viewer(model, qpos, fps: float, *, loops: int = 1) -> None:
    """Play states in MuJoCo's interactive viewer at real time (``mujoco.viewer``).

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : ndarray, shape (T, nq)
    fps : float
    loops : int
        How many times to play it (the window can be closed at any time).

    Raises
    ------
    UsageError
        Where there is no display.
    """
    import time

    from upm.core.errors import UsageError

    if not has_display():
        raise UsageError("--viewer needs a display (DISPLAY is not set); use --video "
                         "V.mp4 to render offscreen instead")
    import mujoco
    import mujoco.viewer

    qpos = np.asarray(qpos, dtype=float)
    qpos = qpos[np.all(np.isfinite(qpos), axis=1)]
    data = mujoco.MjData(model)
    with mujoco.viewer.launch_passive(model, data) as viewer:
        for _ in range(loops):
            start = time.perf_counter()
            for t, q in enumerate(qpos):
                if not viewer.is_running():
                    return
                data.qpos[:] = q
                mujoco.mj_forward(model, data)
                viewer.sync()
                delay = start + t / fps - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)
