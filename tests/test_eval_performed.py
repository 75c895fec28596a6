"""The method performed in the study: scored on the first ``performed_pairs`` pairs only
(about 40 s a window), NaN rows for the others, which the summaries leave out and the
paired comparisons skip; ``upm eval --full`` includes it, the default study does not."""

import math

import pytest

from eval.metrics import METRICS
from eval.pairs import Pair, RealWindow, Segment
from eval.physics import PHYSICS_METRICS, records_of, task_list
from eval.records import Records
from eval.study import FULL_METHODS, STUDY_METHODS, StudyConfig
from eval.summaries import summarise
from upm.cli import main


def test_full_has_performed_and_the_default_study_not():
    assert "performed" in FULL_METHODS and "performed" not in STUDY_METHODS
    assert set(FULL_METHODS) - set(STUDY_METHODS) == {"performed"}
    config = StudyConfig(data_dir=".", pairs=5, methods=FULL_METHODS, performed_pairs=2)
    assert [config.scores("performed", i) for i in range(4)] == [True, True, False, False]
    assert config.scores("upm", 4) and "performed" not in config.kinematic_methods
    assert config.as_dict()["performed_pairs"] == 2


def test_unscored_pairs_are_nan_rows_left_out_of_the_summaries():
    pairs = [Pair(index=i, first=Segment("a", 0, 10), second=Segment("b", 0, 10))
             for i in range(4)]
    real = {20: [RealWindow(index=0, clip="a", start=0, frames=20)]}
    methods = ("upm", "performed")
    config = StudyConfig(data_dir=".", pairs=4, methods=methods, performed_pairs=2)
    units = task_list(pairs, real, methods, (20,), config.scores)
    every = task_list(pairs, real, methods, (20,))
    assert len(every) - len(units) == 2  # performed on pairs 2 and 3
    assert {u.index for u in units if u.method == "performed"} == {0, 1}
    done = {u.key: {m: float(u.index) for m in PHYSICS_METRICS} for u in units}
    skipped = [u for u in every if u.key not in {v.key for v in units}]
    records = records_of(units, done, skipped)
    values = records.values("pair", 20, "performed", "fell")
    assert values[:2].tolist() == [0.0, 1.0] and all(math.isnan(v) for v in values[2:])
    # the kinematic summaries: the same rule (summaries drop NaN; pairs with both)
    table = Records(METRICS)
    for i in range(4):
        table.add("pair", i, 20, "upm", {m: 1.0 + i for m in METRICS})
        table.add("pair", i, 20, "performed",
                  {m: (0.5 if i < 2 else math.nan) for m in METRICS})
    table.add("real", 0, 20, "real", {m: 1.0 for m in METRICS})
    pair_rows = [{"id": i, "ab_distance_deg": 10.0 * i, "seen": True, "flat_floor": True,
                  "end_self_collision": [False, False]} for i in range(4)]
    real_rows = {20: [{"id": 0, "clip": "a", "flat_floor": True}]}
    stats = summarise(table, METRICS, pair_rows, real_rows, methods, (20,), seed=0)
    metric = next(iter(METRICS))
    assert stats.interval(20, "performed", metric)["n"] == 2
    assert stats.interval(20, "upm", metric)["n"] == 4
    assert stats.comparison(20, "performed", metric)["n"] == 2


def test_performed_pairs_goes_with_performed(capsys):
    assert main(["eval", "--methods", "upm", "linear", "--performed-pairs", "3"]) == 2
    assert "--performed-pairs goes with the method performed" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["0", "-2"])
def test_performed_pairs_at_least_one(capsys, value):
    assert main(["eval", "--full", "--performed-pairs", value]) == 2
    assert "--performed-pairs must be at least 1" in capsys.readouterr().err
