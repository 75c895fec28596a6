"""The long-form results table: one registry of metrics (a misspelt name raises at once,
naming it), one CSV writer, and a CSV that reads back to the same table with int windows."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from eval.metrics import METRICS
from eval.records import COLUMNS, REAL, Records, csv_text
from upm.core.errors import DataFileError


def _table() -> Records:
    records = Records(METRICS)
    records.add("pair", 1, 20, "upm", {"valid_pct": 55.0, "jerk_rms_deg_s3": 423123.456789})
    records.add("pair", 0, 20, "upm", {"valid_pct": 1 / 3, "jerk_rms_deg_s3": math.nan})
    records.add("pair", 0, 10, "linear", {"valid_pct": 100.0})
    records.add(REAL, 0, 20, REAL, {"valid_pct": 62.5})
    return records


def test_a_misspelt_metric_raises_naming_it():
    records = _table()
    with pytest.raises(KeyError, match="'valid_pc'"):
        records.add("pair", 2, 20, "upm", {"valid_pc": 1.0})
    with pytest.raises(KeyError, match="'jerk_rms_deg_s'"):
        records.values("pair", 20, "upm", "jerk_rms_deg_s")
    assert records.ids("pair", 20, "upm") == [0, 1]  # nothing of the bad row was added
    with pytest.raises(KeyError, match="'kinematic'"):
        records.add("kinematic", 0, 20, "upm", {"valid_pct": 1.0})
    with pytest.raises(KeyError, match="'upm'"):
        records.add(REAL, 0, 20, "upm", {"valid_pct": 1.0})


def test_values_follow_the_ids_asked_for():
    records = _table()
    assert records.values("pair", 20, "upm", "valid_pct").tolist() == [1 / 3, 55.0]
    assert records.values("pair", 20, "upm", "valid_pct", [1, 0]).tolist() == [55.0, 1 / 3]
    with pytest.raises(KeyError, match="no row"):
        records.values("pair", 20, "upm", "valid_pct", [7])


def test_the_table_round_trips_through_its_csv_with_int_windows():
    records = _table()
    text = records.to_csv()
    lines = text.splitlines()
    assert lines[0] == ",".join(COLUMNS)
    assert "pair,0,20,upm,jerk_rms_deg_s3," in lines  # NaN: an empty cell
    back = Records.from_csv(text, METRICS, "scores.csv")
    assert back == records and back.to_csv() == text
    for (kind, index, window, method, metric, value), again in zip(records.rows(), back.rows(),
                                                                   strict=True):
        assert type(again[2]) is int and again[2] == window and type(again[1]) is int
        assert again[:5] == (kind, index, window, method, metric)
        assert (math.isnan(value) and math.isnan(again[5])) or again[5] == value
    assert back.values("pair", 20, "upm", "valid_pct", [0])[0] == 1 / 3  # every digit kept
    assert back.ids("pair", 10, "linear") == [0]


@pytest.mark.parametrize("line, message", [
    ("pair,0,20,upm,valid_pc,1.0", "'valid_pc' is not in the registry"),
    ("pair,0,20.5,upm,valid_pct,1.0", "must be integers"),
    ("pair,0,20,upm,valid_pct,lots", "a number"),
    ("pair,0,20,upm,valid_pct", "5 cells, not 6"),
    ("dream,0,20,upm,valid_pct,1.0", "'dream'"),
    ("pair,0,20,upm,valid_pct,4.0", "a second row for pair 0, window 20, upm, valid_pct"),
])
def test_reading_a_bad_csv_names_the_file_and_line(line, message):
    text = ",".join(COLUMNS) + "\npair,0,20,upm,valid_pct,3.0\n" + line + "\n"
    with pytest.raises(DataFileError, match=message) as caught:
        Records.from_csv(text, METRICS, "scores.csv")
    assert str(caught.value).startswith("scores.csv:3: ")
    with pytest.raises(DataFileError, match="scores.csv:1: the header"):
        Records.from_csv("kind,id,L,method,metric,value\n", METRICS, "scores.csv")


def test_one_csv_writer_for_every_table():
    text = csv_text(("window_frames", "method", "mean", "n"),
                    [(20, "upm", 0.1 + 0.2, 3), (20, "a, b", None, 0),
                     (10, "real", math.nan, 2)])
    assert text.splitlines() == ["window_frames,method,mean,n",
                                 "20,upm,0.30000000000000004,3", '20,"a, b",,0', "10,real,,2"]
    with pytest.raises(ValueError, match="2 cells under 4 columns"):
        csv_text(("a", "b", "c", "d"), [(1, 2)])


_rows = st.lists(st.tuples(
    st.sampled_from(("pair", REAL)), st.integers(0, 10 ** 6), st.integers(1, 240),
    st.sampled_from(("upm", "linear", 'a "quoted", comma')), st.sampled_from(tuple(METRICS)),
    st.floats(allow_nan=True, allow_infinity=True)), max_size=30)


@given(_rows)
def test_any_table_reads_back_from_its_csv_exactly(rows):
    records = Records(METRICS)
    expected = {}
    for kind, index, window, method, metric, value in rows:
        method = REAL if kind == REAL else method
        records.add(kind, index, window, method, {metric: value})
        expected[(kind, index, window, method, metric)] = value
    back = Records.from_csv(records.to_csv(), METRICS, "scores.csv")
    assert back == records and len(back) == len(expected)
    for kind, index, window, method, metric, value in back.rows():
        want = expected[(kind, index, window, method, metric)]
        assert (math.isnan(want) and math.isnan(value)) or (
            value == want and math.copysign(1, value) == math.copysign(1, want))
        assert index in back.ids(kind, window, method)
