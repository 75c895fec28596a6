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


def main_exit(argv, capsys):
    """``main(argv)`` in this process: (exit code, stdout, stderr); argparse's exits
    (help, bad arguments) included."""
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def test_help_lists_every_command(capsys):
    result = run("--help")  # the module's entry point, in its own process
    assert result.returncode == 0
    for name in COMMANDS:
        assert name in result.stdout
        code, out, _ = main_exit([name, "--help"], capsys)
        assert code == 0 and "usage: upm " + name in out


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


def test_malformed_data_is_one_line_exit_2(tmp_path, synthetic_dir):
    (tmp_path / "82").mkdir()
    (tmp_path / "82" / "82.asf").write_bytes((synthetic_dir / "82" / "82.asf").read_bytes())
    text = (synthetic_dir / "82" / "82_02.amc").read_bytes()  # CRLF
    (tmp_path / "82" / "82_02.amc").write_bytes(text.replace(b"lfemur", b"lfemurX", 1))
    (tmp_path / "clips.csv").write_text("clip,fps\n82_02,120\n")
    line = text.split(b"\r\n").index(next(t for t in text.split(b"\r\n")
                                            if t.startswith(b"lfemur "))) + 1
    result = run("clips", "--data", str(tmp_path))
    assert result.returncode == 2
    assert f"82_02.amc:{line}:" in result.stderr
    assert "unknown bone 'lfemurX'" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_clips_lists_the_synthetic_clips(synthetic_dir, capsys):
    code, out, err = main_exit(["clips", "--data", str(synthetic_dir), "--json"], capsys)
    assert code == 0 and err == ""
    report = json.loads(out)
    assert report["data"] == str(synthetic_dir)
    rows = {r["clip"]: r for r in report["clips"]}
    assert list(rows) == ["81_01", "81_02", "81_03", "82_01", "82_02"]
    assert rows["82_01"]["fps"] == 60 and rows["82_01"]["frames"] == 120
    assert rows["82_01"]["seconds"] == pytest.approx(2.0)
    assert rows["81_03"]["split"] == "test" and rows["81_03"]["subject"] == "81"
    assert all(r["outside_limits_pct"] == 0 for r in rows.values())  # made inside them
    code, out, _ = main_exit(["clips", "--data", str(synthetic_dir), "--split", "test"],
                             capsys)
    assert code == 0
    assert "81_03" in out and "82_02" in out and "81_01" not in out
    assert "2 clips, 324 frames" in out


@pytest.mark.parametrize("args, message", [
    (["clips", "--split", "dev"], "invalid choice: 'dev'"),
    (["clips", "--json", "extra"], "unrecognized arguments: extra"),
    (["transition", "--from", "81_01", "--to", "81_02", "--frames", "ten", "--out", "x.amc"],
     "invalid int value: 'ten'"),
    (["transition", "--from", "81_01", "--to", "81_02", "--method", "linear",
      "--alpha", "-0.5", "--out", "x.amc"], "alpha must be in [0, 1]"),
    (["transition", "--from", "81_01@500", "--to", "81_02", "--method", "linear",
      "--out", "x.amc"], "frame out of range"),
    (["transition", "--from", "81_01", "--to", "83_01", "--method", "linear",
      "--out", "x.amc"], "no clip '83_01'"),
    (["transition", "--from", "81_01@x", "--to", "81_02", "--method", "linear",
      "--out", "x.amc"], "bad clip reference '81_01@x'"),
    (["transition", "--from", "81_01", "--to", "81_02", "--method", "upm",
      "--out", "x.amc"], "needs --map MAP.npz"),
    (["transition", "--from", "81_01", "--to", "81_02", "--out", "a-file/x.amc",
      "--method", "linear"], "a-file"),
])
def test_bad_arguments_on_the_synthetic_data_exit_2_with_one_line(synthetic_dir, tmp_path,
                                                                  capsys, args, message):
    import warnings

    args = [str(tmp_path / a) if a.endswith(".amc") else a for a in args]
    (tmp_path / "a-file").write_text("not a folder")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code, out, err = main_exit([*args, "--data", str(synthetic_dir)], capsys)
    assert code == 2, err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert caught == []  # nothing else said on the way (a warning would be a 2nd line)
    assert not list(tmp_path.rglob("*.amc"))


def test_main_restores_process_state(monkeypatch, capsys, synthetic_dir):
    """Warnings format and BLAS thread variables are the command's, not the session's."""
    import warnings

    from upm.cli import main

    monkeypatch.setenv("UPM_DATA", str(synthetic_dir))  # the default data folder
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.delenv(name, raising=False)
    before = warnings.formatwarning
    assert main(["clips", "--json"]) == 0
    capsys.readouterr()
    assert warnings.formatwarning is before
    assert os.environ.get("OMP_NUM_THREADS") is None


def test_closed_pipe_is_a_quiet_exit(monkeypatch, capsys, synthetic_dir):
    monkeypatch.setenv("UPM_DATA", str(synthetic_dir))  # the default data folder

    class ClosedPipe:
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", ClosedPipe())
    assert main(["clips"]) == 141
    monkeypatch.undo()
    assert capsys.readouterr().err == ""
