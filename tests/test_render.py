"""Offscreen rendering without a GPU (OSMesa): a filmstrip PNG with the window marked, and
short videos in each format."""

import subprocess
from dataclasses import replace

import numpy as np
import pytest
from PIL import Image

from controller import to_qpos
from controller.render import (
    WINDOW_COLOUR,
    filmstrip,
    mark_windows,
    offscreen_gl,
    render_frames,
    side_view,
    write_video,
)
from upm.core.errors import UsageError


@pytest.fixture(scope="module")
def walk_qpos(model02, walk):
    return to_qpos(model02, walk)


def test_offscreen_backend_is_chosen():
    assert offscreen_gl() in ("osmesa", "egl", "glfw")


def test_rendered_frames_show_the_body(model02, walk_qpos):
    images = render_frames(model02, walk_qpos[[0, 60]], width=64, height=96)
    assert images.shape == (2, 96, 64, 3) and images.dtype == np.uint8
    for image in images:
        assert image.std() > 10  # not a blank picture
    # The camera follows the body: it sits near the middle column in both pictures.
    body = np.abs(images.astype(int) - images[:, :1, :1].astype(int)).sum(axis=3) > 60
    for mask in body:
        columns = np.flatnonzero(mask[:60].any(axis=0))  # above the floor's horizon
        assert columns.size and abs(columns.mean() - 32) < 16


def test_side_view_looks_across_the_travel(model02, walk_qpos):
    view = side_view(model02, walk_qpos)
    travel = walk_qpos[-1, :2] - walk_qpos[0, :2]
    heading = np.degrees(np.arctan2(travel[1], travel[0]))
    assert (view.azimuth_deg - heading) % 360 == pytest.approx(90.0)
    assert 2.5 < view.distance_m < 3.5


def test_filmstrip_png_marks_the_window(tmp_path, model02, walk_qpos):
    path = filmstrip(model02, [("walk", walk_qpos)], [100, 110, 120], tmp_path / "strip.png",
                     fps=120.0, windows=[slice(105, 115)], width=60, height=90,
                     title="02_01")
    image = np.asarray(Image.open(path).convert("RGB"))
    assert image.shape[1] >= 3 * 60 * 0.9
    orange = np.all(np.abs(image.astype(int) - WINDOW_COLOUR) < 12, axis=2)
    assert orange.sum() > 100  # the bar under the window frame (and its label)
    assert not list(tmp_path.glob(".tmp-*"))


def test_mark_windows_only_marks_window_frames():
    images = np.zeros((3, 10, 4, 3), dtype=np.uint8)
    marked = mark_windows(images, [False, True, False], thickness=2)
    assert (marked[1, -2:] == WINDOW_COLOUR).all() and not marked[[0, 2]].any()
    assert not images.any()


def test_videos_in_each_format(tmp_path, model02, walk_qpos):
    qpos = walk_qpos[:40]
    mp4 = write_video(model02, qpos, 120.0, tmp_path / "walk.mp4", video_fps=30,
                      width=96, height=64, windows=[slice(10, 20)])
    gif = write_video(model02, qpos, 120.0, tmp_path / "walk.gif", video_fps=30,
                      width=96, height=64)
    assert mp4.read_bytes()[4:8] == b"ftyp"
    import imageio_ffmpeg

    probe = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(mp4),
                            "-f", "null", "-"], capture_output=True, text=True)
    assert probe.returncode == 0, probe.stderr  # ffmpeg decodes every frame
    assert Image.open(gif).n_frames == 10
    with pytest.raises(UsageError, match="unknown video format"):
        write_video(model02, qpos, 120.0, tmp_path / "walk.avi")


def test_viewer_without_a_display_is_a_clear_error(monkeypatch, model02, walk_qpos):
    from controller.render import has_display, play_in_viewer

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")
    assert not has_display()
    with pytest.raises(UsageError, match="needs a display"):
        play_in_viewer(model02, walk_qpos[:5], 120.0)


def test_filmstrip_frames_surround_each_window():
    from controller.render import filmstrip_frames

    frames = filmstrip_frames([slice(100, 120)], 400)
    assert frames == list(range(90, 130, 5))
    assert len(filmstrip_frames([slice(10, 200), slice(250, 390)], 400)) == 16
    assert filmstrip_frames([], 40, limit=8) == list(range(0, 40, 5))
    assert max(filmstrip_frames([slice(380, 400)], 400)) < 400


def _in_forked_child(check) -> int:
    """Run ``check()`` in a forked process (so that OpenGL used there stays there): its exit
    code, 0 when it returned without raising."""
    import multiprocessing

    process = multiprocessing.get_context("fork").Process(target=check)
    process.start()
    process.join(300)
    return process.exitcode


def test_workers_render_the_same_pictures_and_leave_this_process_without_opengl(
        model02, walk_qpos):
    from controller.render_pool import VIDEO, fork_is_safe

    qpos = walk_qpos[:40:4]
    view = side_view(model02, walk_qpos)
    shadow, samples = model02.vis.quality.shadowsize, model02.vis.quality.offsamples
    one = render_frames(model02, qpos, 64, 48, view, settings=VIDEO.with_processes(1))
    two = render_frames(model02, qpos, 64, 48, view,
                        settings=replace(VIDEO, processes=2, min_frames_per_process=1))
    assert one.shape == (10, 48, 64, 3) and one.std() > 10
    assert np.array_equal(one, two)  # split between two processes, the same pixels
    # the model's own settings are left as they were, and this process never rendered
    assert (model02.vis.quality.shadowsize, model02.vis.quality.offsamples) == (shadow, samples)
    assert fork_is_safe()


def test_rendering_here_once_opengl_ran_here(model02, walk_qpos):
    """Where this process has run llvmpipe (its threads), forked workers would hang: the
    frames are rendered here, the same pictures (checked in a child of its own)."""
    from controller.render_pool import VIDEO, fork_is_safe, render_into

    qpos = walk_qpos[:8:4]
    view = side_view(model02, walk_qpos)
    forked = render_frames(model02, qpos, 64, 48, view, settings=VIDEO.with_processes(1))

    def check():
        here = np.zeros_like(forked)
        render_into(here, model02, qpos, qpos[:, :2], view, VIDEO)
        assert not fork_is_safe()  # llvmpipe's threads now run here
        again = render_frames(model02, qpos, 64, 48, view)
        assert np.array_equal(here, forked) and np.array_equal(again, forked)

    assert _in_forked_child(check) == 0


def test_a_worker_that_fails_is_an_error(model02, walk_qpos):
    from controller.render_pool import VIDEO

    with pytest.raises(RuntimeError, match="rendering process failed"):
        render_frames(model02, walk_qpos[:4, :-1], 64, 48, side_view(model02, walk_qpos),
                      settings=VIDEO.with_processes(1))


def test_the_floor_left_out_of_the_shadow_map_changes_no_pixel(model02, walk_qpos,
                                                              monkeypatch):
    from controller import render_pool

    qpos = walk_qpos[:60:20]
    view = side_view(model02, walk_qpos)
    settings = render_pool.VIDEO.with_processes(1)
    left_out = render_frames(model02, qpos, 96, 64, view, settings=settings)
    monkeypatch.setattr(render_pool, "_floor_casts_no_shadow", lambda scene: None)
    drawn = render_frames(model02, qpos, 96, 64, view, settings=settings)
    assert np.array_equal(left_out, drawn)


def test_only_a_floor_lit_from_above_is_left_out_of_the_shadow_map(model02):
    import mujoco

    from controller.render_pool import _floor_casts_no_shadow

    scene = mujoco.MjvScene(model02, maxgeom=100)
    data = mujoco.MjData(model02)
    mujoco.mj_forward(model02, data)
    mujoco.mjv_updateScene(model02, data, mujoco.MjvOption(), None, mujoco.MjvCamera(),
                           mujoco.mjtCatBit.mjCAT_ALL, scene)
    kinds = [scene.geoms[i].type for i in range(scene.ngeom)]
    floor = kinds.index(mujoco.mjtGeom.mjGEOM_PLANE)
    sun = [i for i in range(scene.nlight) if scene.lights[i].castshadow]
    assert sun and scene.geoms[floor].category == mujoco.mjtCatBit.mjCAT_STATIC
    scene.lights[sun[0]].dir[2] = 0.5  # a shadow-casting light from below: the floor stays
    _floor_casts_no_shadow(scene)
    assert scene.geoms[floor].category == mujoco.mjtCatBit.mjCAT_STATIC
    scene.lights[sun[0]].dir[2] = -1.0
    _floor_casts_no_shadow(scene)
    assert scene.geoms[floor].category == mujoco.mjtCatBit.mjCAT_DECOR
    assert all(scene.geoms[i].category != mujoco.mjtCatBit.mjCAT_DECOR
               for i in range(scene.ngeom) if i != floor)
