"""Statistics of the study: bootstrap intervals that cover, reproduce and shrink; paired
wins/ties/losses the right way round for each metric; groups that partition the pairs."""

import numpy as np
import pytest

from eval.metrics import METRICS
from eval.records import REAL, Records
from eval.statistics import (
    bootstrap_mean,
    compare,
    pair_groups,
    resample_indices,
)
from eval.summaries import summarise


def test_interval_contains_the_mean_and_is_reproducible():
    values = np.random.default_rng(0).normal(3.0, 1.0, 80)
    a = bootstrap_mean(values, seed=5)
    assert a.lo < a.mean < a.hi and a.n == 80
    assert a == bootstrap_mean(values, seed=5)
    assert a != bootstrap_mean(values, seed=6)
    wide = bootstrap_mean(values[:10], seed=5)
    assert wide.hi - wide.lo > a.hi - a.lo


def test_interval_of_a_constant_is_a_point_and_of_nothing_is_empty():
    point = bootstrap_mean(np.full(20, 7.5), seed=0)
    assert (point.mean, point.lo, point.hi) == (7.5, 7.5, 7.5)
    empty = bootstrap_mean([], seed=0)
    assert empty.n == 0 and empty.as_dict()["mean"] is None


def test_interval_covers_about_95_percent():
    """Over 300 seeded samples of 40 from N(0, 1), the interval holds 0 about 95 % of the
    time (percentile intervals run a little narrow at this size)."""
    rng = np.random.default_rng(1)
    covered = 0
    for k in range(300):
        iv = bootstrap_mean(rng.normal(0.0, 1.0, 40), seed=k, resamples=500)
        covered += iv.lo < 0.0 < iv.hi
    assert 0.88 <= covered / 300 <= 0.99


def test_resamples_depend_on_seed_and_size_only():
    assert np.array_equal(resample_indices(12, 3), resample_indices(12, 3))
    assert resample_indices(12, 3).shape == (2000, 12)
    assert resample_indices(12, 3).max() < 12


def test_paired_wins_follow_the_metric_direction():
    upm = np.array([100.0, 50.0, 80.0, 20.0])
    other = np.array([90.0, 50.0, 85.0, 10.0])
    higher = compare(upm, other, "higher", seed=0)
    assert (higher.wins, higher.ties, higher.losses) == (2, 1, 1)
    lower = compare(upm, other, "lower", seed=0)
    assert (lower.wins, lower.ties, lower.losses) == (1, 1, 2)
    assert higher.difference.mean == pytest.approx(3.75)


def _pairs(n: int, records: Records | None = None) -> list[dict]:
    rng = np.random.default_rng(2)
    pairs = []
    for i in range(n):
        if records is not None:
            for m in ("upm", "linear"):
                records.add("pair", i, 20, m, {k: float(rng.normal(1.0 if m == "upm" else 2.0,
                                                                   0.1)) for k in METRICS})
        pairs.append({"id": i, "ab_distance_deg": float(i), "seen": i % 3 == 0,
                      "flat_floor": i % 2 == 0, "end_self_collision": [False, i == 1]})
    return pairs


def test_groups_partition_the_pairs():
    groups, edges = pair_groups(_pairs(30))
    for a, b in (("seen", "unseen"), ("flat_floor", "uneven_floor")):
        assert not (groups[a] & groups[b]).any() and (groups[a] | groups[b]).all()
    terciles = groups["ab_near"].astype(int) + groups["ab_middle"] + groups["ab_far"]
    assert (terciles == 1).all()
    assert [groups[g].sum() for g in ("ab_near", "ab_middle", "ab_far")] == [10, 10, 10]
    assert edges[0] < edges[1]


def test_study_statistics_has_every_method_metric_and_comparison():
    records = Records(METRICS)
    pairs = _pairs(12, records)
    real = {20: [{"id": i, "clip": "02_01" if i % 2 else "16_15", "flat_floor": True}
                 for i in range(6)]}
    for w in real[20]:
        records.add(REAL, w["id"], 20, REAL, {k: 1.5 for k in METRICS})
    stats = summarise(records, METRICS, pairs, real, ("upm", "linear"), (20,), seed=0)
    assert {(m, k) for (w, g, m, k) in stats.summary if g == "all"} == {
        (m, k) for m in ("upm", "linear", REAL) for k in METRICS}
    assert stats.interval(20, REAL, "valid_pct") == {"mean": 1.5, "lo": 1.5, "hi": 1.5, "n": 6}
    # UPM's values are lower everywhere: it wins the lower-is-better metrics.
    assert stats.comparison(20, "linear", "jerk_rms_deg_s3")["wins"] == 12
    assert stats.comparison(20, "linear", "valid_pct")["losses"] == 12
    assert stats.comparison(20, "linear", "valid_pct")["hi"] < 0
    assert stats.groups["end_self_collision"] == {"A": 0, "B": 1, "either": 1}
    assert stats.clips(20) == ["02_01", "16_15"]
    assert stats.clip_mean(20, "16_15", "valid_pct") == 1.5
    assert stats.compared(20) == ["linear"] and stats.compared(10) == []
    with pytest.raises(KeyError, match="'valid_pc'"):
        stats.interval(20, "upm", "valid_pc")
    with pytest.raises(KeyError, match="'jerk_rms'"):
        stats.comparison(20, "linear", "jerk_rms")


def test_missing_figures_are_left_out_of_means_and_pairs():
    """A NaN (a figure that does not exist for that unit) is left out: the mean of the
    rest, and the pairs where both methods have it."""
    records = Records(METRICS)
    pairs = _pairs(4)
    for i, (u, x) in enumerate([(1.0, 2.0), (np.nan, 5.0), (3.0, np.nan), (2.0, 2.0)]):
        records.add("pair", i, 20, "upm", {"jerk_rms_deg_s3": u})
        records.add("pair", i, 20, "linear", {"jerk_rms_deg_s3": x})
    stats = summarise(records, {"jerk_rms_deg_s3": METRICS["jerk_rms_deg_s3"]}, pairs, {},
                      ("upm", "linear"), (20,), seed=0)
    assert stats.interval(20, "upm", "jerk_rms_deg_s3")["mean"] == 2.0
    assert stats.interval(20, "upm", "jerk_rms_deg_s3")["n"] == 3
    c = stats.comparison(20, "linear", "jerk_rms_deg_s3")
    assert (c["n"], c["wins"], c["ties"], c["losses"]) == (2, 1, 1, 0)
    assert stats.interval(20, REAL, "jerk_rms_deg_s3")["n"] == 0
