"""The command line: help, clips, one-line errors with exit code 2."""

import json
import os
import subprocess
import sys

import pytest

from upm.cli import COMMANDS, main


def run(*args, env_data=None):
    return subprocess.run([sys.executable, "-m", "upm", *args], capture_output=True, text=True,
                          env=env_data)


def test_help_lists_every_command():
    result = run("--help")
    assert result.returncode == 0
    for name in COMMANDS:
        assert name in result.stdout
        sub = run(name, "--help")
        assert sub.returncode == 0 and "usage: upm " + name in sub.stdout


def test_building_the_cli_does_not_import_mujoco():
    code = ("import sys; from upm.cli import build_parser; build_parser(); "
            "print('mujoco' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.strip() == "False", out.stderr


def test_clips_json(data_dir, capsys):
    assert main(["clips", "--data", str(data_dir), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert len(report["clips"]) == 26
    row = next(r for r in report["clips"] if r["clip"] == "60_10")
    assert row["fps"] == 60 and row["frames"] == 1197 and row["seconds"] == pytest.approx(19.95)
    assert set(row) >= {"clip", "subject", "frames", "seconds", "fps", "description", "split",
                        "outside_limits_pct"}
    assert all(2 < r["outside_limits_pct"] < 17 for r in report["clips"])


def test_clips_table(data_dir, capsys):
    assert main(["clips", "--data", str(data_dir), "--split", "test"]) == 0
    out = capsys.readouterr().out
    assert "02_01" in out and "02_02" not in out and "7 clips" in out
    if (data_dir.parent / "bvh").is_dir():  # BVH files beside the clips are listed too
        assert "bvh/mocapbank_test.bvh" in out and "12 BVH files" in out


@pytest.mark.parametrize("args, message", [
    (["clips", "--data", "/definitely/not/here"], "does not exist"),
    (["clips", "--bogus"], "unrecognized arguments"),
    (["nope"], "invalid choice"),
])
def test_bad_input_is_one_line_exit_2(args, message):
    result = run(*args)
    assert result.returncode == 2
    assert message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr


def test_malformed_data_is_one_line_exit_2(tmp_path, data_dir):
    (tmp_path / "02").mkdir()
    (tmp_path / "02" / "02.asf").write_bytes((data_dir / "02" / "02.asf").read_bytes())
    text = (data_dir / "02" / "02_03.amc").read_text()
    (tmp_path / "02" / "02_03.amc").write_text(text.replace("lfemur", "lfemurX", 1))
    (tmp_path / "clips.csv").write_text("clip,fps\n02_03,120\n")
    result = run("clips", "--data", str(tmp_path))
    assert result.returncode == 2
    assert "02_03.amc:" in result.stderr and "unknown bone 'lfemurX'" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_main_restores_process_state(monkeypatch, capsys):
    """Warnings format and BLAS thread variables are the command's, not the session's."""
    import warnings

    from upm.cli import main

    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.delenv(name, raising=False)
    before = warnings.formatwarning
    assert main(["clips", "--json"]) == 0
    capsys.readouterr()
    assert warnings.formatwarning is before
    assert os.environ.get("OMP_NUM_THREADS") is None


def test_closed_pipe_is_a_quiet_exit(monkeypatch, capsys):
    class ClosedPipe:
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", ClosedPipe())
    assert main(["clips"]) == 141
    monkeypatch.undo()
    assert capsys.readouterr().err == ""
