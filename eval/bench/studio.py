"""The studio: an alpha slider move to the updated scene, through the studio's server-side
API (:meth:`studio.app.Studio.set`, what a browser's slider event runs), on a running viser
server with the ``upm`` method.

``slider_to_scene_ms``: from the move to the new capsule poses and tints sent to the page
(recomputed transition, forward kinematics and kinematic checks of every frame);
``slider_to_scene_and_curve_ms`` until the Fig. 13 image (drawn by a thread of its own,
after the scene) shows it too. The reference,
timed interleaved (alternating rounds, medians), is ``mj_kinematics`` on every frame of
the scene: a fixed piece of library work of the scene's size.
"""

from __future__ import annotations

import contextlib
import socket
import statistics
import sys
import time

from eval.bench import BenchContext, target

NAME = "studio"

#: Clip 1 up to frame A, clip 2 from frame B: the studio's default pair.
PAIR = ("02_01", 200, "02_03", 20)
ALPHAS = (0.2, 0.8)
#: Issue 13's target for a slider move to the updated scene.
TARGET_MS = 50.0


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def run(context: BenchContext) -> dict:
    try:
        import viser  # noqa: F401
    except ImportError:
        return {"skipped": "viser is not installed (pip install 'upm-controller[studio]')"}
    from studio.app import Studio
    from studio.session import Session
    from upm.motion.catalog import Catalog
    from upm.transitions import KeySourceContext, build_key_source

    catalog = Catalog(context.data_dir)
    clip1, a_frame, clip2, b_frame = PAIR
    sources = {"upm": build_key_source("upm", KeySourceContext(
        catalog=catalog, train_maps=True, train_step=8 if context.quick else 1))}
    session = Session(catalog, clip1, clip2, key_sources=sources)
    session.a_frame, session.b_frame, session.method = a_frame, b_frame, "upm"
    # viser prints its banner on stdout, which carries the bench's JSON.
    with contextlib.redirect_stdout(sys.stderr):
        return _measure(Studio(session, port=_free_port()), clip1, a_frame, clip2, b_frame,
                        context.quick)


def _measure(studio, clip1: str, a_frame: int, clip2: str, b_frame: int,
             quick: bool) -> dict:
    import mujoco

    from controller.qpos import to_qpos

    try:
        studio.playing.value = False
        studio.set(alpha=ALPHAS[0])  # sources, caches and the first figure outside the timing
        studio.wait_for_curve()
        model = studio.scene.model
        data = mujoco.MjData(model)
        qpos = to_qpos(model, studio.scene.result.motion)

        def reference() -> float:
            start = time.perf_counter()
            for q in qpos:
                data.qpos[:] = q
                mujoco.mj_kinematics(model, data)
            return time.perf_counter() - start

        reference()
        rounds = 4 if quick else 15
        scene_s, total_s, reference_s = [], [], []
        for i in range(rounds):
            if i % 2:
                reference_s.append(reference())
            start = time.perf_counter()
            studio.set(alpha=ALPHAS[(i + 1) % 2])
            studio.wait_for_curve()
            total_s.append(time.perf_counter() - start)
            scene_s.append(studio.last_update_s)
            if not i % 2:
                reference_s.append(reference())
        frames = studio.scene.geom_pos_m.shape[0]
        window = studio.scene.result.window
    finally:
        studio.stop()
    ratios = [s / r for s, r in zip(scene_s, reference_s, strict=True)]
    return {
        "targets": {"slider_to_scene_ms": target(1e3 * statistics.median(scene_s),
                                                 TARGET_MS)},
        "pair": f"{clip1}@{a_frame}->{clip2}@{b_frame}",
        "method": "upm",
        "scene_frames": frames,
        "window_frames": window.stop - window.start,
        "slider_to_scene_ms": 1e3 * statistics.median(scene_s),
        "slider_to_scene_and_curve_ms": 1e3 * statistics.median(total_s),
        "reference_mj_kinematics_scene_ms": 1e3 * statistics.median(reference_s),
        "slider_to_scene_ratio_to_reference": statistics.median(ratios),
        "slider_to_scene_ratio_range": [min(ratios), max(ratios)],
        "timing": f"medians of {rounds} slider moves (alpha {ALPHAS[0]} <-> {ALPHAS[1]}), "
                  "each interleaved with the reference",
    }
