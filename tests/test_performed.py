"""The ``performed`` transition method (upm.transitions.performed): a real window is
performable and the humanoid reproduces it closely; the registry entry drives ``upm
transition`` and ``upm sequence``, the window is written as AMC and read back; without the
humanoid's performer, or with a bad --config, a one-line usage error."""

import json

import numpy as np
import pytest

from controller.config import DEFAULT
from controller.offline.performer import install, perform_transition
from upm.cli import main
from upm.core.errors import UsageError
from upm.motion.amc import read_amc
from upm.ops.angles import angle_diff_deg
from upm.transitions import METHODS, Transition, performed, transition
from upm.transitions.performed import PerformedKeys

#: A small search: seconds per window, not a minute.
SMALL = DEFAULT.updated({"offline": {"samples": 32, "keep": 4}})
SMALL_TOML = "[offline]\nsamples = 24\nkeep = 4\n"


def test_without_the_performer_it_is_a_usage_error(synthetic_catalog, monkeypatch):
    monkeypatch.setattr(performed, "_PERFORMER", [None])
    before = synthetic_catalog.load("81_01").frames(0, 30)
    after = synthetic_catalog.load("81_02").frames(0, 30)
    with pytest.raises(UsageError, match="needs the humanoid's performer"):
        transition("performed", before, after, 10, 0.5, PerformedKeys(follow=METHODS["linear"]))
    with pytest.raises(UsageError, match="no key_posture"):
        transition("performed", before, after, 10, 0.5, object())


def test_bad_options_are_one_line_errors(tmp_path, synthetic_dir, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[offline]\nsamples = -3\n")
    base = ["transition", "--data", str(synthetic_dir), "--from", "81_01@20", "--to",
            "81_02@0", "--out", str(tmp_path / "x.amc")]
    cases = [(["--method", "performed", "--config", str(bad)], "offline.samples must be"),
             (["--method", "linear", "--config", str(bad)], "it goes with that method"),
             (["--method", "linear", "--follow", "slerp"], "--follow goes with"),
             (["--method", "performed", "--follow", "performed"], "follow another method")]
    for args, words in cases:
        assert main([*base, *args]) == 2, args
        err = capsys.readouterr().err.strip()
        assert words in err and "\n" not in err, args
    assert not (tmp_path / "x.amc").exists()


@pytest.mark.physics
def test_a_real_window_is_performed_closely(catalog):
    """The clip's own frames as the asked window (02_01, frames 100-119, 0.5 s of context
    each side): a real window is performable, and the humanoid stays close to it."""
    motion = catalog.load("02_01").frames(0, 240)
    real = Transition(motion=motion, window=slice(100, 120), method="real", frames=20,
                      alpha=0.5, key_posture_deg=None, key_time=10.5, seconds=0.0,
                      heading_turn_deg=0.0, diagnostics={})
    done = perform_transition(real, 0.5, SMALL)
    figures = done.figures
    assert figures["fell"] == 0 and figures["left_window"] == 0
    assert figures["joint_error_deg"] < 6.0 and figures["body_error_mm"] < 80
    assert done.first == 40 and done.posture_deg.shape == (120 - 40 + 60, 63)
    inside = slice(100 - done.first, 120 - done.first)
    declared = motion.skeleton.declared
    error = angle_diff_deg(done.posture_deg[inside][:, declared],
                           motion.posture_deg[100:120, declared])
    assert np.sqrt(np.mean(error ** 2)) < 6.0
    assert np.abs(done.root[inside, :3] - motion.root[100:120, :3]).max() < 0.15  # metres
    # the run starts from the clip's own state: no step into it
    assert figures["join_step_start_deg"] < 2.0
    assert 0 <= figures["torque_saturation_share"] < 0.2


@pytest.mark.physics
def test_the_registry_entry_drives_transition_and_sequence(tmp_path, data_dir):
    install()
    config = tmp_path / "small.toml"
    config.write_text(SMALL_TOML)
    out, report = tmp_path / "p.amc", tmp_path / "p.json"
    assert main(["transition", "--data", str(data_dir), "--method", "performed", "--follow",
                 "linear", "--from", "02_01@200", "--to", "02_03@20", "--frames", "10",
                 "--context", "80", "--config", str(config), "--out", str(out),
                 "--json", str(report)]) == 0
    written = json.loads(report.read_text())
    assert written["method"] == "performed" and written["follow"] == "linear"
    figures = written["diagnostics"]
    assert {"performed_joint_error_deg", "performed_body_error_mm", "performed_fell",
            "performed_left_window", "performed_torque_saturation_share"} <= set(figures)
    # AMC round trip: the window read back is the performed window written
    from upm.motion.catalog import Catalog

    skeleton = Catalog(data_dir).skeleton("02")
    back = read_amc(out, skeleton, fps=120.0)
    w0, w1 = written["window_first_frame"], written["window_stop_frame"]
    window = np.asarray(written["window_posture_deg"])
    np.testing.assert_allclose(angle_diff_deg(back.posture_deg[w0:w1], window), 0, atol=1e-4)
    np.testing.assert_allclose(back.root[w0:w1], written["window_root"], atol=1e-4)
    # what the body did is not the linear window it was asked
    linear = tmp_path / "l.json"
    assert main(["transition", "--data", str(data_dir), "--method", "linear", "--from",
                 "02_01@200", "--to", "02_03@20", "--frames", "10", "--context", "80",
                 "--out", str(tmp_path / "l.amc"), "--json", str(linear)]) == 0
    asked = np.asarray(json.loads(linear.read_text())["window_posture_deg"])
    assert np.abs(angle_diff_deg(window, asked)).max() > 0.1
    # upm sequence: each window's figures in its JSON
    seq = tmp_path / "s.json"
    assert main(["sequence", "--data", str(data_dir), "02_01@100:200", "02_03@20:80",
                 "--method", "performed", "--follow", "linear", "--frames", "10",
                 "--config", str(config), "--out", str(tmp_path / "s.bvh"),
                 "--json", str(seq)]) == 0
    (entry,) = json.loads(seq.read_text())["windows"]
    assert entry["performed"]["joint_error_deg"] >= 0 and "fell" in entry["performed"]


@pytest.mark.physics
def test_the_performed_window_needs_no_hand_of_god(catalog, model02):
    """On a flat-floor pair the performed window's residual ("hand of god") force is at
    contact level, as a motion a body did must be, where the window it followed needs
    more (measured with this small search: linear 0.19 body weights, performed 0.01; the
    study's real windows 0.14 on average)."""
    from controller import to_qpos
    from controller.checks.dynamics import root_residual
    from upm.transitions import get_method

    install()
    before = catalog.load("02_01").frames(80, 201)
    after = catalog.load("02_03").frames(20, 140)
    keys = PerformedKeys(follow=get_method("linear"), config=SMALL)
    check = DEFAULT.residual

    def residual(result):
        r = root_residual(model02, to_qpos(model02, result.motion), result.motion.fps,
                          check.support_distance_m, check.friction, check.lowpass_hz)
        return r.summary(result.window)["residual_force_bw_mean"]

    asked = residual(transition("linear", before, after, 20, 0.5))
    done = transition("performed", before, after, 20, 0.5, keys)
    assert done.diagnostics["performed_fell"] == 0
    assert residual(done) < 0.05 < asked
