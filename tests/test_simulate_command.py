"""``upm simulate``: a sequence of real clips joined by transitions drives the humanoid;
the report marks the windows and pieces, the CSV has a row per part, --video writes a
playable file offscreen; bad input is a one-line error."""

import csv
import json
import os
import subprocess
import sys

import pytest

from upm.cli import main


@pytest.fixture(autouse=True)
def cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("UPM_CACHE", str(tmp_path_factory.getbasetemp() / "simulate-cache"))


@pytest.fixture(scope="module")
def simulated(tmp_path_factory, data_dir):
    out = tmp_path_factory.mktemp("simulate")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("UPM_CACHE", str(tmp_path_factory.getbasetemp() / "simulate-cache"))
        code = main(["simulate", "--data", str(data_dir), "--method", "linear",
                     "--sequence", "02_01@0:90", "02_02@30:100", "--frames", "20",
                     "--report", str(out / "r.json"), "--video", str(out / "r.gif")])
    assert code == 0
    return out


def test_report_marks_windows_and_pieces(simulated):
    report = json.loads((simulated / "r.json").read_text())
    assert report["kind"] == "simulate"
    assert report["sequence"]["method"] == "linear"
    assert report["sequence"]["pieces"] == ["02_01@0:90", "02_02@30:100"]
    assert report["motion"]["frames"] == 90 + 20 + 70
    (window,) = report["windows"]
    assert (window["start"], window["stop"]) == (90, 110)
    assert window["from"] == "02_01@0:90" and window["to"] == "02_02@30:100"
    assert [p["name"] for p in report["pieces"]] == ["02_01@0:90", "02_02@30:100"]
    assert [(p["start"], p["stop"]) for p in report["pieces"]] == [(0, 90), (110, 180)]
    frames = report["frames"]
    assert [f["window"] for f in frames[89:91]] == [None, 0]
    assert "added_excess_max_deg" in frames[100]
    for mode in ("driven", "free"):
        run = report["totals"]["tracking"][mode]
        assert run["warnings"] == {} and run["diverged_frame"] is None
        assert f"{mode}_error_deg" in frames[50]
    assert "free_window" in window["tracking"]
    # Before the window the servos follow the walk closely (as on the clip alone); the
    # linear blend then dips a foot 5 cm into the floor (measured), which the floor
    # pushes back: the window is flagged for it.
    assert report["pieces"][0]["tracking"]["driven"]["error_deg_rms"] < 2.0
    assert window["kinematic"]["floor_penetration_frames"] > 0
    assert window["kinematic"]["floor_depth_peak_mm"] > 10
    rows = list(csv.DictReader((simulated / "r.csv").open()))
    assert [r["part"] for r in rows] == ["all", "window 0", "piece 0", "piece 1"]
    from PIL import Image

    assert Image.open(simulated / "r.gif").n_frames == 180 // 4  # drawn at 30 fps


def test_errors_are_one_line_exit_2(tmp_path, data_dir, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    base = ["--data", str(data_dir), "--report", str(tmp_path / "r.json")]
    # The installed command line, once: exit code 2 and one line on stderr.
    result = subprocess.run([sys.executable, "-m", "upm", "simulate", *base, "--sequence",
                             "02_01@0:50", "--method", "nope"], capture_output=True, text=True,
                            env={**os.environ, "UPM_CACHE": str(tmp_path / "cache")})
    assert result.returncode == 2
    assert result.stderr.strip() == ("upm simulate: error: no transition method 'nope' "
                                     "(methods: upm, som, classnn, snap, linear, slerp, "
                                     "inertialize, spacetime)")
    for args, message in [
        (["--sequence", "99_01", "--method", "linear"], "no clip '99_01'"),
        (["--sequence", "02_01@0:50", "02_02", "--method", "upm"], "needs --map"),
        (["--sequence", "02_01@0:50", "--method", "linear", "--video", "x.avi"],
         "--video x.avi"),
        (["--sequence", "02_01@0:50", "--method", "linear", "--viewer"], "needs a display"),
        (["--sequence", "02_01@0:50", "--method", "linear", "--modes", "free",
          "--render", "driven"], "--render driven needs"),
    ]:
        assert main(["simulate", *base, *args]) == 2, args
        err = capsys.readouterr().err
        assert message in err, (args, err)
        assert len(err.strip().splitlines()) == 1, err
        assert not (tmp_path / "r.json").exists()


def test_simulate_with_the_uniform_posture_map(tmp_path, data_dir, capsys):
    """The paper's method end to end: a small map trained on two clips gives the key
    posture of the window; the report names the map and the method."""
    map_path = tmp_path / "small.npz"
    assert main(["train", "--data", str(data_dir), "--clips", "02_02", "05_01",
                 "--out", str(map_path)]) == 0
    out = tmp_path / "upm.json"
    assert main(["simulate", "--data", str(data_dir), "--map", str(map_path),
                 "--sequence", "02_01@0:60", "02_03@20:80", "--modes", "driven",
                 "--no-window-runs", "--report", str(out)]) == 0
    assert "method upm" in capsys.readouterr().out
    report = json.loads(out.read_text())
    assert report["sequence"]["method"] == "upm"
    assert report["sequence"]["map"] == str(map_path)
    (window,) = report["windows"]
    assert window["method"] == "upm" and window["frames"] == 20
    assert "free" not in report["totals"]["tracking"]
    assert "free_window" not in window.get("tracking", {})
    assert report["pieces"][0]["tracking"]["driven"]["error_deg_rms"] < 2.0
