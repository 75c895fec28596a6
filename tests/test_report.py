"""Reports: per frame, per window, per piece and totals, as strict JSON and a CSV table;
the analysis of a motion with windows, dynamics and tracking in one call."""

import csv
import json
import math

import mujoco
import numpy as np
import pytest

from controller.analysis import analyse
from controller.report import SCHEMA_VERSION, csv_text, summary_rows, write_report
from humanoid_xml import catalog_model_path, load_model


@pytest.fixture(scope="module")
def analysed(catalog, walk):
    model = load_model(catalog_model_path(catalog, "02"))
    motion = walk.frames(0, 150)
    windows = [slice(40, 60), slice(100, 110)]
    report, results = analyse(
        model, motion, kind="simulate", windows=windows,
        window_meta=[{"method": "test", "seconds": 0.001}] * 2,
        pieces=[("a", slice(0, 40)), ("b", slice(60, 100)), ("c", slice(110, 150))],
        tracking_modes=("driven",), window_free=True)
    return report, results


def test_report_has_every_part(analysed):
    report, results = analysed
    assert report["schema_version"] == SCHEMA_VERSION and report["kind"] == "simulate"
    assert len(report["frames"]) == 150
    windows = report["windows"]
    assert [(w["start"], w["stop"], w["frames"]) for w in windows] == [(40, 60, 20),
                                                                       (100, 110, 10)]
    assert windows[0]["method"] == "test"
    assert windows[0]["kinematic"]["frames"] == 20
    assert "added_excess_peak_deg" in windows[0]["kinematic"]
    assert set(windows[0]["dynamics"]) >= {"residual_force_bw_mean", "residual_force_bw_peak"}
    assert windows[0]["tracking"]["driven"]["frames"] == 20
    free = windows[0]["tracking"]["free_window"]
    assert free["start"] == 0 and free["stop"] == 120  # 0.5 s either side, clipped
    assert isinstance(free["fell"], bool)
    assert [p["name"] for p in report["pieces"]] == ["a", "b", "c"]
    assert report["software"]["mujoco"] == mujoco.__version__
    assert report["software"]["numpy"] == np.__version__
    frames = report["frames"]
    assert [f["window"] for f in frames[38:42]] == [None, None, 0, 0]
    assert "added_dofs" in frames[40] and "added_dofs" not in frames[39]
    assert frames[0]["driven_error_deg"] == pytest.approx(0.0, abs=1e-6)
    run = report["totals"]["tracking"]["driven"]
    assert run["steps"] == 149 * 5 and run["warnings"] == {}
    assert results["tracking"]["driven"].n_frames == 150


def test_report_is_strict_json_with_nulls_for_non_finite(tmp_path, analysed):
    report, _ = analysed
    json_path, csv_path = write_report(report, tmp_path / "r.json")
    text = json_path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    assert json.loads(text) == report
    rows = list(csv.DictReader(csv_path.open()))
    assert [r["part"] for r in rows] == ["all", "window 0", "window 1", "piece 0", "piece 1",
                                         "piece 2"]
    assert rows[1]["method"] == "test" and rows[3]["name"] == "a"
    assert int(rows[1]["frames"]) == 20
    assert "driven_error_deg_rms" in rows[0] and "residual_force_bw_mean" in rows[0]
    assert "free_window_fell" in rows[1]
    assert not any(k.startswith("pairs") for k in rows[0])


def test_summary_rows_and_csv_agree(analysed):
    report, _ = analysed
    rows = summary_rows(report)
    text = csv_text(rows)
    parsed = list(csv.DictReader(text.splitlines()))
    assert len(parsed) == len(rows)
    for row, back in zip(rows, parsed, strict=True):
        for key, value in row.items():
            if isinstance(value, float) and math.isfinite(value):
                assert float(back[key]) == pytest.approx(value)


def test_nan_becomes_null():
    from controller.report import _clean

    cleaned = _clean({"a": np.nan, "b": [np.float32(1.5), np.inf], "c": np.int64(3),
                      "d": np.bool_(True)})
    assert cleaned == {"a": None, "b": [1.5, None], "c": 3, "d": True}
    json.dumps(cleaned, allow_nan=False)
