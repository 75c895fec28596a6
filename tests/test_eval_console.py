"""What ``upm eval`` prints (eval.console, eval.inbetween_report): the headline names every
method run and the real windows, explains its columns and ``ms``, and fits 100 columns,
as does the in-betweening table, with the widest figures the study can give."""

import pytest

from eval.console import CONSOLE, WIDTH, headline_text
from eval.inbetween_report import inbetween_text
from eval.lafan import BASELINES, LAFAN_LENGTHS
from eval.metrics import HEADLINE, METRICS
from eval.records import REAL
from eval.summaries import Summaries
from upm.transitions import METHODS

#: Wide but real values: the widest each headline figure reached in a study.
WIDEST = {"valid_pct": 100.0, "added_limit_mean_deg": 12.34, "self_collision_pct": 100.0,
          "nearest_real_mean_deg": 25.5, "residual_force_mean_bw": 12.345,
          "jerk_rms_deg_s3": 9_999_000.0, "foot_skate_mps": 12.345,
          "tracking_error_deg": 45.67}


def _summaries(methods, window=20):
    summary = {}
    for method in (*methods, REAL):
        for metric in METRICS:
            value = WIDEST.get(metric, 1.0)
            summary[(window, "all", method, metric)] = {"mean": value, "lo": value,
                                                        "hi": value, "n": 100}
    return Summaries(metrics=dict(METRICS), windows=(window,), methods=tuple(methods),
                     reference=None, settings={}, groups={}, summary=summary, paired={},
                     calibration={}, clip_windows={})


@pytest.mark.parametrize("methods", [tuple(METHODS), ("linear",), ("upm", "spacetime")])
def test_the_headline_names_every_method_and_fits_100_columns(methods):
    timing = {"ms": {"20": {m: {"median": 12345.678} for m in methods}}}
    lines = headline_text(_summaries(methods), timing, 20, methods).splitlines()
    assert max(len(line) for line in lines) <= WIDTH
    assert lines[0].split()[0] == "method" and lines[0].split()[-1] == "ms"
    assert [line.split()[0] for line in lines[1:len(methods) + 1]] == list(methods)
    assert lines[len(methods) + 1].startswith("real windows")
    assert lines[1].split()[-1] == "12345.68"
    legend = " ".join(lines[len(methods) + 2:])
    assert "ms: median milliseconds to compute one transition" in legend
    for metric in HEADLINE:  # every column header is explained
        assert CONSOLE[metric][0] in lines[0].split() and f"{CONSOLE[metric][0]}: " in legend


def test_the_inbetween_table_fits_100_columns_with_every_method_and_baseline():
    methods = (*METHODS, *BASELINES)
    rows = [{"length": n, "method": m, "metric": metric, "mean": value, "lo": value,
             "hi": value, "n": 100}
            for n in LAFAN_LENGTHS for m in methods
            for metric, value in (("l2q", 12.345), ("l2p", 123.45), ("npss", 12.3456))]
    lines = inbetween_text(rows).splitlines()
    assert max(len(line) for line in lines) <= WIDTH
    assert [line.split()[0] for line in lines[1:]] == list(methods)
    assert lines[0].split()[1:] == [f"{k}@{n}" for k in ("L2Q", "L2P", "NPSS")
                                    for n in LAFAN_LENGTHS]
