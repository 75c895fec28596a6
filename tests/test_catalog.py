"""The clip catalogue and clip references."""

import warnings

import numpy as np
import pytest

from upm.core.errors import UsageError
from upm.motion.catalog import Catalog, ClipRef, parse_clip_ref


def test_catalogue_matches_clips_csv(catalog):
    assert len(catalog) == 26
    assert catalog.info("60_10").fps == 60 and catalog.info("141_01").fps == 60
    assert catalog.info("02_01").fps == 120
    assert catalog.info("02_01").split == "test" and catalog.info("02_02").split == "train"
    assert catalog.info("131_04").asf_path.name == "131.asf"
    assert len(catalog.names("train")) == 19 and len(catalog.names("test")) == 7
    assert catalog.names()[:3] == ["01_01", "01_08", "02_01"]


def test_unknown_clip_is_a_usage_error(catalog):
    with pytest.raises(UsageError, match="no clip '99_99'"):
        catalog.info("99_99")


@pytest.mark.parametrize("text, ref", [
    ("02_01", ClipRef("02_01")),
    ("02_01@10", ClipRef("02_01", 10)),
    ("02_01@10:200", ClipRef("02_01", 10, 200, True)),
    ("02_01@:200", ClipRef("02_01", None, 200, True)),
    ("02_01@-50:", ClipRef("02_01", -50, None, True)),
])
def test_parse_clip_ref(text, ref):
    assert parse_clip_ref(text) == ref
    assert str(parse_clip_ref(text)) == text


@pytest.mark.parametrize("text", ["", "02_01@", "02_01@a:b", "02_01@1:2:3", "a b"])
def test_bad_clip_refs(text):
    with pytest.raises(UsageError, match="bad clip reference"):
        parse_clip_ref(text)


def test_load_ref_slices(catalog):
    assert catalog.load_ref("02_01@10:30").n_frames == 20
    assert catalog.load_ref("02_01@5").n_frames == 1
    assert catalog.load_ref("02_01@-40:").n_frames == 40
    with pytest.raises(UsageError, match="out of range"):
        catalog.load_ref("02_01@300:400")


def test_unlisted_clip_read_at_120_with_warning(tmp_path, data_dir):
    (tmp_path / "02").mkdir()
    for name in ("02.asf", "02_03.amc"):
        (tmp_path / "02" / name).write_bytes((data_dir / "02" / name).read_bytes())
    (tmp_path / "02" / "02_99.amc").write_bytes((data_dir / "02" / "02_03.amc").read_bytes())
    (tmp_path / "clips.csv").write_text("clip,subject,fps,frames,split,description\n"
                                        "02_03,02,120,173,test,run\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        catalog = Catalog(tmp_path)
    assert any("02_99 is not in clips.csv" in str(w.message) for w in caught)
    assert catalog.info("02_99").fps == 120 and catalog.info("02_99").split == ""


def test_missing_data_dir(tmp_path):
    with pytest.raises(UsageError, match="does not exist"):
        Catalog(tmp_path / "nowhere")
    with pytest.raises(UsageError, match="no clips"):
        Catalog(tmp_path)


@pytest.mark.parametrize("ref, message", [
    ("02_01@200:100", "empty range \\(frame 200 is not before frame 100"),
    ("02_01@-3:-5", "empty range"),
    ("02_01@5:5", "empty range"),
    ("02_01@999999", "out of range"),
])
def test_reversed_and_out_of_range_frames_are_told_apart(catalog, ref, message):
    with pytest.raises(UsageError, match=message):
        catalog.load_ref(ref)


def test_negative_frames_count_from_the_end(catalog):
    motion = catalog.load("02_01")
    last3 = catalog.load_ref("02_01@-3:")
    assert last3.n_frames == 3
    assert np.array_equal(last3.posture_deg, motion.posture_deg[-3:])
    assert np.array_equal(catalog.load_ref("02_01@-1").posture_deg, motion.posture_deg[-1:])


def test_no_clips_csv_is_one_warning_never_a_silent_rate(tmp_path, data_dir):
    (tmp_path / "02").mkdir()
    for name in ("02.asf", "02_03.amc", "02_01.amc"):
        (tmp_path / "02" / name).write_bytes((data_dir / "02" / name).read_bytes())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        catalog = Catalog(tmp_path)
    messages = [str(w.message) for w in caught]
    assert len(messages) == 1, messages
    assert "no clips.csv" in messages[0] and "its 2 clips are read at 120 fps" in messages[0]
    assert all(info.fps == 120 for info in catalog)


@pytest.mark.parametrize("row, message", [
    ("02_03,inf", "outside"), ("02_03,nan", "outside"), ("02_03,0", "outside"),
    ("02_03", "columns"), (",120", "without a clip name"), ("02_03,1e400", "outside"),
])
def test_bad_clips_csv_rows_name_the_line(tmp_path, data_dir, row, message):
    from upm.core.errors import DataFileError

    (tmp_path / "02").mkdir()
    (tmp_path / "02" / "02_03.amc").write_bytes(b"1\n")
    (tmp_path / "clips.csv").write_text(f"clip,fps\n02_01,120\n{row}\n")
    with pytest.raises(DataFileError, match=message) as info:
        Catalog(tmp_path)
    assert info.value.path == str(tmp_path / "clips.csv") and info.value.line == 3
