"""``upm studio``: the session recomputes on every change, and the real page shows it in
headless Chromium (Debian's ``chromium``, driven by Playwright)."""

from __future__ import annotations

import contextlib
import os
import shutil

import numpy as np
import pytest

pytest.importorskip("viser", reason="upm studio needs viser (the dev extra installs it)")

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture(scope="module")
def session(catalog):
    from studio.session import Session

    s = Session(catalog, "02_01", "02_03")
    s.method = "snap"
    return s


def test_every_registered_method_is_offered():
    from studio.session import method_names
    from upm.transitions import METHODS

    assert method_names() == list(METHODS)


def test_only_the_offending_bodies_are_tinted(session, catalog):
    """On 05_11 (a dance whose frames break limits) the tint marks some capsules, not the
    whole figure; a frame is invalid exactly when at least one capsule is marked."""
    from studio.session import Session

    dance = Session(catalog, "05_11", "02_03")
    dance.method = "linear"
    scene = dance.recompute()
    marked = scene.offending.sum(axis=1)
    assert scene.offending.shape == scene.geom_pos_m.shape[:2]
    np.testing.assert_array_equal(marked > 0, ~scene.valid)
    assert (~scene.valid).any()
    assert (marked[~scene.valid] < scene.offending.shape[1]).all()


def test_alpha_reshapes_the_window_and_poses_follow(session):
    session.alpha = 0.1
    low = session.recompute()
    session.alpha = 0.9
    high = session.recompute()
    w = low.result.window
    assert high.result.alpha == 0.9 and low.result.alpha == 0.1
    # the key posture moves from near clip 1's end towards clip 2's start
    assert np.abs(high.result.window_posture_deg - low.result.window_posture_deg).max() > 5.0
    # clip frames are untouched, the window's capsules move
    np.testing.assert_allclose(low.geom_pos_m[: w.start], high.geom_pos_m[: w.start])
    assert np.abs(low.geom_pos_m[w] - high.geom_pos_m[w]).max() > 0.01
    n = low.result.motion.n_frames
    assert low.geom_pos_m.shape[:1] == (n,) and low.geom_wxyz.shape[:1] == (n,)
    np.testing.assert_allclose(np.linalg.norm(low.geom_wxyz, axis=-1), 1.0, atol=1e-9)
    assert low.valid.shape == (n,)


@contextlib.contextmanager
def _chromium():
    """Headless Chromium (Debian's) driven by Playwright, so the test waits for what it
    needs to see instead of guessing a load time: a one-shot ``--screenshot`` with a
    virtual-time budget captured a blank page on a loaded CI machine. Closed on exit."""
    from playwright.sync_api import sync_playwright

    driver = sync_playwright().start()
    try:
        browser = driver.chromium.launch(
            executable_path=CHROMIUM,
            args=["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync", "--use-gl=swiftshader", "--enable-unsafe-swiftshader"])
        try:
            yield browser
        finally:
            browser.close()
    finally:
        driver.stop()


def _wait_for_shot(page, path, done, timeout_s=240.0) -> np.ndarray:
    """Screenshots of ``page`` until ``done(rgb)`` holds; the last one is kept at ``path``.

    Returns the (H, W, 3) integer RGB of the last screenshot. Slow on a loaded machine
    (software WebGL), hence the generous real-time ``timeout_s``; the screenshot is asserted
    on afterwards, so a page that never renders fails the test."""
    import time

    import matplotlib.image

    deadline = time.monotonic() + timeout_s
    while True:
        page.screenshot(path=str(path), timeout=timeout_s * 1000)
        rgb = (matplotlib.image.imread(path)[..., :3] * 255).round().astype(int)
        if done(rgb) or time.monotonic() > deadline:
            return rgb
        page.wait_for_timeout(500)


def _figure_pixels(rgb: np.ndarray) -> int:
    """Pixels of the 3D view (left of the GUI panel) in the body's valid or invalid tint."""
    from studio.app import INVALID_RGB, VALID_RGB

    view = rgb[:, :900]
    count = 0
    for tint in (VALID_RGB, INVALID_RGB):  # lit surfaces: same hue, shaded brightness
        t = np.array(tint, float)
        shade = (view @ t) / (t @ t)
        near = np.linalg.norm(view - shade[..., None] * t, axis=-1) < 12
        count += int((near & (shade > 0.4) & (shade < 1.2)).sum())
    return count


@pytest.mark.browser
@pytest.mark.skipif(CHROMIUM is None, reason="no chromium on this machine (scripts/setup "
                    "installs Debian's chromium; none could be installed here)")
def test_page_in_headless_chromium_follows_alpha(session, tmp_path):
    """The real page: the humanoid appears in the 3D view, the Fig. 13 image in the panel,
    and moving alpha through the server's API moves the humanoid on the page."""
    from studio.app import Studio

    studio = Studio(session, port=_free_port())
    messages = []
    try:
        # Paused, so that the only change on the page is the one alpha makes.
        studio.playing.value = False
        first = studio.set(alpha=0.1, frame=studio.scene.result.window.start + 10)
        first_pos_m = first.geom_pos_m[int(studio.frame.value)]
        with _chromium() as browser:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.on("pageerror", lambda error: messages.append(f"page error: {error}"))
            page.on("console", lambda message: messages.append(message.text))
            page.goto(f"http://127.0.0.1:{studio.port}/", timeout=240_000)
            low = _wait_for_shot(page, tmp_path / "a.png", lambda rgb: _figure_pixels(rgb) > 500)
            assert _figure_pixels(low) > 500, f"no humanoid in the 3D view; page said {messages}"
            second = studio.set(alpha=0.9)
            high = _wait_for_shot(page, tmp_path / "b.png",
                                  lambda rgb: _view_pixels_changed(low, rgb) > 300)
            assert studio.wait_for_curve(timeout=300)
            curve_h, curve_w = np.asarray(studio.curve.image).shape[:2]
            shown = page.evaluate("Array.from(document.images, i => [i.naturalWidth, "
                                  "i.naturalHeight])")
    finally:
        studio.stop()
    assert first.result.alpha == 0.1 and second.result.alpha == 0.9
    assert np.abs(first.result.window_posture_deg
                  - second.result.window_posture_deg).max() > 5.0
    # the pose the page is sent moved with alpha, and the page drew it
    assert np.abs(second.geom_pos_m[int(studio.frame.value)] - first_pos_m).max() > 0.01
    assert len(np.unique(high.reshape(-1, 3), axis=0)) > 50, "blank page"
    assert _figure_pixels(high) > 500, f"no humanoid in the 3D view; page said {messages}"
    assert _view_pixels_changed(low, high) > 300, "the humanoid did not move with alpha"
    assert [curve_w, curve_h] in shown, f"no Fig. 13 image on the page (images: {shown})"
    keep = os.environ.get("UPM_STUDIO_SCREENSHOT")  # README figure: docs/figures/studio.png
    if keep:
        shutil.copyfile(tmp_path / "b.png", keep)


def _view_pixels_changed(before: np.ndarray, after: np.ndarray) -> int:
    """Pixels of the 3D view (left of the GUI panel) that changed between two screenshots."""
    return int((np.abs(after[:, :900] - before[:, :900]).sum(axis=-1) > 30).sum())


def _free_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_export_and_physics_check_of_the_window(session, tmp_path):
    from studio.session import export_amc, physics_check
    from upm.motion.amc import read_amc

    result = session.transition()
    path = export_amc(result, tmp_path / "t.amc")
    back = read_amc(path, result.motion.skeleton)
    assert back.n_frames == result.motion.n_frames
    np.testing.assert_allclose(back.posture_deg, result.motion.posture_deg, atol=1e-3)
    rows = physics_check(session.model, result)
    window = next(r for r in rows if r["part"] == "window 0")
    assert (window["start"], window["stop"]) == (result.window.start, result.window.stop)
    assert window["method"] == result.method and "driven_error_deg_rms" in window


def test_fig13_curve_is_drawn(session, tmp_path):
    import matplotlib.image

    from studio.session import dof_curve_png

    result = session.transition()
    linear = session.transition("linear")
    assert dof_curve_png(result, linear, tmp_path / "c.png", "rhumerus.rz") == "rhumerus.rz"
    rgb = matplotlib.image.imread(tmp_path / "c.png")[..., :3]
    assert rgb.std() > 0.05


def test_clip_1_of_another_subject_rebuilds_the_humanoid(catalog):
    """02_01 -> 05_11 as clip 1: the page's capsules become subject 05's (built from its
    MJCF) and the poses are those of a studio opened on 05_11."""
    from humanoid_xml import catalog_model_path, load_model
    from studio.app import Studio
    from studio.session import Session, capsule_geoms

    studio = Studio(Session(catalog, "02_01", "02_03"), port=_free_port())
    try:
        first = studio.scene
        calls = []
        recompute = studio.session.recompute
        studio.session.recompute = lambda *a: calls.append(a) or recompute(*a)
        second = studio.set(clip1="05_11", a_frame=100)
        assert len(calls) == 1, "set() recomputes once for all its values"
        capsules = [np.asarray(h.vertices) for h in studio._capsules]
    finally:
        studio.stop()
    expected = load_model(catalog_model_path(catalog, "05_11"))
    assert not np.allclose(first.model.geom_size, expected.geom_size)
    np.testing.assert_array_equal(second.model.geom_size, expected.geom_size)
    # each capsule mesh (long axis z) spans its geom's half-length plus radius
    gids = capsule_geoms(expected)
    assert len(capsules) == len(gids)
    for vertices, gid in zip(capsules, gids, strict=True):
        assert vertices[:, 2].max() == pytest.approx(expected.geom_size[gid, :2].sum(), rel=1e-6)
    fresh = Session(catalog, "05_11", "02_03")
    fresh.a_frame = 100
    np.testing.assert_allclose(second.geom_pos_m, fresh.recompute().geom_pos_m, atol=1e-12)


def test_fig13_image_is_drawn_from_the_latest_move(session, tmp_path):
    """The Fig. 13 image is drawn by its own thread after the scene: after several quick
    slider moves it shows the last transition, exactly as drawn directly."""
    import matplotlib.image

    from studio.app import Studio
    from studio.session import dof_curve_png

    studio = Studio(session, port=_free_port())
    try:
        studio.playing.value = False
        for alpha in (0.2, 0.4, 0.85):
            scene = studio.set(alpha=alpha)
        assert studio.wait_for_curve(timeout=300)
        shown = np.array(studio.curve.image)
        dof = studio.dof.value
    finally:
        studio.stop()
    assert scene.result.alpha == 0.85
    dof_curve_png(scene.result, session.transition("linear"), tmp_path / "c.png", dof)
    expected = (matplotlib.image.imread(tmp_path / "c.png")[..., :3] * 255).round()
    np.testing.assert_array_equal(shown, expected.astype(np.uint8))


def test_stopping_while_the_image_is_drawn_writes_nothing_to_a_closed_page(session):
    """stop() waits for a Fig. 13 image under way: it would otherwise be written to the
    page after the server has gone (viser warns of a message queued on a closed
    connection)."""
    import time
    import warnings

    from studio.app import Studio

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        studio = Studio(session, port=_free_port())
        studio.set(alpha=0.3)  # queues an image; its drawing takes about 0.1 s
        time.sleep(0.02)
        studio.stop()
        time.sleep(0.5)  # a drawing stop() did not wait for ends here
    assert not [w for w in caught if "closed connection" in str(w.message)]


@pytest.fixture(scope="module")
def guarded_studio(session, tmp_path_factory):
    """A running studio that also lets in one extra origin, exporting to a folder of its
    own (not named like a package: ``studio`` would shadow the package in the tests)."""
    from studio.app import Studio

    exports = tmp_path_factory.mktemp("box") / "exports"
    running = Studio(session, port=_free_port(), out=exports,
                     allow_origins=("http://tools.example:9000",))
    running.playing.value = False
    yield running
    running.stop()


def _viser_subprotocol() -> str:
    import viser

    return f"viser-v{viser.__version__}"


def _raw_handshake(port: int, origin: str) -> bytes:
    """A websocket handshake with ``Origin: origin`` over a plain socket: every byte the
    server sends until it closes the connection (or 3 s pass)."""
    import base64
    import socket

    key = base64.b64encode(os.urandom(16)).decode()
    request = (f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
               f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
               f"Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: {_viser_subprotocol()}"
               f"\r\nOrigin: {origin}\r\n\r\n")
    received = b""
    with socket.create_connection(("127.0.0.1", port), timeout=3) as sock:
        sock.sendall(request.encode())
        try:
            while chunk := sock.recv(65536):
                received += chunk
        except TimeoutError:
            pass
    return received


def test_a_foreign_origin_gets_403_and_no_gui_message(guarded_studio, caplog):
    """Cross-site WebSocket hijacking: a page at http://evil.example opening the studio's
    websocket is answered 403, and nothing follows the answer (no GUI state)."""
    import websockets.sync.client
    from websockets.exceptions import InvalidStatus

    port = guarded_studio.port
    refused = guarded_studio.guard.refused
    with caplog.at_level("WARNING", logger="studio.origin"):
        raw = _raw_handshake(port, "http://evil.example")
        with pytest.raises(InvalidStatus) as error:
            websockets.sync.client.connect(f"ws://127.0.0.1:{port}", origin="http://evil.example",
                                           subprotocols=[_viser_subprotocol()], open_timeout=10)
    head, _, body = raw.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 403"), raw[:200]
    length = int(next(line.split(b":")[1] for line in head.split(b"\r\n")
                      if line.lower().startswith(b"content-length")))
    assert len(body) == length and b"Forbidden" in body  # the 403's text, then nothing
    assert error.value.response.status_code == 403
    assert guarded_studio.guard.refused == refused + 2
    assert "http://evil.example" in caplog.text


@pytest.mark.parametrize("origin", ["http://127.0.0.1:{port}", "http://localhost:{port}",
                                    "http://tools.example:9000"])
def test_the_studios_own_origin_gets_the_gui(guarded_studio, origin):
    import websockets.sync.client

    port = guarded_studio.port
    with websockets.sync.client.connect(f"ws://127.0.0.1:{port}",
                                        origin=origin.format(port=port),
                                        subprotocols=[_viser_subprotocol()],
                                        open_timeout=10) as ws:
        message = ws.recv(timeout=30)
    assert isinstance(message, bytes) and len(message) > 0  # viser's GUI state


def test_page_exports_stay_in_the_folder(guarded_studio):
    """The page's export field: a refused name writes nothing (the page says why), a
    plain name lands in the folder, a second export of it gets a suffix."""
    from upm.motion.amc import read_amc

    box = guarded_studio.exports.root
    outside = box.parent
    for name in ("../x.amc", str(outside / "abs.amc"), "a/b.amc", "x.txt"):
        guarded_studio.amc_path.value = name
        assert guarded_studio.export() is None
        assert "export refused" in guarded_studio.report.content
    assert sorted(p.name for p in outside.rglob("*")) == []
    guarded_studio.amc_path.value = "take.bvh"
    first = guarded_studio.export()
    guarded_studio.amc_path.value = "take.amc"
    second, third = guarded_studio.export(), guarded_studio.export()
    assert sorted(p.name for p in box.iterdir()) == ["take-1.amc", "take.amc", "take.bvh"]
    assert (first, second, third) == tuple(str(box / n) for n in
                                           ("take.bvh", "take.amc", "take-1.amc"))
    result = guarded_studio.scene.result
    assert read_amc(third, result.motion.skeleton).n_frames == result.motion.n_frames


def test_a_second_physics_check_while_one_runs_is_refused(guarded_studio, monkeypatch):
    import threading

    import studio.session

    started, release = threading.Event(), threading.Event()
    calls = []

    def slow_check(model, result):
        calls.append(result.method)
        started.set()
        release.wait(60)
        return [{"part": "all", "valid_pct": 100.0}]

    monkeypatch.setattr(studio.session, "physics_check", slow_check)
    assert guarded_studio.start_check()
    assert started.wait(30)
    assert not guarded_studio.start_check()  # the button again
    assert "already running" in guarded_studio.report.content
    assert guarded_studio.check() is None  # the server-side call too
    release.set()
    for _ in range(600):  # the first check's thread lets go
        if not guarded_studio._checking.locked():
            break
        threading.Event().wait(0.05)
    assert "valid_pct" in guarded_studio.report.content
    assert calls == [guarded_studio.scene.result.method]
    assert guarded_studio.check() == [{"part": "all", "valid_pct": 100.0}]
    assert len(calls) == 2


def test_a_non_loopback_host_is_warned_about(tmp_path, capsys):
    from upm.cli import main

    assert main(["studio", "--host", "0.0.0.0", "--data", str(tmp_path / "none")]) == 2
    err = capsys.readouterr().err
    assert "warning" in err and "anyone who can reach" in err
    assert "ssh -L 8080:127.0.0.1:8080" in err
    assert main(["studio", "--data", str(tmp_path / "none")]) == 2
    assert "warning" not in capsys.readouterr().err


def test_no_studio_runs_without_its_origin_check(session, monkeypatch):
    """A viser that started its websocket server another way would leave the check out:
    the studio stops that server and refuses to run."""
    import contextlib
    import socket

    import studio.app

    monkeypatch.setattr(studio.app, "guarded_viser", lambda guard: contextlib.nullcontext())
    port = _free_port()
    with pytest.raises(RuntimeError, match="unguarded"):
        studio.app.Studio(session, port=port)
    with socket.socket() as sock:  # the port is free again: the server was stopped
        sock.bind(("127.0.0.1", port))


def test_a_map_starts_the_studio_on_its_method_and_the_view_frames_the_body(
        catalog, synthetic_maps, tmp_path, session):
    """`upm studio --map M` starts on the method the map serves (upm, or som for a SOM
    map), not linear; the initial view looks at the motion from close enough that the
    body fills it."""
    from types import SimpleNamespace

    from studio.app import Studio
    from studio.session import Session

    for kind in ("upm", "som"):
        path = tmp_path / f"{kind}.npz"
        synthetic_maps[kind].save(path)
        assert Session(catalog, "02_01", "02_03", map_path=path).method == kind
    assert Session(catalog, "02_01", "02_03").method == "linear"
    camera = SimpleNamespace(fov=1.3, look_at=None, position=None)
    scene = session.recompute()
    stub = SimpleNamespace(scene=scene, server=SimpleNamespace(initial_camera=camera))
    Studio.frame_camera(stub)
    pos = scene.geom_pos_m.reshape(-1, 3)
    centre = (pos.min(axis=0) + pos.max(axis=0)) / 2
    np.testing.assert_allclose(camera.look_at, centre)
    distance = np.linalg.norm(np.subtract(camera.position, camera.look_at))
    height = pos[:, 2].max() - pos[:, 2].min()
    assert 1.0 < distance < 6.0 and distance < 4.0 * max(height, 1.0)
