"""``upm train`` and ``upm map-info`` from the command line."""

import json
import subprocess
import sys

import numpy as np

from upm.cli import main
from upm.maps.map_file import load_map


def test_train_then_map_info(data_dir, tmp_path, capsys):
    out = tmp_path / "maps" / "small.npz"
    assert main(["train", "--data", str(data_dir), "--clips", "02_02", "09_06",
                 "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["kind"] == "upm" and summary["clips"] == ["02_02", "09_06"]
    assert summary["samples"] == 298 + 141
    assert [row["class"] for row in summary["classes"]] == ["body", "global", "medium", "detail"]
    upm = load_map(out)
    assert upm.provenance["clip_names"] == ["02_02", "09_06"]
    assert main(["map-info", str(out), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["kind"] == "upm" and info["samples"] == 439 and info["format_version"] == 1
    for row in info["classes"]:
        assert row["neurons"] == len(upm.neurons[row["class"]])
        assert row["quantisation_error_max_deg"] <= row["radius_deg"] + 1e-9
    assert main(["map-info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Uniform Posture Map" in text and "R (deg)" in text and "02_02 09_06" in text


def test_train_som_with_a_grid(data_dir, tmp_path, capsys):
    out = tmp_path / "som.npz"
    assert main(["train", "--data", str(data_dir), "--clips", "09_06", "--kind", "som",
                 "--grid", "4x5", "--epochs", "3", "--out", str(out)]) == 0
    assert "SOM trained on 1 clip," in capsys.readouterr().out
    som = load_map(out)
    assert som.kind == "som" and all(len(w) == 20 for w in som.neurons.values())
    assert main(["map-info", str(out)]) == 0
    assert "Kohonen SOM" in capsys.readouterr().out


def test_train_is_deterministic(data_dir, tmp_path, capsys):
    paths = [tmp_path / "a.npz", tmp_path / "b.npz"]
    for p in paths:
        assert main(["train", "--data", str(data_dir), "--clips", "141_01", "--seed", "3",
                     "--out", str(p)]) == 0
    a, b = load_map(paths[0]), load_map(paths[1])
    assert all(np.array_equal(a.neurons[c], b.neurons[c]) for c in a.neurons)


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "upm", *args], capture_output=True, text=True)


def test_bad_input_is_one_line_exit_2(data_dir, tmp_path):
    bad_map = tmp_path / "bad.npz"
    bad_map.write_bytes(b"nope")
    cases = [
        (["train", "--data", str(data_dir), "--clips", "99_99", "--out", str(tmp_path / "x.npz")],
         "no clip '99_99'"),
        (["train", "--data", str(data_dir), "--clips", "09_06", "--kind", "som", "--grid", "4by5",
          "--out", str(tmp_path / "x.npz")], "--grid must look like 30x40"),
        (["train", "--data", str(data_dir), "--clips", "09_06", "--learning-rate", "2",
          "--out", str(tmp_path / "x.npz")], "learning_rate must be in (0, 1)"),
        (["train", "--data", str(data_dir)], "required: --out"),
        (["map-info", str(bad_map)], "not an .npz (zip) archive"),
        (["map-info", str(tmp_path / "absent.npz")], "no such file"),
    ]
    for args, message in cases:
        result = _cli(*args)
        assert result.returncode == 2, (args, result.stderr)
        assert message in result.stderr, (args, result.stderr)
        assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert not (tmp_path / "x.npz").exists()
