"""upm robustness: the balance controller on exact and offset references (real clips)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from eval.robustness import (
    CHECKPOINT_NAME,
    CHECKPOINT_VERSION,
    Row,
    Settings,
    parse_row,
    parse_rows,
    reference,
    run_robustness,
)
from eval.robustness_report import summed_by_mode
from upm.cli import main
from upm.core.errors import UsageError
from upm.motion.catalog import Catalog


@pytest.mark.parametrize("text, row", [
    ("02_01", Row(("02_01",), "upm")),
    (" 02_01@0:240 ", Row(("02_01@0:240",), "upm")),
    ("02_01+02_02", Row(("02_01", "02_02"), "upm")),
    ("02_01@10:+16_15@:-5,feasible", Row(("02_01@10:", "16_15@:-5"), "feasible")),
])
def test_rows_parse(text, row):
    parsed = parse_row(text)
    assert parsed == row
    assert parse_row(parsed.text) == parsed


@pytest.mark.parametrize("text, message", [
    ("", "write CLIP"), ("02_01+", "write CLIP"), ("+02_01", "write CLIP"),
    ("02_01+02_02,nosuch", "nosuch"), ("02_01@x", "bad clip reference"),
])
def test_bad_rows_name_the_row(text, message):
    with pytest.raises(UsageError, match=message) as caught:
        parse_row(text)
    assert repr(text) in str(caught.value)


def test_rows_all_is_every_clip_of_the_data_once(data_dir):
    names = Catalog(data_dir).names()
    rows = parse_rows(["all"], names)
    assert [row.pieces for row in rows] == [(name,) for name in names]
    assert len(rows) == len(set(rows)) >= 20  # every clip of the shared data, none twice
    assert parse_rows(["02_01", "16_15+16_15"], names) == [
        Row(("02_01",)), Row(("16_15", "16_15"), "upm")]
    with pytest.raises(UsageError, match="stands alone"):
        parse_rows(["all", "02_01"], names)
    with pytest.raises(UsageError, match="repeated"):
        parse_rows(["02_01", " 02_01"], names)


def test_each_row_runs_on_its_exact_and_offset_references(data_dir, tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["robustness", "--data", str(data_dir), "--rows", "02_01@0:120",
                 "02_01@0:60+02_02@0:60,linear", "--seeds", "1", "--workers", "1",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    report = json.loads((out / "robustness.json").read_text())
    assert report["settings"]["offset_seeds"] == 1 and report["settings"]["offset_deg"] == 0.1
    assert report["totals"]["runs"] == 4 and len(report["runs"]) == 4
    walk, sequence = report["rows"]
    assert walk["label"] == "02_01@0:120" and walk["seconds"] == pytest.approx(1.0)
    assert sequence["label"] == "02_01@0:60 -> 02_02@0:60 (linear)"
    # the first second of a walk: the controller stands, on the clip and on its offset
    exact, offset = report["runs"]["02_01@0:120#0"], report["runs"]["02_01@0:120#1"]
    assert not exact["fell"] and not offset["fell"] and walk["falls"] == 0
    assert 0 < exact["error_deg_rms"] < 5 and 0 < exact["body_error_mm_mean"] < 50
    # 0.1 degree offsets are a different reference: a different run
    assert exact["error_deg_rms"] != offset["error_deg_rms"]
    assert walk["standing_error_deg_rms"] == [
        min(exact["error_deg_rms"], offset["error_deg_rms"]),
        max(exact["error_deg_rms"], offset["error_deg_rms"])]
    assert (out / "robustness.md").read_text() in printed
    assert (out / "robustness.png").stat().st_size > 1000
    assert not (out / CHECKPOINT_NAME).exists()


def test_a_run_is_upm_simulate_on_the_same_offset_reference(data_dir, tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["robustness", "--data", str(data_dir), "--rows", "02_01@0:90", "--seeds",
                 "1", "--workers", "1", "--no-figures", "--out", str(out)]) == 0
    run = json.loads((out / "robustness.json").read_text())["runs"]["02_01@0:90#1"]
    assert main(["simulate", "--data", str(data_dir), "--sequence", "02_01@0:90",
                 "--method", "linear", "--modes", "free", "--no-window-runs",
                 "--processes", "1",
                 "--offset-deg", "0.1", "--offset-seed", "1",
                 "--report", str(tmp_path / "s.json")]) == 0
    capsys.readouterr()
    free = json.loads((tmp_path / "s.json").read_text())["totals"]["tracking"]["free"]
    for key in ("fell", "error_deg_rms", "body_error_mm_mean", "root_drift_m",
                "search_retries"):
        assert run[key] == free[key], key


def test_a_stopped_study_resumes_with_only_the_missing_runs(data_dir, tmp_path):
    from eval.runs import Checkpoint

    settings = Settings(str(data_dir), None, 0.1)
    row = Row(("02_01@0:60",))
    earlier = Checkpoint(tmp_path, settings.as_dict(), name=CHECKPOINT_NAME,
                         format_name="upm-controller/robustness-checkpoint",
                         version=CHECKPOINT_VERSION, numbers=False)
    earlier.open()
    kept = {"fell": False, "fall_time_s": None, "seconds": 0.5, "marker": 1}
    earlier.add(f"{row.text}#0", kept)
    earlier.close()
    result = run_robustness(settings, [row], 1, tmp_path, workers=1, show_progress=False)
    assert result.resumed == 1
    assert result.run(row, 0) == kept  # read back, not run again
    assert result.run(row, 1)["seconds"] == pytest.approx(0.5)
    assert "marker" not in result.run(row, 1)
    # the resumed run has no search figures by mode: no sum over only some of the runs
    assert "search_by_mode" in result.run(row, 1)
    assert summed_by_mode(result.runs.values()) is None
    assert summed_by_mode([result.run(row, 1)]) == result.run(row, 1)["search_by_mode"]


def test_the_controller_configuration_is_a_setting_of_the_study(data_dir, tmp_path, capsys):
    """--config reaches the runs (a search budget of 0: no retries, where the default's
    search works on 05_11) and the report; --search-budget is laid over the file's; a
    checkpoint made with another configuration is not resumed."""
    from controller.config import DEFAULT, ControllerConfig

    path = tmp_path / "c.toml"
    path.write_text("[search]\nbudget = 0\n[placement]\ngain = 0.35\n")
    out = tmp_path / "r"
    assert main(["robustness", "--data", str(data_dir), "--rows", "05_11", "--seeds",
                 "0", "--workers", "1", "--no-figures", "--config", str(path),
                 "--out", str(out)]) == 0
    capsys.readouterr()
    report = json.loads((out / "robustness.json").read_text())
    config = ControllerConfig.from_dict(report["settings"]["controller_config"])
    assert config.search.budget == 0.0 and config.placement.gain == 0.35
    assert report["runs"]["05_11#0"]["search_retries"] == 0
    assert main(["robustness", "--data", str(data_dir), "--rows", "05_11", "--seeds",
                 "0", "--workers", "1", "--no-figures", "--config", str(path),
                 "--search-budget", "0.5", "--out", str(out)]) == 0
    capsys.readouterr()
    report = json.loads((out / "robustness.json").read_text())
    assert report["settings"]["controller_config"]["search"]["budget"] == 0.5
    assert report["runs"]["05_11#0"]["search_retries"] > 0
    plain = Settings(str(data_dir), None, 0.1)
    other = Settings(str(data_dir), None, 0.1, DEFAULT.with_search_budget(0))
    row = Row(("02_01@0:30",))
    run_robustness(other, [row], 0, tmp_path, workers=1, show_progress=False)
    # the same settings resume; the default configuration's do not
    assert run_robustness(other, [row], 0, tmp_path, workers=1,
                          show_progress=False).resumed == 1
    assert run_robustness(plain, [row], 0, tmp_path, workers=1,
                          show_progress=False).resumed == 0


def test_strength_is_a_setting_of_the_study(data_dir):
    plain = Settings(str(data_dir), None, 0.1)
    stronger = Settings(str(data_dir), None, 0.1, strength=1.5)
    assert plain.as_dict()["strength"] == 1.0 and stronger.as_dict()["strength"] == 1.5
    model, _ = reference(plain, Row(("02_01@0:60",)), 0)
    strong_model, _ = reference(stronger, Row(("02_01@0:60",)), 0)
    np.testing.assert_allclose(strong_model.actuator_forcerange,
                               1.5 * model.actuator_forcerange)


@pytest.mark.parametrize("args, message", [
    (["--rows", "02_01+"], "write CLIP"),
    (["--rows", "99_99"], "no clip '99_99'"),
    (["--rows", "02_01@5"], "one frame"),
    (["--rows", "02_01", "02_01"], "repeated"),
    (["--rows", "all", "02_01"], "stands alone"),
    (["--offset-deg", "0"], "--offset-deg"),
    (["--seeds", "-1"], "--seeds"),
    (["--strength", "0"], "--strength 0"),
    (["--config", "nosuch.toml"], "nosuch.toml: cannot read the configuration"),
    (["--offline-seeds", "1"], "--offline-seeds is the offline effort's"),
    (["--threads", "2"], "--threads is the offline effort's"),
    (["--effort", "both", "--threads", "0"], "--threads 0"),
    (["--effort", "offline", "--offline-seeds", "-1"], "--offline-seeds must be"),
    (["--max-s", "0"], "--max-s 0"),
    (["--effort", "offline", "--search-budget", "2"], "--search-budget is the real-time"),
])
def test_bad_input_is_one_line_exit_2(data_dir, tmp_path, args, message):
    result = subprocess.run([sys.executable, "-m", "upm", "robustness", "--data",
                             str(data_dir), "--out", str(tmp_path / "r"), *args],
                            capture_output=True, text=True)
    assert result.returncode == 2, result.stderr
    assert message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert not (tmp_path / "r").exists()


def test_a_fall_after_the_search_spent_its_budget_is_counted_as_such(data_dir, tmp_path,
                                                                    capsys):
    """05_11's dance falls at about 1.1 s (its first second the body now performs, with
    the human range's hinge limits); with a budget of half the clip's steps the search
    gives up on it with the budget spent, and the report says so."""
    out = tmp_path / "r"
    assert main(["robustness", "--data", str(data_dir), "--rows", "05_11", "--seeds",
                 "0", "--workers", "1", "--no-figures", "--search-budget", "0.5",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    report = json.loads((out / "robustness.json").read_text())
    run = report["runs"]["05_11#0"]
    assert run["fell"] and run["search_gave_up"]
    assert run["search_gave_up"][-1]["outcome"] == "budget spent"
    assert run["search_gave_up"][0]["time_s"] <= run["fall_time_s"]
    assert report["rows"][0]["falls_budget_spent"] == 1
    assert report["totals"]["falls_budget_spent"] == 1
    assert "Of the falls, 1 came after the search had spent its budget" in printed
    # where the search's work went, by mode: every restart and second run again counted once
    by_mode = report["totals"]["search_by_mode"]
    assert sum(by_mode["restarts"]) == run["search_retries"] > 0
    assert by_mode["restarts"][1] > 0 and sum(by_mode["got_past"]) == 0  # it got past none
    assert "The search's work by the mode of the segment each restart changed" in printed


def test_cut_matched_runs_the_sequence_on_pieces_cut_at_the_next_ones_phase(data_dir,
                                                                            tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["robustness", "--data", str(data_dir), "--rows",
                 "02_01@0:200+02_02@0:60,linear", "--seeds", "0", "--workers", "1",
                 "--no-figures", "--cut", "matched", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    report = json.loads((out / "robustness.json").read_text())
    assert report["settings"]["cut"] == "matched"
    run = report["runs"]["02_01@0:200+02_02@0:60,linear#0"]
    # 02_01 ends earlier than its frame 200: the sequence is shorter than the whole pieces'
    assert run["seconds"] < (200 + 20 + 60) / 120
    assert "cut where the next one's gait phase matches" in printed


def test_both_efforts_perform_every_row_side_by_side(data_dir, tmp_path, capsys):
    """``--effort both``: each row by the real-time controller and by the offline effort
    (a small search here: 24 samples, one pass), on the row's first ``--max-s`` seconds;
    the offline runs carry the same figures by name, the report a table with both and
    each effort's totals, and the checkpoint keys each effort's runs apart."""
    config = tmp_path / "small.toml"
    config.write_text("[offline]\nsamples = 24\nkeep = 4\nbudget = 1.0\n")
    out = tmp_path / "r"
    assert main(["robustness", "--data", str(data_dir), "--rows", "02_01", "--seeds", "0",
                 "--effort", "both", "--max-s", "0.5", "--config", str(config),
                 "--threads", "1", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    report = json.loads((out / "robustness.json").read_text())
    assert report["settings"]["efforts"] == ["realtime", "offline"]
    assert report["settings"]["max_s"] == 0.5
    assert set(report["runs"]) == {"02_01#0", "02_01#0@offline"}
    realtime, offline = report["runs"]["02_01#0"], report["runs"]["02_01#0@offline"]
    for run in (realtime, offline):
        assert run["seconds"] == pytest.approx(61 / 120, abs=1e-4)
        assert not run["fell"] and run["ends_in_trouble"] in (False, 0.0)
        assert 0.0 < run["error_deg_rms"] < 10.0
    assert offline["search_rollouts"] > 0 and offline["search_retries"] is None
    rows = report["by_effort"]["offline"]["rows"]
    assert rows[0]["exact"] == offline and report["rows"][0]["exact"] == realtime
    assert report["by_effort"]["offline"]["totals"]["exact_falls"] == 0
    assert "offline, exact reference" in printed and "Offline: 0 of 1 exact" in printed
    assert "Each row's first 0.5 s" in printed
    assert (out / "robustness.png").stat().st_size > 0
