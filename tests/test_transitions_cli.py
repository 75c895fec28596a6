"""``upm transition`` and ``upm sequence`` on the CMU clips: playable AMC out, JSON, plot,
one-line errors."""

import json
import subprocess
import sys

import numpy as np
import pytest

from upm.cli import main
from upm.maps.map_file import load_map
from upm.motion.amc import read_amc


def test_transition_writes_amc_and_json(data_dir, catalog, tmp_path, capsys):
    out, report = tmp_path / "t.amc", tmp_path / "t.json"
    code = main(["transition", "--data", str(data_dir), "--from", "02_01@200", "--to",
                 "02_03@20", "--method", "linear", "--frames", "20", "--context", "30",
                 "--out", str(out), "--json", str(report)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "window = frames 30-49" in printed and "ms" in printed
    motion = read_amc(out, catalog.skeleton("02"), fps=120.0)
    assert motion.n_frames == 30 + 20 + 30
    walk = catalog.load("02_01")
    np.testing.assert_allclose(motion.posture_deg[:30], walk.posture_deg[171:201], atol=1e-6)
    data = json.loads(report.read_text())
    assert data["window_first_frame"] == 30 and data["window_stop_frame"] == 50
    assert data["from"] == "02_01@200" and data["to"] == "02_03@20"
    assert np.array(data["window_posture_deg"]).shape == (20, 63)
    np.testing.assert_allclose(np.array(data["window_posture_deg"]), motion.posture_deg[30:50],
                               atol=1e-5)
    assert len(data["dof_names"]) == 63 and data["key_posture_deg"] is None


def test_transition_with_classnn_and_plot(data_dir, tmp_path, capsys):
    out, figure = tmp_path / "c.amc", tmp_path / "c.png"
    code = main(["transition", "--data", str(data_dir), "--from", "05_01", "--to", "05_11@10",
                 "--method", "classnn", "--out", str(out), "--plot", str(figure)])
    assert code == 0
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "classnn: 05_01@597 -> 05_11@10" in capsys.readouterr().out


def test_sequence_command(data_dir, catalog, tmp_path, capsys):
    out, report = tmp_path / "s.amc", tmp_path / "s.json"
    code = main(["sequence", "--data", str(data_dir), "02_01@0:100", "60_10@0:100",
                 "16_15@50:120", "--method", "linear", "--frames", "10", "--out", str(out),
                 "--json", str(report)])
    assert code == 0
    motion = read_amc(out, catalog.skeleton("02"), fps=120.0)
    assert motion.n_frames == 100 + 10 + 199 + 10 + 70
    data = json.loads(report.read_text())
    assert [w["first_frame"] for w in data["windows"]] == [100, 309]
    assert "window 2" in capsys.readouterr().out


def run(*args):
    return subprocess.run([sys.executable, "-m", "upm", *args], capture_output=True, text=True)


@pytest.mark.parametrize("args, message", [
    (["transition", "--from", "02_01", "--to", "02_03", "--out", "x.amc"], "needs --map"),
    (["transition", "--from", "02_01", "--to", "02_03", "--method", "som", "--map",
      "nope.npz", "--out", "x.amc"], "nope.npz"),
    (["transition", "--from", "02_01@999", "--to", "02_03", "--method", "linear",
      "--out", "x.amc"], "frame out of range"),
    (["transition", "--from", "02_01@1:5", "--to", "02_03", "--method", "linear",
      "--out", "x.amc"], "not a range"),
    (["transition", "--from", "02_01", "--to", "99_99", "--method", "linear",
      "--out", "x.amc"], "no clip '99_99'"),
    (["transition", "--from", "02_01", "--to", "02_03", "--method", "linear", "--alpha",
      "2", "--out", "x.amc"], "alpha"),
    (["transition", "--from", "02_01", "--to", "02_03", "--method", "wiggle",
      "--out", "x.amc"], "no transition method 'wiggle'"),
    (["transition", "--from", "02_01", "--to", "02_03", "--method", "linear", "--frames",
      "0", "--out", "x.amc"], "window length"),
    (["transition", "--from", "02_01", "--to", "02_03", "--method", "linear", "--plot",
      "f.png", "--plot-dof", "knee.rx", "--out", "x.amc"], "not a posture DOF"),
    (["sequence", "02_01@0:100", "--method", "linear", "--out", "x.amc"], "at least two"),
    (["sequence", "02_01@0:100", "--out", "x.amc"], "at least two"),
    (["sequence", "02_01@0:100", "02_03@50:10", "--method", "linear", "--out", "x.amc"],
     "empty range"),
])
def test_bad_input_is_one_line_exit_2(data_dir, tmp_path, args, message):
    args = [a if a != "x.amc" else str(tmp_path / "x.amc") for a in args]
    result = run(*args, "--data", str(data_dir))
    assert result.returncode == 2, result.stderr
    assert message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert not (tmp_path / "x.amc").exists()


# --- on the synthetic data folder (unit tier) ---------------------------------------------

def test_transition_on_the_synthetic_data_writes_amc_and_json(synthetic_dir, synthetic_catalog,
                                                              tmp_path, capsys):
    """81_02 into the shorter subject's 82_02: the AMC on 81's skeleton, the context frames
    of clip 1 as they are, the window between them, clip 2 after it."""
    out, report = tmp_path / "t.amc", tmp_path / "t.json"
    code = main(["transition", "--data", str(synthetic_dir), "--from", "81_02@100", "--to",
                 "82_02@20", "--method", "inertialize", "--frames", "16", "--context", "24",
                 "--out", str(out), "--json", str(report)])
    assert code == 0
    assert "window = frames 24-39" in capsys.readouterr().out
    motion = read_amc(out, synthetic_catalog.skeleton("81"), fps=120.0)
    assert motion.n_frames == 24 + 16 + 24
    run_clip = synthetic_catalog.load("81_02")
    np.testing.assert_allclose(motion.posture_deg[:24], run_clip.posture_deg[77:101], atol=1e-6)
    after = synthetic_catalog.load("82_02").posture_deg[20:44]  # postures carry over as
    np.testing.assert_allclose(motion.posture_deg[40:], after, atol=1e-6)  # they are
    data = json.loads(report.read_text())
    assert (data["window_first_frame"], data["window_stop_frame"]) == (24, 40)
    assert data["from"] == "81_02@100" and data["to"] == "82_02@20"
    np.testing.assert_allclose(np.array(data["window_posture_deg"]), motion.posture_deg[24:40],
                               atol=1e-5)


def test_train_then_transition_with_the_map_on_the_synthetic_data(synthetic_dir,
                                                                  synthetic_catalog,
                                                                  tmp_path, capsys):
    """The paper's pipeline from the command line: train a UPM on the train split, then
    a ``upm`` transition with it; the key posture (in the JSON) is made of its neurons."""
    from upm.motion.skeleton import CLASS_NAMES, CLASS_SLICES

    path = tmp_path / "upm.npz"
    assert main(["train", "--data", str(synthetic_dir), "--out", str(path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["kind"] == "upm" and summary["clips"] == ["81_01", "81_02", "82_01"]
    out, report = tmp_path / "t.amc", tmp_path / "t.json"
    assert main(["transition", "--data", str(synthetic_dir), "--map", str(path), "--from",
                 "81_03@-1", "--to", "81_01@0", "--out", str(out), "--json",
                 str(report)]) == 0
    key = np.array(json.loads(report.read_text())["key_posture_deg"])
    upm = load_map(path)
    for c in CLASS_NAMES:  # the JSON keeps 5 decimals
        nearest = np.abs(upm.neurons[c] - key[CLASS_SLICES[c]]).max(axis=1).min()
        assert nearest < 1e-5, c
    assert read_amc(out, synthetic_catalog.skeleton("81")).n_frames == 120 + 20 + 120
