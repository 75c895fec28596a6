"""Gait-phase-matched cuts: where a clip ends so that the next one follows it at the same
phase of the stride, on the real walks."""

import json

import numpy as np
import pytest

from upm.cli import main
from upm.motion.kinematics import forward_kinematics
from upm.transitions import build_sequence
from upm.transitions.cuts import MATCH_SEARCH_S, matched_cut, matched_pieces


@pytest.fixture(scope="module")
def walks(catalog):
    return catalog.load("02_01"), catalog.load("02_02")


def _window_ankle_speed_mps(sequence) -> float:
    """The largest horizontal ankle speed from 2 frames before the first window to 2 after."""
    motion = sequence.motion
    skeleton = motion.skeleton
    ankles = forward_kinematics(motion)[:, [skeleton.bone_index(b) for b in ("ltibia",
                                                                           "rtibia")]]
    speed = np.linalg.norm(np.gradient(ankles[:, :, [0, 2]], 1.0 / motion.fps, axis=0), axis=2)
    window = sequence.windows[0]
    return float(speed[window.start - 2:window.stop + 2].max())


@pytest.mark.parametrize("stop", [200, 250, 300])
def test_a_clip_cut_against_its_own_continuation_is_cut_where_it_continues(walks, stop):
    walk = walks[0]
    cut = matched_cut(walk.frames(0, stop + 60), walk.frames(stop))
    assert stop <= cut.stop - 1 <= stop + 1  # its frame stop (velocities differ at the ends)
    assert cut.distance_m < 0.02 < cut.whole_distance_m


@pytest.mark.parametrize("order", [(0, 1), (1, 0)])
def test_walks_joined_at_their_gait_phase_skate_less_in_the_window(walks, order):
    pieces = [walks[i] for i in order]
    cut_pieces, (cut,) = matched_pieces(pieces)
    before = pieces[0]
    assert before.n_frames - MATCH_SEARCH_S * before.fps <= cut.stop < before.n_frames
    assert cut_pieces[0].n_frames == cut.stop and cut_pieces[1] is pieces[1]
    # the whole clip ends at another phase: its feet are several times further off
    assert cut.distance_m < 0.25 * cut.whole_distance_m
    whole = _window_ankle_speed_mps(build_sequence(pieces, "linear"))
    matched = _window_ankle_speed_mps(build_sequence(cut_pieces, "linear"))
    assert whole > 4.5 and matched < 0.7 * whole


def test_the_cut_does_not_depend_on_where_the_next_clip_stands(walks):
    before, after = walks
    moved = after.replace(root=after.root + np.array([1.5, 0.0, -2.0, 0.0, 0.0, 0.0]))
    cut, cut_moved = matched_cut(before, after), matched_cut(before, moved)
    assert cut_moved.stop == cut.stop
    assert cut_moved.distance_m == pytest.approx(cut.distance_m, abs=1e-9)


def test_upm_sequence_cut_matched_reports_the_pieces_it_used(data_dir, tmp_path, capsys):
    out, report = tmp_path / "s.amc", tmp_path / "s.json"
    assert main(["sequence", "--data", str(data_dir), "02_01", "02_02@10:200", "02_01",
                 "--method", "linear", "--cut", "matched", "--out", str(out),
                 "--json", str(report)]) == 0
    printed = capsys.readouterr().out
    clips = [p["clip"] for p in json.loads(report.read_text())["pieces"]]
    assert clips[0].startswith("02_01@0:") and clips[1].startswith("02_02@10:")
    assert clips[2] == "02_01"
    first, second = (int(c.rsplit(":", 1)[1]) for c in clips[:2])
    assert 343 - 144 <= first < 343 and 200 - 144 <= second < 200
    assert f"cut {clips[0]}: its feet" in printed


def test_cut_matched_refuses_a_held_pose(data_dir, tmp_path, capsys):
    code = main(["sequence", "--data", str(data_dir), "02_01@100", "02_02", "--method",
                 "linear", "--cut", "matched", "--out", str(tmp_path / "s.amc")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "02_01@100 is one" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "s.amc").exists()


@pytest.mark.parametrize("frames", [2, 3, 50, 200])
def test_a_short_piece_keeps_at_least_half_its_frames(walks, frames):
    before = walks[0].frames(100, 100 + frames)
    cut = matched_cut(before, walks[1])
    assert max(2, (frames + 1) // 2) <= cut.stop <= frames
