"""``upm simulate --viewer``: MuJoCo's own viewer, checked once for real under Xvfb (its
framebuffer read back as a screenshot), and its one-line error where there is no display."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest

XVFB = shutil.which("Xvfb")

_PLAY = """
import sys
from controller.qpos import to_qpos
from controller.render import play_in_viewer
from humanoid_xml import catalog_model_path, load_model
from upm.motion.catalog import Catalog
catalog = Catalog(sys.argv[1])
motion = catalog.load("02_01").frames(0, 120)
model = load_model(catalog_model_path(catalog, "02_01"))
play_in_viewer(model, to_qpos(model, motion), motion.fps, loops=100)
"""


def read_xwd(path) -> np.ndarray:
    """An (H, W, 3) uint8 image from an X window dump (Xvfb's ``-fbdir`` framebuffer, 32 bpp)."""
    raw = np.fromfile(path, np.uint8)
    header = raw[:100].view(">u4")
    header_size, width, height = int(header[0]), int(header[4]), int(header[5])
    bits_per_pixel, bytes_per_line, n_colors = int(header[11]), int(header[12]), int(header[19])
    assert bits_per_pixel == 32, f"unexpected XWD depth {bits_per_pixel}"
    start = header_size + 12 * n_colors
    pixels = raw[start:start + height * bytes_per_line].reshape(height, bytes_per_line)
    bgrx = pixels[:, : 4 * width].reshape(height, width, 4)
    return bgrx[..., 2::-1] if int(header[7]) == 0 else bgrx[..., 1:]


def test_viewer_without_display_is_one_line_error(data_dir, tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    done = subprocess.run([sys.executable, "-m", "upm", "simulate", "--viewer",
                           "--data", str(data_dir), "--sequence", "02_01@0:30",
                           "--report", str(tmp_path / "r.json")],
                          env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and "--viewer needs a display" in done.stderr
    assert not (tmp_path / "r.json").exists()


@pytest.mark.skipif(XVFB is None, reason="no Xvfb on this machine (scripts/setup installs "
                    "Debian's xvfb; it could not be installed here)")
def test_viewer_draws_the_humanoid_under_xvfb(data_dir, tmp_path):
    display = f":{90 + os.getpid() % 100}"
    xvfb = subprocess.Popen([XVFB, display, "-screen", "0", "1024x768x24", "-fbdir",
                             str(tmp_path), "-nolisten", "tcp"], stderr=subprocess.DEVNULL)
    env = {**os.environ, "DISPLAY": display, "MUJOCO_GL": "glfw"}
    viewer = None
    try:
        time.sleep(2)
        viewer = subprocess.Popen([sys.executable, "-c", _PLAY, str(data_dir)], env=env,
                                  stderr=subprocess.PIPE)
        rgb = None
        for _ in range(120):  # the viewer needs a few seconds to open on a loaded machine
            time.sleep(1)
            assert viewer.poll() is None, viewer.stderr.read().decode()[-2000:]
            rgb = read_xwd(tmp_path / "Xvfb_screen0")
            if len(np.unique(rgb[::4, ::4].reshape(-1, 3), axis=0)) > 50:
                break
        keep = os.environ.get("UPM_VIEWER_SCREENSHOT")
        if keep:
            import matplotlib.image

            matplotlib.image.imsave(keep, rgb)
        assert len(np.unique(rgb[::4, ::4].reshape(-1, 3), axis=0)) > 50, "viewer drew nothing"
    finally:
        if viewer is not None:
            viewer.kill()
        xvfb.kill()
