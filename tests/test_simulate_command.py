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
                                     "inertialize, spacetime, feasible, performed)")
    for args, message in [
        (["--sequence", "99_01", "--method", "linear"], "no clip '99_01'"),
        (["--sequence", "02_01@0:50", "02_02", "--method", "upm"], "needs --map"),
        (["--sequence", "02_01@0:50", "--method", "linear", "--video", "x.avi"],
         "--video x.avi"),
        (["--sequence", "02_01@0:50", "--method", "linear", "--viewer"], "needs a display"),
        (["--sequence", "02_01@0:50", "--method", "linear", "--modes", "free",
          "--render", "driven"], "--render driven needs"),
        (["--sequence", "02_01@0:50", "--method", "linear", "--modes", "driven",
          "--amc", "s.amc"], "need the free-root run"),
        (["--sequence", "02_01@0:50", "--method", "linear", "--controller", "servo",
          "--control", "c.npz"], "--control records the balance controller"),
        (["--sequence", "02_01@0:50", "--method", "linear", "--amc", "s.fbx"],
         "--amc s.fbx: use a name ending in .amc or .bvh"),
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


def test_free_root_is_the_balance_controller_by_default(tmp_path, data_dir, catalog, capsys):
    """The free-root run balances through the linear window between two walks; the AMC of
    what it did reads back on the skeleton, and the recorded torques replay to it."""
    # (a run stops 1 s after a fall: the AMC and the control cover the frames simulated)
    import numpy as np

    from controller import to_qpos
    from controller.balance.run import BalanceRun, replay
    from humanoid_xml import catalog_model_path, load_model
    from upm.motion.amc import read_amc

    out = tmp_path / "free.json"
    assert main(["simulate", "--data", str(data_dir), "--method", "linear", "--frames", "20",
                 "--sequence", "02_01@0:90", "02_02@30:100", "--modes", "free",
                 "--no-window-runs", "--report", str(out), "--amc", str(tmp_path / "s.amc"),
                 "--control", str(tmp_path / "c.npz")]) == 0
    printed = capsys.readouterr().out
    report = json.loads(out.read_text())
    assert report["schema_version"] == 2
    assert report["settings"]["tracking"]["free_controller"] == "balance"
    free = report["totals"]["tracking"]["free"]
    assert free["controller"] == "balance"
    assert ("free root (balance): " + (f"falls at {free['fall_time_s']:.2f} s" if free["fell"]
                                        else "does not fall")) in printed
    # it walks through the window and the second walk (measured: no fall, 9.8 deg RMS in
    # the window, where the linear blend slides the feet, with no search; the servos alone
    # fall within 1.4 s)
    (window,) = report["windows"]
    assert not free["fell"]
    assert not window["tracking"]["free"]["fell"]
    # where the search worked, and what it spent there
    troubles = free["search_troubles"]
    assert sum(r["retries"] for r in troubles) == free["search_retries"]
    assert {r["outcome"] for r in troubles} <= {"got past"}
    assert ("search: " in printed) == bool(troubles)
    assert 0.0 <= free["search_mode_share"] <= 1.0
    assert ("error by mode: " in printed) == bool(free["search_mode_share"])
    # each torque limit: how often the joint was at its strength, its peak and mean
    by_actuator = free["torque_by_actuator"]
    model = load_model(catalog_model_path(catalog, "02_01"))
    assert len(by_actuator) == model.nu
    shares = [a["saturation_share"] for a in by_actuator.values()]
    assert np.mean(shares) == pytest.approx(free["torque_saturation_share"], abs=1e-4)
    assert max(a["peak_nm"] for a in by_actuator.values()) == pytest.approx(
        free["torque_peak_nm"], abs=1e-3)
    for name, a in by_actuator.items():
        low, high = a["range_nm"]
        assert low < 0 < high
        assert 0 <= a["mean_nm"] <= a["peak_nm"] <= max(-low, high) + 1e-3, name
        # at full strength: at one end of the range, to the QP's rounding
        assert a["saturation_share"] == 0 or a["peak_nm"] > 0.99 * min(-low, high), name
        # of the frames at full strength, the share with the joint turning its way
        concentric = a["saturated_concentric_share"]
        assert (concentric is None) == (a["saturation_share"] == 0), name
        assert concentric is None or 0 <= concentric <= 1, name
    assert ("at full strength most often" in printed) == (max(shares) > 0)
    assert "torque_by_actuator" not in out.with_suffix(".csv").read_text()
    assert window["tracking"]["free"]["error_deg_rms"] < 15.0
    assert window["tracking"]["free"]["body_error_mm_mean"] < 100.0
    assert 0 <= free["heading_error_deg_peak"] <= 180
    for key in ("error_deg_rms", "body_error_mm_mean", "root_drift_m", "com_height_error_m",
                "contact_force_peak_bw", "torque_peak_nm", "torque_saturation_share",
                "trouble_time_s", "wall_s_per_sim_s", "raw_steps_per_step"):
        assert free[key] is not None and free[key] >= 0, key
    assert isinstance(free["ends_in_trouble"], bool)
    trouble = [f["free_trouble"] for f in report["frames"]]
    assert free["trouble_time_s"] == pytest.approx(sum(trouble) / 120.0, abs=1e-5)
    assert free["trouble_rule"].startswith("in trouble: the pelvis more than 12 cm below")
    simulated_frames = (180 if not free["fell"]
                        else min(180, free["fall_frame"] + 1 + 120))  # 1 s after a fall

    simulated = read_amc(tmp_path / "s.amc", catalog.skeleton("02"), fps=120.0)
    assert simulated.n_frames == simulated_frames
    with np.load(tmp_path / "c.npz", allow_pickle=False) as control:
        substeps = int(control["substeps"])
        assert control["ctrl"].shape == ((simulated_frames - 1) * substeps, model.nu)
        run = BalanceRun(
            fps=120.0, timestep_s=float(control["timestep_s"]), substeps=substeps, seed=0,
            start_qpos=control["start_qpos"], start_qvel=control["start_qvel"],
            qpos=np.zeros((simulated_frames, model.nq)), ctrl=control["ctrl"], fell=False,
            fall_frame=None, fall_time_s=None, diverged_frame=None,
            **{k: None for k in ("joint_error_deg", "body_error_mm", "root_drift_m",
                                 "heading_error_deg", "com_height_error_m", "contact_force_n",
                                 "torque_nm", "torque_saturated", "limit_rows", "self_contacts",
                                 "trouble", "warnings", "external_force_peak", "weight_n",
                                 "wall_s", "sim_s", "raw_step_s", "segment_modes", "retries",
                                 "simulated_steps")})
    replayed = replay(model, run)
    # the AMC holds what the character did: the replay of its torques, to the AMC's
    # printed precision
    np.testing.assert_allclose(to_qpos(model, simulated)[:, 7:], replayed[:, 7:], atol=1e-6)
    np.testing.assert_allclose(to_qpos(model, simulated)[:, :3], replayed[:, :3], atol=1e-6)


def test_servo_controller_is_still_available(tmp_path, data_dir, capsys):
    out = tmp_path / "servo.json"
    assert main(["simulate", "--data", str(data_dir), "--method", "linear", "--frames", "20",
                 "--sequence", "02_01@0:90", "02_02@30:100", "--modes", "free",
                 "--controller", "servo", "--no-window-runs", "--report", str(out)]) == 0
    report = json.loads(out.read_text())
    assert report["settings"]["tracking"]["free_controller"] == "servo"
    assert "body_error_mm_mean" not in report["totals"]["tracking"]["free"]
    # the servos fall; the pieces were joined whole, and the summary points at the cut
    assert report["totals"]["tracking"]["free"]["fell"] and report["sequence"]["cut"] == "whole"
    assert "--cut matched joins each" in capsys.readouterr().out


def test_search_budget_and_offsets_are_recorded_and_checked(tmp_path, data_dir, capsys):
    out = tmp_path / "b.json"
    # one piece has no transition: the default method (upm) needs no --map for it
    assert main(["simulate", "--data", str(data_dir),
                 "--sequence", "02_01@0:60", "--modes", "free", "--no-window-runs",
                 "--search-budget", "0", "--offset-deg", "0.1", "--offset-seed", "3",
                 "--report", str(out)]) == 0
    report = json.loads(out.read_text())
    assert report["settings"]["tracking"]["search_budget"] == 0.0
    assert report["sequence"]["offset_deg"] == 0.1 and report["sequence"]["offset_seed"] == 3
    assert "moved by N(0, 0.1 deg) per channel, seed 3" in capsys.readouterr().out
    free = report["totals"]["tracking"]["free"]
    assert free["search_retries"] == 0 and free["simulated_steps"] == free["steps"]
    capsys.readouterr()
    for args, message in [(["--search-budget", "-1"], "from 0 to 1000"),
                          (["--search-budget", "nan"], "from 0 to 1000"),
                          (["--search-budget", "2", "--controller", "servo"],
                           "the balance controller's"),
                          (["--offset-deg", "-0.1"], "--offset-deg -0.1: use a number"),
                          (["--offset-deg", "inf"], "from 0 to 10")]:
        assert main(["simulate", "--data", str(data_dir), "--method", "linear",
                     "--sequence", "02_01@0:60", "--report", str(tmp_path / "x.json"), *args]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1
        assert not (tmp_path / "x.json").exists()


def test_strength_multiplies_every_torque_limit_the_controller_may_use(tmp_path, data_dir,
                                                                      capsys):
    """09_06's run meets its ankles' and hips' limits in its first half second; a body twice
    as strong is given twice the ranges, and its controller uses torques the first body
    does not have."""
    by_strength = {}
    for k in ("1", "2"):
        out = tmp_path / f"s{k}.json"
        assert main(["simulate", "--data", str(data_dir), "--sequence", "09_06@0:60",
                     "--modes", "free", "--no-window-runs", "--search-budget", "0",
                     "--processes", "1", "--strength", k, "--report", str(out)]) == 0
        report = json.loads(out.read_text())
        assert report["settings"]["strength"] == float(k)
        by_strength[k] = report["totals"]["tracking"]["free"]["torque_by_actuator"]
    assert "every joint's torque limit x 2 (--strength)" in capsys.readouterr().out
    weak, strong = by_strength["1"], by_strength["2"]
    assert weak.keys() == strong.keys()
    for name in weak:
        assert strong[name]["range_nm"] == pytest.approx([2 * v for v in weak[name]["range_nm"]],
                                                         abs=2e-3)
    at_limit = [n for n in weak if weak[n]["saturation_share"] > 0]
    assert {"lfemur_rx", "rfoot_rx"} <= set(at_limit)
    beyond = [n for n in weak if strong[n]["peak_nm"] > max(map(abs, weak[n]["range_nm"]))]
    assert {"lfemur_rx", "rfoot_rx"} <= set(beyond)
    for bad in ("0", "-1", "nan", "11"):
        assert main(["simulate", "--data", str(data_dir), "--sequence", "09_06@0:60",
                     "--modes", "free", "--strength", bad,
                     "--report", str(tmp_path / "x.json")]) == 2
        err = capsys.readouterr().err
        assert f"--strength {bad}" in err and err.count("\n") == 1
        assert not (tmp_path / "x.json").exists()


def test_the_search_is_summed_up_in_one_line():
    from upm.commands.simulate_summary import search_line

    troubles = [
        {"frame": 94, "time_s": 0.78333, "cause": ["pelvis low"], "retries": 96,
         "rerun_s": 19.175, "outcome": "got past"},
        {"frame": 129, "time_s": 1.075, "cause": ["pelvis low", "tilted"], "retries": 51,
         "rerun_s": 15.95833, "outcome": "budget spent"}]
    assert search_line(troubles) == (
        "  search: 2 troubles (first at 0.78 s), 147 retries running 35.1 simulated s "
        "again; got past 1; gave up at 1.07 s (pelvis low and tilted: budget spent)")
    # with the seconds by mode (reports of this version): summed over the troubles
    troubles[0]["rerun_s_by_mode"] = [0.0, 4.0, 5.0, 0.0, 10.175, 0.0]
    troubles[1]["rerun_s_by_mode"] = [0.5, 1.0, 2.0, 3.0, 4.0, 5.45833]
    assert search_line(troubles) == (
        "  search: 2 troubles (first at 0.78 s), 147 retries running 35.1 simulated s "
        "again; got past 1 (seconds run again by the mode tried, 0-5: 0.5 / 5.0 / 7.0 / "
        "3.0 / 14.2 / 5.5); gave up at 1.07 s (pelvis low and tilted: budget spent)")


def test_the_error_by_mode_in_one_line():
    from upm.commands.simulate_summary import by_mode_line

    free = {"search_mode_share": 0.30612, "error_deg_rms_search_modes": 6.04,
            "body_error_mm_mean_search_modes": 81.6, "error_deg_rms_default_mode": 3.1,
            "body_error_mm_mean_default_mode": 31.2}
    assert by_mode_line(free) == (
        "  error by mode: the 31 % of the frames the search changed 6.0 deg / 82 mm, the "
        "rest (the default mode) 3.1 deg / 31 mm")
    # every frame changed: no default-mode figure
    free.update(search_mode_share=1.0, error_deg_rms_default_mode=None,
                body_error_mm_mean_default_mode=None)
    assert by_mode_line(free).endswith("the rest (the default mode) -")
    # no search, or a report from before the split: no line
    assert by_mode_line({"search_mode_share": 0.0}) == ""
    assert by_mode_line({}) == ""


def test_the_joints_most_often_at_full_strength_in_one_line():
    from upm.commands.simulate_summary import strength_line

    by_actuator = {name: {"peak_nm": 1.0, "mean_nm": 0.5, "range_nm": [-1.0, 1.0],
                          "saturation_share": share}
                   for name, share in (("lfemur_rx", 0.1844), ("rfoot_rx", 0.12766),
                                       ("ltoes_rx", 0.0), ("lfoot_rx", 0.11348),
                                       ("rfemur_rz", 0.0922))}
    assert strength_line(by_actuator) == (
        "  at full strength most often: lfemur_rx 18.4 %, rfoot_rx 12.8 %, lfoot_rx 11.3 % "
        "of the frames")
    assert strength_line({"ltoes_rx": by_actuator["ltoes_rx"]}) == ""
    for name, concentric in (("lfemur_rx", 0.1212), ("rfoot_rx", 0.33), ("lfoot_rx", 0.3125)):
        by_actuator[name]["saturated_concentric_share"] = concentric
    assert strength_line(by_actuator) == (
        "  at full strength most often (share of the frames; of those, concentric: the joint "
        "turning the way it pushes): lfemur_rx 18.4 % (12 %), rfoot_rx 12.8 % (33 %), "
        "lfoot_rx 11.3 % (31 %)")


def test_cut_matched_drives_the_pieces_it_cut(tmp_path, data_dir, capsys):
    out = tmp_path / "cut.json"
    assert main(["simulate", "--data", str(data_dir), "--method", "linear",
                 "--sequence", "02_01@0:200", "02_02@0:100", "--cut", "matched",
                 "--modes", "driven", "--report", str(out)]) == 0
    report = json.loads(out.read_text())
    first, second = report["sequence"]["pieces"]
    assert report["sequence"]["cut"] == "matched" and second == "02_02@0:100"
    stop = int(first.split(":")[1])
    assert first == f"02_01@0:{stop}" and 200 - 144 <= stop < 200
    # the driven run covers the cut piece, the window and the next piece
    assert report["motion"]["frames"] == stop + 20 + 100
    assert f"cut {first}: its feet" in capsys.readouterr().out
