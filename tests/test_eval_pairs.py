"""The held-out protocol: seeded pairs of 200-frame segments from two different test clips,
balanced over the ordered clip pairs; real windows with context; exclusion zones."""

import pytest

from eval.pairs import (
    REAL_CONTEXT,
    SEGMENT_FRAMES,
    draw_pairs,
    draw_real_windows,
    exclusion_zones,
    real_exclusion_zone,
)
from upm.core.errors import UsageError


@pytest.fixture(scope="module")
def lengths(catalog):
    from eval.realdata import load_test_clips

    return {name: m.n_frames for name, m in load_test_clips(catalog).items()}


def test_test_clips_at_120_fps(lengths, catalog):
    assert set(lengths) == set(catalog.names("test"))
    assert lengths["141_04"] == 2 * 547 - 1  # stored at 60 fps
    assert lengths["02_03"] == 173  # shorter than a segment


def test_pairs_are_segments_of_two_different_clips(lengths):
    pairs = draw_pairs(lengths, 200, seed=0)
    assert [p.index for p in pairs] == list(range(200))
    for p in pairs:
        assert p.first.clip != p.second.clip
        for seg in (p.first, p.second):
            assert 0 <= seg.start < seg.stop <= lengths[seg.clip]
            assert seg.frames == min(SEGMENT_FRAMES, lengths[seg.clip])
    short = [s for p in pairs for s in (p.first, p.second) if s.clip == "02_03"]
    assert short and all((s.start, s.stop) == (0, 173) for s in short)


def test_pairs_visit_every_ordered_clip_pair_once_per_round(lengths):
    n = len(lengths) * (len(lengths) - 1)
    pairs = draw_pairs(lengths, n + 5, seed=3)
    first_round = {(p.first.clip, p.second.clip) for p in pairs[:n]}
    assert len(first_round) == n


def test_pairs_are_seeded(lengths):
    a, b = draw_pairs(lengths, 30, seed=1), draw_pairs(lengths, 30, seed=1)
    assert a == b
    assert draw_pairs(lengths, 30, seed=2) != a
    # More pairs extend the list; the first ones do not change.
    assert draw_pairs(lengths, 60, seed=1)[:30] == a


def test_real_windows_leave_context(lengths):
    for frames in (10, 40):
        windows = draw_real_windows(lengths, 50, frames, seed=0)
        assert len(windows) == 50
        assert len({w.clip for w in windows}) == len(lengths)
        for w in windows:
            assert w.frames == frames
            assert REAL_CONTEXT <= w.start and w.stop + REAL_CONTEXT <= lengths[w.clip]
    assert draw_real_windows(lengths, 5, 20, 7) == draw_real_windows(lengths, 5, 20, 7)
    assert draw_real_windows(lengths, 12, 20, 7)[:5] == draw_real_windows(lengths, 5, 20, 7)


def test_exclusion_zones_are_alike_for_pairs_and_real_windows(lengths):
    pair = draw_pairs(lengths, 1, seed=0)[0]
    zone1, zone2 = exclusion_zones(pair, 20, lengths)
    a = pair.first.stop - 1  # A
    assert zone1.clip == pair.first.clip and zone1.start == pair.first.start
    assert zone1.stop == min(lengths[zone1.clip], a + 1 + 20 + SEGMENT_FRAMES)
    b = pair.second.start  # B
    assert zone2.start == max(0, b - 20 - SEGMENT_FRAMES) and zone2.stop == pair.second.stop
    windows = draw_real_windows(lengths, 1, 20, seed=0)
    (zone,) = real_exclusion_zone(windows[0], lengths)
    assert zone.start == max(0, windows[0].start - SEGMENT_FRAMES)
    assert zone.stop == min(lengths[zone.clip], windows[0].stop + SEGMENT_FRAMES)


def test_bad_protocols():
    with pytest.raises(UsageError, match="two test clips"):
        draw_pairs({"02_01": 300}, 5, 0)
    with pytest.raises(UsageError, match="at least 1"):
        draw_pairs({"a": 300, "b": 300}, 0, 0)
    with pytest.raises(UsageError, match="long enough"):
        draw_real_windows({"a": 50, "b": 60}, 3, 40, 0)
