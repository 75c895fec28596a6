"""Atomic output: a failure while writing leaves the old file and no temp files."""

import pytest

from upm.core.fileio import atomic_open, atomic_write_text


def test_failure_midway_leaves_the_old_file(tmp_path):
    out = tmp_path / "report.json"
    out.write_text("previous")
    with pytest.raises(RuntimeError), atomic_open(out) as handle:
        handle.write("half of a new fi")
        raise RuntimeError("disk full")
    assert out.read_text() == "previous"
    assert [p.name for p in tmp_path.iterdir()] == ["report.json"]


def test_success_replaces_and_creates_directories(tmp_path):
    out = tmp_path / "new" / "dir" / "a.txt"
    atomic_write_text(out, "hello\n")
    assert out.read_text() == "hello\n"
    atomic_write_text(out, "again\n")
    assert out.read_text() == "again\n"
    assert [p.name for p in out.parent.iterdir()] == ["a.txt"]


def test_permissions_are_those_of_a_plain_open(tmp_path):
    plain, atomic = tmp_path / "plain.txt", tmp_path / "atomic.txt"
    plain.write_text("x")
    atomic_write_text(atomic, "x")
    assert atomic.stat().st_mode == plain.stat().st_mode
