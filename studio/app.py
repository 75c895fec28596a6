"""The studio's web page: viser (a three.js client served from Python, no front-end build).

The humanoid's capsules play clip 1 -> window -> clip 2 in a loop; the GUI changes clips,
frames, method, alpha and window length, and every change recomputes at once.

What a page can make the studio do is bounded: its websocket lets in only the studio's
own page (:mod:`studio.origin`), exports go into one folder and never overwrite
(:mod:`studio.exports`), and one physics check runs at a time.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from studio.exports import ExportFolder, ExportRefused
from studio.ghost import PerformedGhost
from studio.origin import OriginGuard, guarded_viser
from studio.session import Scene, Session, capsule_geoms, method_names

VALID_RGB = (170, 180, 200)
INVALID_RGB = (220, 60, 50)
GHOST_RGB = (90, 160, 90)
#: The physics-check figures shown in the page (the full report: ``upm simulate``).
REPORT_COLUMNS = ("part", "valid_pct", "limit_violation_pct", "self_collision_frames",
                  "floor_penetration_frames", "added_limit_violation_frames",
                  "residual_force_bw_peak", "residual_torque_bwh_peak", "driven_fell",
                  "driven_error_deg_rms", "driven_torque_peak_nm")


def _strip_rgb(valid, window: slice, height: int = 12) -> np.ndarray:
    """A (height, T, 3) uint8 image: green valid / red invalid frames, the window darker."""
    row = np.where(np.asarray(valid)[:, None], [60, 170, 80], [210, 50, 40]).astype(np.uint8)
    img = np.repeat(row[None], height, axis=0)
    img[: height // 3, window] = (40, 40, 40)
    return img


class Studio:
    """A running studio: a viser server drawing a :class:`~studio.session.Session`.

    Parameters
    ----------
    session : studio.session.Session
    host, port : str, int
        Where to serve (a taken port: the next free one, :attr:`port`).
    out : path
        The export folder (:class:`studio.exports.ExportFolder`).
    allow_origins : sequence of str
        Origins besides the studio's own page whose websockets are let in (normalised,
        :func:`studio.origin.parse_allowed`).
    """

    def __init__(self, session: Session, host: str = "127.0.0.1", port: int = 8080, *,
                 out="studio-exports", allow_origins=()):
        import viser

        self.session = session
        self.guard = OriginGuard(host, allow_origins)
        with guarded_viser(self.guard):
            self.server = viser.ViserServer(host=host, port=port, verbose=False)
        if not self.guard.installed:
            self.server.stop()
            raise RuntimeError("the studio could not put its websocket Origin check on this "
                               "viser version (it starts its server another way): refusing "
                               "to run unguarded")
        self.port = self.server.get_port()
        self.exports = ExportFolder(out)
        self._checking = threading.Lock()
        self.lock = threading.Lock()
        self._holding = False
        self._capsules, self._ghosts = [], []
        self.humanoid_model = None
        self._build_humanoid(session.model)
        self.server.scene.add_grid("/floor", width=8.0, height=8.0, plane="xy")
        gui = self.server.gui
        clips = session.catalog.names() if hasattr(session.catalog, "names") else [
            session.clip1, session.clip2]
        self.clip1 = gui.add_dropdown("clip 1", clips, initial_value=session.clip1)
        self.a_frame = gui.add_number("clip 1 ends at frame", session.a_frame, min=0, step=1)
        self.clip2 = gui.add_dropdown("clip 2", clips, initial_value=session.clip2)
        self.b_frame = gui.add_number("clip 2 starts at frame", session.b_frame, min=0, step=1)
        methods = method_names()
        self.method = gui.add_dropdown("method", methods, initial_value=session.method)
        self.compare = gui.add_dropdown("ghost method", ["(none)", *methods],
                                        initial_value="(none)")
        self.follow = gui.add_dropdown("performed follows",
                                       [m for m in methods if m != "performed"],
                                       initial_value=session.follow)
        self.performed_ghost = gui.add_checkbox("ghost: performed beside asked", False)
        self.ghost_note = gui.add_markdown("")
        self.performer = PerformedGhost(self.ghost_note, self.refresh)
        self.alpha = gui.add_slider("alpha", 0.0, 1.0, 0.01, session.alpha)
        self.frames = gui.add_slider("window frames", 2, 120, 1, session.frames)
        self.playing = gui.add_checkbox("play", True)
        self.frame = gui.add_slider("frame", 0, 1, 1, 0)
        self.status = gui.add_markdown("")
        self.strip = gui.add_image(np.zeros((12, 2, 3), np.uint8), label="valid frames")
        self.dof = gui.add_text("Fig. 13 DOF", "rhumerus.rz")
        self.curve = gui.add_image(np.full((8, 8, 3), 255, np.uint8), label="DOF vs linear")
        self.amc_path = gui.add_text("export name (.amc or .bvh)", "transition.amc")
        export = gui.add_button("export AMC / BVH")
        export.on_click(lambda _: self.export())
        check = gui.add_button("physics check (upm simulate)")
        check.on_click(lambda _: self.start_check())
        self.report = gui.add_markdown("")
        self.dof.on_update(lambda _: self.apply_gui())
        for handle in (self.clip1, self.a_frame, self.clip2, self.b_frame, self.method,
                       self.compare, self.alpha, self.frames, self.follow,
                       self.performed_ghost):
            handle.on_update(lambda _: self.apply_gui())
        self.frame.on_update(lambda _: self.show_frame(int(self.frame.value)))
        self.scene: Scene | None = None
        self.ghost: Scene | None = None
        self.last_update_s = float("nan")
        # The Fig. 13 image (about 0.1 s of matplotlib) is drawn by a thread of its own
        # from the latest transition, so that a dragged slider moves the humanoid at the
        # scene's pace and the image catches up with the last position.
        self._curve_job = None
        self._drawing = False
        self._stopped = False
        self._curve_ready = threading.Condition()
        threading.Thread(target=self._curve_worker, daemon=True).start()
        self.apply_gui()
        self.frame_camera()

    def frame_camera(self) -> None:
        """Point the initial view at the motion and come close enough that it fills the
        view: the larger of the body's height (with a margin) and the ground it covers."""
        import math

        pos = self.scene.geom_pos_m.reshape(-1, 3)
        low, high = pos.min(axis=0), pos.max(axis=0)
        centre = (low + high) / 2.0
        extent = max(1.3 * float(high[2] - low[2]), float(max(high[:2] - low[:2])))
        fov = float(getattr(self.server.initial_camera, "fov", 1.3) or 1.3)
        distance = 1.15 * extent / 2.0 / math.tan(fov / 2.0)
        direction = np.array([1.0, -1.0, 0.35]) / np.linalg.norm([1.0, -1.0, 0.35])
        self.server.initial_camera.look_at = tuple(float(v) for v in centre)
        self.server.initial_camera.position = tuple(float(v) for v in centre
                                                    + distance * direction)

    def _build_humanoid(self, model) -> None:
        """Capsule meshes of ``model`` (and their ghosts) in the scene, replacing any drawn
        before: the studio draws clip 1's subject, whose bone lengths and girths differ."""
        import trimesh

        for handle in self._capsules + self._ghosts:
            handle.remove()
        self._capsules, self._ghosts = [], []
        for gid in capsule_geoms(model):
            radius_m, half_m = model.geom_size[gid, :2]
            mesh = trimesh.creation.capsule(height=2 * half_m, radius=radius_m, count=[8, 8])
            self._capsules.append(self.server.scene.add_mesh_simple(
                f"/body/g{gid}", mesh.vertices, mesh.faces, color=VALID_RGB))
            self._ghosts.append(self.server.scene.add_mesh_simple(
                f"/ghost/g{gid}", mesh.vertices, mesh.faces, color=GHOST_RGB, opacity=0.35,
                visible=False))
        self.humanoid_model = model

    def set(self, **values) -> Scene:
        """Set controls by name (``alpha=0.9``, ``method="snap"``...) and recompute.

        The server-side API: tests and scripts drive the page through it, and every
        connected browser sees the same controls move.
        """
        # Assigning a value runs its handle's callbacks at once: held back here so that
        # the scene is recomputed once for all the values, not once per value.
        self._holding = True
        try:
            for name, value in values.items():
                getattr(self, name).value = value
        finally:
            self._holding = False
        self.apply_gui()
        return self.scene

    def apply_gui(self) -> None:
        """Copy the GUI's values into the session and recompute (what every control calls)."""
        if self._holding:
            return
        s = self.session
        s.clip1, s.clip2 = self.clip1.value, self.clip2.value
        s.a_frame, s.b_frame = int(self.a_frame.value), int(self.b_frame.value)
        s.method, s.alpha, s.frames = self.method.value, float(self.alpha.value), int(
            self.frames.value)
        s.compare_method = None if self.compare.value == "(none)" else self.compare.value
        s.follow, s.performed_ghost = self.follow.value, bool(self.performed_ghost.value)
        self.refresh()

    def refresh(self) -> None:
        """Recompute the transition (and the ghost) and redraw the current frame; a
        performed window not made yet is asked of :attr:`performer` (off this thread), and
        the asked one is drawn until it is done."""
        start = time.perf_counter()
        with self.lock:
            try:
                scene, ghost, note = self.performer.scenes(self.session)
                self.ghost_note.content = note
                linear = (scene.result if scene.result.method == "linear"
                          else self.session.transition("linear"))
            except Exception as error:  # shown in the page, the server keeps running
                self.status.content = f"**error:** {error}"
                return
            if scene.model is not self.humanoid_model:  # clip 1 changed subject
                self._build_humanoid(scene.model)
            self.scene, self.ghost = scene, ghost
            n = scene.geom_pos_m.shape[0]
            self.frame.max = n - 1
            w = scene.result.window
            self.strip.image = _strip_rgb(scene.valid, w)
            self.status.content = (
                f"{scene.result.method}, alpha {self.session.alpha:.2f}: window frames "
                f"{w.start}-{w.stop - 1}, {int(scene.valid[w].sum())}/{w.stop - w.start} "
                f"valid; recomputed in {1e3 * scene.seconds:.0f} ms")
        self.show_frame(min(int(self.frame.value), n - 1))
        self.last_update_s = time.perf_counter() - start
        with self._curve_ready:  # the latest transition replaces any not drawn yet
            self._curve_job = (scene.result, linear, self.dof.value or None)
            self._curve_ready.notify_all()

    def _curve_worker(self) -> None:
        while True:
            with self._curve_ready:
                self._curve_ready.wait_for(lambda: self._curve_job is not None or self._stopped)
                if self._stopped:
                    return
                job, self._curve_job, self._drawing = self._curve_job, None, True
            try:
                self._draw_curve(*job)
            finally:
                with self._curve_ready:
                    self._drawing = False
                    self._curve_ready.notify_all()

    def wait_for_curve(self, timeout: float | None = None) -> bool:
        """Wait until the Fig. 13 image shows the latest transition; False on timeout."""
        with self._curve_ready:
            return self._curve_ready.wait_for(
                lambda: self._curve_job is None and not self._drawing, timeout)

    def _draw_curve(self, result, linear, dof: str | None) -> None:
        """The Fig. 13 image of ``result`` against ``linear`` (the same clips and window)."""
        import tempfile
        from pathlib import Path

        import matplotlib.image

        from studio.session import dof_curve_png

        try:
            with tempfile.TemporaryDirectory() as tmp:
                png = Path(tmp) / "dof.png"
                dof_curve_png(result, linear, png, dof)
                rgb = matplotlib.image.imread(png)[..., :3]
            self.curve.image = (rgb * 255).round().astype(np.uint8)
        except Exception as error:  # a bad DOF name: say so in the page
            self.status.content += f"  \n**Fig. 13:** {error}"

    def export(self) -> str | None:
        """Write the current transition as AMC or BVH (by the extension of the export
        name) into the export folder; the path written, or None for a refused name (the
        page says why)."""
        from studio.session import export_amc

        result = self.scene.result
        try:
            path = self.exports.write(self.amc_path.value, lambda tmp: export_amc(result, tmp))
        except ExportRefused as refused:
            self.report.content = f"**export refused:** {refused}"
            return None
        self.report.content = f"wrote {path.name} in {path.parent}"
        return str(path)

    def start_check(self) -> bool:
        """The button's action: the physics check in a thread of its own, unless one is
        running (then the page says the click is ignored). Whether a check started."""
        if not self._checking.acquire(blocking=False):
            self._busy()
            return False
        threading.Thread(target=self._check_held, daemon=True).start()
        return True

    def _busy(self) -> None:
        self.report.content = ("**a physics check is already running:** this click is "
                               "ignored; wait for its figures")

    def _check_held(self) -> None:
        try:
            self._run_check()
        except Exception as error:  # shown in the page, the server keeps running
            self.report.content = f"**physics check failed:** {error}"
        finally:
            self._checking.release()

    def check(self) -> list[dict] | None:
        """Run the physics check of the current transition here and show its summary; None
        (and a message in the page) if a check is running already."""
        if not self._checking.acquire(blocking=False):
            self._busy()
            return None
        try:
            return self._run_check()
        finally:
            self._checking.release()

    def _run_check(self) -> list[dict]:
        from studio import session as studio_session

        self.report.content = "physics check running..."
        rows = studio_session.physics_check(self.scene.model, self.scene.result)
        lines = []
        for row in rows:
            cells = ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                              for k, v in row.items() if k in REPORT_COLUMNS)
            lines.append(f"- {cells}")
        self.report.content = "\n".join(lines)
        return rows

    def show_frame(self, t: int) -> None:
        """Pose the capsules at frame ``t``; the bodies that break a check are red."""
        scene, ghost = self.scene, self.ghost
        if scene is None:
            return
        bad = scene.offending[t]
        with self.server.atomic():
            for g, handle in enumerate(self._capsules):
                handle.position = scene.geom_pos_m[t, g]
                handle.wxyz = scene.geom_wxyz[t, g]
                handle.color = INVALID_RGB if bad[g] else VALID_RGB
            for g, handle in enumerate(self._ghosts):
                handle.visible = ghost is not None
                if ghost is not None:
                    tg = min(t, ghost.geom_pos_m.shape[0] - 1)
                    handle.position = ghost.geom_pos_m[tg, g]
                    handle.wxyz = ghost.geom_wxyz[tg, g]

    def play_forever(self) -> None:
        """Loop the motion at its frame rate while "play" is ticked."""
        while True:
            scene = self.scene
            fps = scene.result.motion.fps if scene is not None else 30.0
            time.sleep(1.0 / fps)
            if scene is not None and self.playing.value:
                t = (int(self.frame.value) + 1) % scene.geom_pos_m.shape[0]
                self.frame.value = t

    def stop(self) -> None:
        """Shut the web server (and the Fig. 13 thread) down; a performance under way
        finishes in its thread and draws nothing."""
        self.performer.closed = True
        with self._curve_ready:
            self._stopped = True
            self._curve_ready.notify_all()
            # an image under way is written to the page: it ends before the server goes
            self._curve_ready.wait_for(lambda: not self._drawing, timeout=10.0)
        self.server.stop()
