"""Sequences: several pieces (different subjects and frame rates) joined into one motion."""

import numpy as np
import pytest

from tests.transition_data import window_edges
from upm.core.errors import UsageError
from upm.motion.resample import resample
from upm.transitions import Transition, build_sequence


@pytest.fixture(scope="module")
def pieces(catalog):
    return [catalog.load_ref("02_01@0:150"), catalog.load_ref("60_10@100:200"),
            catalog.load_ref("05_01@200:300")]


def test_sequence_layout(pieces):
    sequence = build_sequence(pieces, "inertialize", frames=20)
    motion = sequence.motion
    assert motion.fps == 120 and motion.skeleton is pieces[0].skeleton
    expected = [150, resample(pieces[1], 120.0).n_frames, 100]
    assert [s.stop - s.start for s in sequence.pieces] == expected
    assert [w.stop - w.start for w in sequence.windows] == [20, 20]
    assert motion.n_frames == sum(expected) + 40
    # Pieces and windows tile the motion in order.
    spans = sorted(list(sequence.pieces) + list(sequence.windows), key=lambda s: s.start)
    assert spans[0].start == 0 and spans[-1].stop == motion.n_frames
    assert all(a.stop == b.start for a, b in zip(spans[:-1], spans[1:], strict=True))
    # Each piece's postures are its own (the 60 fps one resampled).
    np.testing.assert_array_equal(motion.posture_deg[sequence.pieces[0]], pieces[0].posture_deg)
    np.testing.assert_allclose(motion.posture_deg[sequence.pieces[1]],
                               resample(pieces[1], 120.0).posture_deg)
    np.testing.assert_array_equal(motion.posture_deg[sequence.pieces[2]], pieces[2].posture_deg)
    assert len(sequence.seconds) == 2 and all(s > 0 for s in sequence.seconds)


def test_sequence_joins_are_continuous(pieces):
    sequence = build_sequence(pieces, "inertialize", frames=20)
    for window in sequence.windows:
        fake = Transition(motion=sequence.motion, window=window, method="inertialize",
                          frames=20, alpha=0.5, key_posture_deg=None, key_time=10.5,
                          seconds=0.0, heading_turn_deg=0.0, diagnostics={})
        (c0_a, c1_a), (c0_b, c1_b) = window_edges(fake)
        assert max(c0_a, c1_a, c0_b, c1_b) <= 0


def test_sequence_at_another_rate(pieces):
    sequence = build_sequence(pieces[:2], "linear", frames=10, fps=60.0)
    assert sequence.motion.fps == 60.0
    assert sequence.pieces[1].stop - sequence.pieces[1].start == pieces[1].n_frames


def test_one_piece_and_no_piece(pieces):
    one = build_sequence(pieces[:1], "linear")
    assert one.windows == () and one.motion.n_frames == pieces[0].n_frames
    with pytest.raises(UsageError, match="at least one"):
        build_sequence([], "linear")
    with pytest.raises(UsageError, match="no transition method"):
        build_sequence(pieces, "nope")
