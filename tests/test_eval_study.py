"""``upm eval`` end to end on a small study (3 pairs, 10-frame windows, every method): the
files, every method x metric for every pair in the long-form scores.csv (read back with
int windows), the calibration row, the in-betweening task's LaFAN1 figures, the figures;
the same seed gives byte-identical results with 2 worker processes and with none; what
it prints fits 100 columns and names every method; bad arguments are one-line errors."""

import contextlib
import io
import json

import mujoco
import numpy as np
import pytest

from eval.collect import SCORE_METRICS
from eval.inbetween import INBETWEEN, INBETWEEN_METRICS
from eval.lafan import BASELINES, LAFAN_LENGTHS
from eval.metrics import HEADLINE, METRICS
from eval.records import REAL, Records
from eval.study import STUDY_METHODS
from upm.cli import main

DETERMINISTIC = ("results.json", "scores.csv", "summary.csv", "paired.csv", "summary.md")


def _run(data_dir, out, *extra):
    return main(["eval", "--data", str(data_dir), "--pairs", "3", "--windows", "10",
                 "--seed", "7", "--out", str(out), *extra])


@pytest.fixture(scope="module")
def study(tmp_path_factory, data_dir):
    out = tmp_path_factory.mktemp("eval")
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert _run(data_dir, out / "two", "--workers", "2") == 0
    (out / "two.txt").write_text(printed.getvalue())
    assert _run(data_dir, out / "one", "--workers", "1", "--no-figures") == 0
    return out


def test_writes_every_output(study):
    names = {p.name for p in (study / "two").iterdir()}
    assert set(DETERMINISTIC) | {"timing.json", "table4.md", "figures.json"} <= names
    for png in ("fig13_window_dof.png", "fig14_sequence_dof.png", "metrics.png",
                "filmstrip.png"):
        data = (study / "two" / png).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000
    assert not [n for n in names if n.startswith(".tmp-")]
    assert not list((study / "one").glob("*.png"))


def test_same_seed_same_bytes_whatever_the_workers(study):
    for name in DETERMINISTIC:
        assert (study / "one" / name).read_bytes() == (study / "two" / name).read_bytes(), name


def _scores(folder) -> Records:
    return Records.from_csv((folder / "scores.csv").read_text(), SCORE_METRICS, "scores.csv")


def test_results_hold_every_pair_method_and_metric(study):
    results = json.loads((study / "two" / "results.json").read_text())
    assert results["format"] == "upm-controller/eval-results"
    assert results["format_version"] == 2
    assert set(results["metrics"]) == set(METRICS)
    assert all(results["metrics"][m]["unit"] for m in METRICS)
    assert [p["id"] for p in results["pairs"]] == [0, 1, 2]
    for pair in results["pairs"]:
        assert pair["first"]["clip"] != pair["second"]["clip"]
        assert pair["first"]["stop"] - pair["first"]["start"] in (173, 200)
    scores = _scores(study / "two")
    per_unit = len(METRICS)
    inbetween = 3 * len(LAFAN_LENGTHS) * (len(STUDY_METHODS) + len(BASELINES))
    assert len(scores) == results["scores"]["rows"] == (
        (3 * len(STUDY_METHODS) + 3) * per_unit + inbetween * len(INBETWEEN_METRICS))
    # the windows read back as ints
    assert {row[2] for row in scores.rows() if row[0] != INBETWEEN} == {10}
    for method in STUDY_METHODS:
        assert scores.ids("pair", 10, method) == [0, 1, 2]
        for metric in METRICS:
            assert np.isfinite(scores.values("pair", 10, method, metric)).all(), (method,
                                                                                  metric)
    assert scores.to_csv() == (study / "two" / "scores.csv").read_text()
    protocol = results["protocol"]
    assert protocol["pairs"] == 3 and protocol["windows"] == [10] and protocol["seed"] == 7
    assert set(protocol["train_subjects"]) >= {"02", "05", "83", "141"}
    assert not {"03", "16"} & set(protocol["train_subjects"])
    assert results["software"]["mujoco"] == mujoco.__version__
    assert {c: results["clips"][c]["seen"] for c in ("16_15", "05_11")} == {
        "16_15": False, "05_11": True}


def test_inbetween_task_scores_every_method_and_baseline(study):
    scores = _scores(study / "two")
    results = json.loads((study / "two" / "results.json").read_text())
    section = results["inbetween"]
    assert [w["id"] for w in section["windows"]] == [0, 1, 2]
    assert set(section["metrics"]) == set(INBETWEEN_METRICS)
    for length in LAFAN_LENGTHS:
        misses = set()
        for method in (*STUDY_METHODS, *BASELINES):
            assert scores.ids(INBETWEEN, length, method) == [0, 1, 2]
            for metric in INBETWEEN_METRICS:
                values = scores.values(INBETWEEN, length, method, metric)
                assert np.isfinite(values).all() and (values >= 0).all(), (method, metric)
            if method not in BASELINES:
                misses.add(tuple(scores.values(INBETWEEN, length, method, "target_miss_m")))
            else:
                assert (scores.values(INBETWEEN, length, method, "target_miss_m") == 0).all()
        assert len(misses) == 1  # every study method gets the same root
    rows = {(r["length"], r["method"], r["metric"]) for r in section["statistics"]}
    assert {(5, "interp", "npss"), (30, "upm", "l2p"), (15, "zerovel", "l2q")} <= rows
    table = (study / "two" / "summary.md").read_text()
    assert "In-betweening: the LaFAN1 metrics" in table and "comparable in kind" in table


def test_what_it_prints_fits_100_columns_and_names_every_method(study):
    printed = (study / "two.txt").read_text().splitlines()
    assert max(len(line) for line in printed) <= 100
    start = next(i for i, line in enumerate(printed) if line.startswith("method "))
    headline = printed[start:start + len(STUDY_METHODS) + 2]
    assert [line.split()[0] for line in headline[1:-1]] == list(STUDY_METHODS)
    assert headline[-1].startswith("real windows")
    text = "\n".join(printed)
    assert "ms: median milliseconds to compute one transition" in text
    for name in ("summary.md", "summary.csv", "scores.csv", "results.json", "table4.md"):
        assert name in text
    lafan = next(i for i, line in enumerate(printed) if line.startswith("method  ")
                 and "L2Q@5" in line)
    assert [line.split()[0] for line in printed[lafan + 1:lafan + 12]] == [
        *STUDY_METHODS, *BASELINES]


def test_calibration_row_exists(study):
    results = json.loads((study / "two" / "results.json").read_text())
    real = [w for w in results["real_windows"] if w["window"] == 10]
    assert [w["id"] for w in real] == [0, 1, 2]
    assert _scores(study / "two").ids(REAL, 10, REAL) == [0, 1, 2]
    summary = [row for row in results["statistics"]["summary"]
               if row["window"] == 10 and row["group"] == "all"]
    assert {row["method"] for row in summary} == set(STUDY_METHODS) | {REAL}
    assert len(summary) == (len(STUDY_METHODS) + 1) * len(METRICS)
    assert next(row["n"] for row in summary if row["method"] == REAL
                and row["metric"] == "nearest_real_mean_deg") == 3
    table = (study / "two" / "summary.md").read_text()
    assert "real windows (calibration)" in table and "UPM - linear" in table


def test_paired_comparisons_and_groups(study):
    results = json.loads((study / "two" / "results.json").read_text())
    paired = [row for row in results["statistics"]["paired"] if row["window"] == 10]
    assert {row["other"] for row in paired} == set(STUDY_METHODS) - {"upm"}
    for metric in HEADLINE:
        c = next(row for row in paired if row["other"] == "linear" and row["group"] == "all"
                 and row["metric"] == metric)
        assert c["wins"] + c["ties"] + c["losses"] == 3
    groups = results["statistics"]["groups"]["pairs"]
    assert groups["all"] == 3
    assert groups["seen"] + groups["unseen"] == 3


def test_timing_and_table4(study):
    timing = json.loads((study / "two" / "timing.json").read_text())
    assert set(timing["ms"]["10"]) == set(STUDY_METHODS)
    assert all(len(v) == 3 for v in timing["per_pair_ms"]["10"].values())
    # Speed is the benchmark's business, not a test's: only that the ratio is reported.
    assert timing["spacetime_over_upm"]["10"] > 0
    assert timing["machine"]["blas_threads"] == 1
    assert "MuJoCo " in (study / "two" / "table4.md").read_text()
    assert "spacetime / UPM" in (study / "two" / "table4.md").read_text()


def test_figures_name_their_example(study):
    figures = json.loads((study / "two" / "figures.json").read_text())
    assert figures["example"]["pair_id"] in (0, 1, 2)
    assert "median" in figures["example"]["rule"]


@pytest.mark.parametrize("args, message", [
    (["--windows", "10,x"], "--windows"),
    (["--windows", "1"], "at least 2 frames"),
    (["--pairs", "1"], "--pairs"),
    (["--methods", "upm", "cubic"], "no transition method 'cubic'"),
    (["--methods", "upm", "som"], "figures compare upm with linear"),
    (["--inbetween", "-1"], "--inbetween must be 0 (skip) or more windows, not -1"),
])
def test_bad_arguments_are_one_line_errors(args, message, tmp_path, data_dir, capsys):
    code = main(["eval", "--data", str(data_dir), "--out", str(tmp_path / "o"), *args])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[0]
    assert not (tmp_path / "o").exists()
