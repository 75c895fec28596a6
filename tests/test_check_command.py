"""``upm check``: an AMC file with its ASF, a clip or a clip's frames, a whole split; the
JSON report and its CSV summary; one-line errors with exit code 2."""

import csv
import json
import os
import shutil
import subprocess
import sys

import pytest

from controller.report import SCHEMA, SCHEMA_VERSION
from upm.cli import main


@pytest.fixture(autouse=True)
def cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("UPM_CACHE", str(tmp_path_factory.getbasetemp() / "check-cache"))


def test_check_an_amc_file_with_its_asf(tmp_path, data_dir, capsys):
    for name in ("02.asf", "02_03.amc"):
        shutil.copy(data_dir / "02" / name, tmp_path / name)
    code = main(["check", str(tmp_path / "02_03.amc"), "--asf", str(tmp_path / "02.asf"),
                 "--json"])
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    assert report["schema"] == SCHEMA and report["schema_version"] == SCHEMA_VERSION
    assert report["kind"] == "check"
    assert report["motion"]["frames"] == 173 and report["motion"]["fps"] == 120.0
    assert len(report["frames"]) == 173
    totals = report["totals"]["kinematic"]
    # The run 02_03 is humanly possible in every frame, and beyond its ASF's declared
    # limits in every frame (reported, not judged)
    assert totals["valid_frames"] == 173 and totals["beyond_asf_frames"] == 173
    assert totals["limits"] == "human"
    frame = report["frames"][0]
    assert frame["valid"] and frame["beyond_asf"] and not frame["limit_dofs"]
    assert 0 <= frame["residual_force_bw"] and frame["support_points"] >= 0
    assert report["settings"]["self_touch_mm"] == 10.0
    # judged by the ASF's boxes instead, every frame breaks one
    code = main(["check", str(tmp_path / "02_03.amc"), "--asf", str(tmp_path / "02.asf"),
                 "--json", "--no-dynamics", "--limits", "asf"])
    asf = json.loads(capsys.readouterr().out)
    assert asf["totals"]["kinematic"]["limit_violation_frames"] == 173
    assert asf["totals"]["kinematic"]["valid_frames"] == 0
    assert asf["frames"][0]["limit_dofs"] and not asf["frames"][0]["valid"]


def test_check_a_clip_prints_totals_and_invalid_frames(data_dir, capsys):
    # judged by the ASF's boxes, the walk has invalid frames to list (the human verdict
    # finds none)
    assert main(["check", "02_01@0:120", "--data", str(data_dir), "--limits", "asf"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("02_01@0:120: 120 frames at 120 fps")
    for words in ("valid frames", "beyond the range", "self-interpenetration",
                  "beyond the ASF limits", "floor penetration", "residual force",
                  "invalid frames: "):
        assert words in out


def test_report_file_and_csv_are_written(tmp_path, data_dir, capsys):
    out = tmp_path / "reports" / "walk.json"
    assert main(["check", "16_15", "--data", str(data_dir), "--report", str(out),
                 "--no-dynamics"]) == 0
    capsys.readouterr()
    report = json.loads(out.read_text())
    assert "dynamics" not in report["totals"]
    assert "residual_force_bw" not in report["frames"][0]
    rows = list(csv.DictReader(out.with_suffix(".csv").open()))
    assert [r["part"] for r in rows] == ["all"]
    assert int(rows[0]["frames"]) == 471
    assert rows[0]["valid_frames"] == str(report["totals"]["kinematic"]["valid_frames"])
    assert not list(out.parent.glob(".tmp-*"))


def test_check_a_split_prints_the_calibration(tmp_path, data_dir, capsys):
    out = tmp_path / "calibration.json"
    assert main(["check", "--split", "test", "--data", str(data_dir), "--json",
                 "--report", str(out)]) == 0
    calibration = json.loads(capsys.readouterr().out)
    assert json.loads(out.read_text()) == calibration
    rows = list(csv.DictReader(out.with_suffix(".csv").open()))
    assert [r["clip"] for r in rows][-2:] == ["total all", "total test"]
    assert rows[0]["clip"] == "02_01" and int(rows[-1]["frames"]) == 3079
    assert [r["clip"] for r in calibration["clips"]] == [
        "02_01", "02_03", "03_01", "05_11", "16_15", "83_26", "141_04"]
    total = calibration["totals"]
    assert total["frames"] == 3079 and total["valid_pct"] > 88  # measured 90.3
    assert 50 < total["beyond_asf_pct"] < 75  # measured 61.3, reported, not judged
    assert calibration["splits"]["test"] == total
    assert 0 < total["residual_force_bw_mean"] < 1


def test_errors_are_one_line_exit_2(tmp_path, data_dir, capsys):
    # The installed command line, once: exit code 2 and one line on stderr.
    result = subprocess.run([sys.executable, "-m", "upm", "check"], capture_output=True,
                            text=True, env={**os.environ, "UPM_CACHE": str(tmp_path / "c")})
    assert result.returncode == 2
    assert result.stderr.strip().startswith("upm check: error: give a motion")
    amc = tmp_path / "x.amc"
    amc.write_text(":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\n")
    asf = tmp_path / "02.asf"
    shutil.copy(data_dir / "02" / "02.asf", asf)
    for args, message in [
        ([str(amc)], "needs its skeleton"),
        ([str(tmp_path / "missing.amc"), "--asf", str(asf)], "no such file"),
        ([str(amc), "--asf", str(asf)], "x.amc"),
        (["02_01", "--split", "test", "--data", str(data_dir)], "not both"),
        (["99_99", "--data", str(data_dir)], "no clip '99_99'"),
        (["02_01@500:900", "--data", str(data_dir)], "out of range"),
        (["02_01", "--asf", str(asf), "--data", str(data_dir)], "go with an AMC file"),
        ([str(tmp_path / "r.json"), "--asf", str(asf)], "r.json: not a motion"),
    ]:
        assert main(["check", *args]) == 2, args
        err = capsys.readouterr().err
        assert message in err, (args, err)
        assert len(err.strip().splitlines()) == 1, err


def test_a_bad_range_model_is_a_one_line_error(tmp_path, data_dir, capsys):
    assert main(["check", "02_01", "--data", str(data_dir), "--limits", "nope"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == ("upm check: error: --limits nope: neither a model (human, asf) nor a "
                   "file")
    bad = tmp_path / "r.json"
    bad.write_text('{"ranges": {"ltibia.flexion": [10]}}')
    assert main(["check", "02_01", "--data", str(data_dir), "--limits", str(bad)]) == 2
    assert "ltibia.flexion must be [low, high]" in capsys.readouterr().err


def test_check_reads_a_bvh_as_convert_does(data_dir, tmp_path, capsys):
    """A BVH named after a clip goes onto that clip's subject (CMU's 31-joint naming keeps
    the ASF's rotations), so it scores as the clip does; --asf puts it on a given ASF; a
    missing file is a one-line error."""
    bvh = data_dir.parent / "bvh" / "05_11.bvh"
    if not bvh.is_file():
        pytest.skip(f"no BVH at {bvh}")
    assert main(["check", str(bvh), "--data", str(data_dir), "--json", "--no-dynamics"]) == 0
    from_bvh = json.loads(capsys.readouterr().out)["totals"]["kinematic"]
    assert main(["check", "05_11", "--data", str(data_dir), "--json", "--no-dynamics"]) == 0
    from_clip = json.loads(capsys.readouterr().out)["totals"]["kinematic"]
    assert from_bvh["frames"] == from_clip["frames"] == 591
    assert abs(from_bvh["valid_frames"] - from_clip["valid_frames"]) <= 3
    assert main(["check", str(bvh), "--asf", str(data_dir / "05" / "05.asf"), "--data",
                 str(data_dir), "--json", "--no-dynamics"]) == 0
    assert json.loads(capsys.readouterr().out)["motion"]["skeleton"] == "05.asf"
    assert main(["check", str(tmp_path / "none.bvh"), "--data", str(data_dir)]) == 2
    assert "none.bvh: no such file" in capsys.readouterr().err


def test_check_text_names_rule_frame_and_amount_and_groups_by_cause(data_dir, capsys):
    """Without --json: a table of the rules broken (frames, peak and its frame, the mean
    over its own frames), the bodies interpenetrating, and the invalid frames by cause,
    every run listed."""
    assert main(["check", "83_26", "--data", str(data_dir), "--no-dynamics"]) == 0
    out = capsys.readouterr().out
    assert "rule broken            frames  peak deg  at frame  mean deg (its frames)" in out
    row = next(line for line in out.splitlines() if "lfoot.plantarflexion" in line)
    count, peak, frame, mean = row.split()[1:]
    assert int(count) == 24 and float(peak) > 50 and 0 <= int(frame) < 522
    assert float(mean) <= float(peak)
    assert "over those frames" in out and "over all" in out
    assert "invalid frames: 100, by cause" in out
    assert "    beyond the range         100: " in out and "more runs" not in out
