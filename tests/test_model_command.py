"""``upm model``: writes a loadable humanoid; one-line errors with exit code 2."""

import json
import os
import subprocess
import sys

import mujoco

import humanoid_xml
from upm.cli import main


def test_model_from_asf(tmp_path, data_dir, capsys, monkeypatch):
    monkeypatch.setenv("UPM_CACHE", str(tmp_path / "cache"))
    asf = tmp_path / "83.asf"
    asf.write_bytes((data_dir / "83" / "83.asf").read_bytes())
    out = tmp_path / "models" / "83.xml"
    assert main(["model", "--asf", str(asf), "--out", str(out)]) == 0
    line = capsys.readouterr().out
    assert str(out) in line and "nq 52, nv 51, nu 45" in line and "kg" in line
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.nu == 45 and not list(out.parent.glob(".tmp-*"))


def test_model_of_a_clip_goes_to_the_cache(tmp_path, data_dir, capsys, monkeypatch):
    monkeypatch.setenv("UPM_CACHE", str(tmp_path / "cache"))
    assert main(["model", "--subject", "02_01", "--data", str(data_dir), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["path"].startswith(str(tmp_path / "cache"))
    assert summary["model"] == "humanoid_02" and summary["nu"] == 45
    assert 45 < summary["mass_kg"] < 120


def test_generic_model(capsys):
    assert main(["model", "--generic", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["path"] == str(humanoid_xml.default_model_path())
    assert (summary["nq"], summary["nv"], summary["nu"]) == (52, 51, 45)


def _run(*args, env=None):
    return subprocess.run([sys.executable, "-m", "upm", *args], capture_output=True, text=True,
                          env=env)


def test_errors_are_one_line_exit_2(tmp_path, data_dir):
    bad = tmp_path / "bad.asf"
    bad.write_text(":version 1.10\n:root\n  order TX TY TZ RX RY RZ\n:bonedata\n  begin\n")
    env = {**os.environ, "UPM_CACHE": str(tmp_path / "cache")}
    for args, message in [
        (["--asf", str(tmp_path / "missing.asf")], "no such file"),
        (["--asf", str(bad)], "bad.asf"),
        (["--subject", "99", "--data", str(data_dir)], "no subject or clip '99'"),
        (["--generic", "--asf", str(bad)], "not allowed with"),
        ([], "one of the arguments"),
    ]:
        result = _run("model", *args, env=env)
        assert result.returncode == 2, (args, result.stderr)
        assert message in result.stderr
        assert len(result.stderr.strip().splitlines()) == 1, result.stderr
