"""The studio's ``performed`` method and its ghost (studio.ghost): the session performs the
asked window on the humanoid, the page draws it off the UI thread, and the ghost holds the
followed method's frames; on the real clips 02_01 -> 02_03, with a small search."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("viser", reason="upm studio needs viser (the dev extra installs it)")

from tests.test_studio import CHROMIUM, _chromium, _free_port, _wait_for_shot  # noqa: E402


def _small():
    from controller.config import DEFAULT

    return DEFAULT.updated({"offline": {"samples": 32, "keep": 4}})


def _session(catalog):
    from studio.session import Session

    s = Session(catalog, "02_01", "02_03", performer_config=_small())
    s.a_frame, s.b_frame, s.frames = 200, 20, 20  # mid-walk to mid-walk, as the study
    return s


@pytest.mark.physics
def test_the_session_performs_the_asked_window(catalog):
    """performed follows linear: the performed window is the humanoid's own (it differs
    from the asked one), the asked scene is linear's, and the run starts from the clip's
    own state (clip 1's frames before the run are untouched)."""
    session = _session(catalog)
    session.method, session.follow = "performed", "linear"
    assert session.asked_method() == "linear" and session.performed_scene() is None
    done = session.perform()
    assert session.performed_scene() is done
    asked = session.recompute("linear")
    linear = session.transition("linear")
    assert done.result.method == "performed"
    np.testing.assert_allclose(asked.result.motion.posture_deg, linear.motion.posture_deg)
    w = done.result.window
    assert done.geom_pos_m.shape == asked.geom_pos_m.shape
    # the body did not do exactly what it was asked, but stayed near it
    gap = np.linalg.norm(done.geom_pos_m[w] - asked.geom_pos_m[w], axis=-1)
    assert gap.max() > 0.005 and np.median(gap) < 0.3
    d = done.result.diagnostics
    assert d["performed_fell"] == 0 and d["performed_joint_error_deg"] < 10
    first = w.start - round(d["performed_context_before_s"] * done.result.motion.fps)
    np.testing.assert_allclose(done.geom_pos_m[:first], asked.geom_pos_m[:first])
    # the same settings are not performed twice; another method asks for another window
    assert session.perform() is done
    session.method, session.performed_ghost = "slerp", True
    assert session.asked_method() == "slerp" and session.performed_scene() is None


@pytest.mark.physics
def test_the_page_performs_off_the_ui_thread_and_ghosts_the_asked_window(catalog, tmp_path):
    """Choosing performed answers at once with the asked window and a status line; the
    worker then draws the performed window solid and, with the ghost ticked, the
    followed method's frames as the ghost; with another method the ghost swaps."""
    from studio.app import Studio
    from studio.ghost import finding

    session = _session(catalog)
    studio = Studio(session, port=_free_port(), out=tmp_path / "exports")
    try:
        studio.playing.value = False
        scene = studio.set(method="performed", follow="linear", performed_ghost=True)
        assert scene.result.method == "linear"  # the asked window, until it is performed
        assert "performing" in studio.ghost_note.content
        assert studio.performer.wait(timeout=600)
        assert studio.scene.result.method == "performed"
        asked = session.recompute("linear")
        np.testing.assert_allclose(studio.ghost.geom_pos_m, asked.geom_pos_m)
        note = studio.ghost_note.content
        assert "solid: **performed**" in note and "translucent green: **asked** (linear" in note
        assert finding(studio.scene.result, "linear") in note
        studio.show_frame(studio.scene.result.window.start + 5)
        assert all(h.visible for h in studio._ghosts)
        # vice versa: linear solid, the performed window (already made) as the ghost
        scene = studio.set(method="linear")
        assert scene.result.method == "linear" and studio.ghost.result.method == "performed"
        assert "solid: **asked** (linear" in studio.ghost_note.content
        # the ghost off: no performed body, no note
        studio.set(performed_ghost=False)
        assert studio.ghost is None and studio.ghost_note.content == ""
    finally:
        studio.stop()


def test_a_window_the_body_cannot_keep_is_a_finding():
    """The page's words for a fall in the window and for leaving it: findings, not errors."""
    from types import SimpleNamespace

    from studio.ghost import finding

    fell = SimpleNamespace(diagnostics={"performed_fell_in_window": 1.0,
                                        "performed_left_window": 1.0})
    left = SimpleNamespace(diagnostics={"performed_left_window": 1.0})
    kept = SimpleNamespace(diagnostics={"performed_joint_error_deg": 3.0})
    assert finding(fell, "feasible").startswith("**finding:** the body cannot perform "
                                                "feasible's window: it fell")
    assert "left it to stay up" in finding(left, "feasible")
    assert "error" not in finding(kept, "linear").split("\n")[0]
    assert "without falling" in finding(kept, "linear")


def _ghost_pixels(rgb: np.ndarray) -> int:
    """Pixels of the 3D view (left of the GUI panel) green enough to be the ghost (its
    translucent green over the grey body or the background)."""
    view = rgb[:, :900].astype(int)
    return int(((view[..., 1] - np.maximum(view[..., 0], view[..., 2])) > 25).sum())


@pytest.mark.browser
def test_the_page_shows_the_ghost_and_says_which_is_which(catalog, tmp_path):
    """The real page in headless Chromium: ticking the ghost draws a second, green body in
    the 3D view, and the panel says which body is the performed window and which the
    asked one."""
    from studio.app import Studio

    if CHROMIUM is None:
        pytest.skip("no chromium on this machine (scripts/setup installs Debian's)")
    session = _session(catalog)
    studio = Studio(session, port=_free_port(), out=tmp_path / "exports")
    try:
        studio.playing.value = False
        studio.set(method="performed", follow="linear")
        assert studio.performer.wait(timeout=600)
        studio.set(frame=studio.scene.result.window.stop - 1)
        with _chromium() as browser:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.goto(f"http://127.0.0.1:{studio.port}/", timeout=240_000)
            page.wait_for_function("document.body.innerText.includes('solid: performed')",
                                   timeout=240_000)
            alone = _wait_for_shot(page, tmp_path / "a.png", lambda rgb: True)
            studio.set(performed_ghost=True)
            both = _wait_for_shot(page, tmp_path / "b.png",
                                  lambda rgb: _ghost_pixels(rgb) > _ghost_pixels(alone) + 300)
            page.wait_for_function("document.body.innerText.includes('translucent green: "
                                   "asked (linear')", timeout=60_000)
    finally:
        studio.stop()
    assert _ghost_pixels(both) > _ghost_pixels(alone) + 300, "no ghost in the 3D view"
