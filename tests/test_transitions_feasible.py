"""``feasible``: every window frame inside the allowed range (the study's rule), C1 joins,
a key posture the humanoid takes without a new self-collision, on real pairs; where the
UPM key breaks a limit, feasible does not; the window check counts what the study counts
and keeps the better window; ``upm`` stays free of MuJoCo."""

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

import upm.transitions.feasible as feasible_module
from controller.checks.kinematic_check import HumanoidChecker
from controller.checks.validity import added_excess, check_motion, limit_excess
from tests.transition_data import (
    PAIRS,
    catalog_of,
    feasible_limit_turns,
    pair,
    sources,
    window_edges,
)
from upm.motion.range_models import range_model
from upm.transitions import make_problem, transition
from upm.transitions.feasible import FeasibleKeys, allowed_range, long_way_turns
from upm.transitions.feasible_range import range_boxes_deg

#: A real pair beyond tests/transition_data.PAIRS, from a random draw: the short way from
#: A to B in rfoot.rz leaves its human range's box ([-99.7, 99.7], widened by the ends'
#: excess to about +-140 but not across 180), so the window must go the long way round.
LONG_WAY = ("05_06", 682, "05_11", 215)
#: A real pair whose UPM window breaks a coupled rule of the human range (the right
#: shoulder) by 46 degrees beyond the ends, inside every per-DOF box.
UPM_BEYOND_RULES = ("83_26", 432, "05_11", 23)


def _pair(data_dir, spec, frames=40):
    catalog = catalog_of(data_dir)
    name1, a, name2, b = spec
    return (catalog.load(name1).frames(a + 1 - frames, a + 1),
            catalog.load(name2).frames(b, b + frames))


def _real_pairs(data_dir):
    return [pair(data_dir, i) for i in range(len(PAIRS))] + [_pair(data_dir, LONG_WAY)]


def _added_excess_deg(result, boxes=None) -> np.ndarray:
    """The added excess of the window frames beyond per-DOF boxes (feasible's: the human
    range's, by default), (L, 63): beyond the larger excess of A and B, per DOF
    (controller.checks.validity)."""
    ends = result.motion.posture_deg[result.a_index:result.b_index + 1]
    boxes = range_boxes_deg(result.motion.skeleton) if boxes is None else boxes
    excess = limit_excess(ends, boxes)
    return added_excess(excess, [slice(1, ends.shape[0] - 1)])[1:-1]


def _added_rule_excess_deg(result) -> np.ndarray:
    """The study's added excess of the window frames beyond the human range's rules
    (coupled rules included), (L, R)."""
    frames = result.motion.posture_deg[result.a_index:result.b_index + 1]
    excess = range_model("human").excess_deg(result.motion.skeleton, frames)
    return added_excess(excess, [slice(1, frames.shape[0] - 1)])[1:-1]


def test_every_frame_in_range_joins_c1_and_key_collision_free(data_dir):
    feasible = sources(data_dir)["feasible"]
    long_way_seen = False
    for before, after in _real_pairs(data_dir):
        a = before.posture_deg[-1]
        result = transition("feasible", before, after, 20, 0.5, feasible)
        assert _added_excess_deg(result).max() <= 1e-6
        if result.diagnostics["window_invalid_frames"] == 0:  # the rules hold as well
            assert _added_rule_excess_deg(result).max() <= 1e-6
        (c0_a, c1_a), (c0_b, c1_b) = window_edges(result, feasible_limit_turns(before, after))
        assert max(c0_a, c0_b, c1_a, c1_b) <= 0, (c0_a, c1_a, c0_b, c1_b)
        # The key: no self-collision on the humanoid that A and B do not already have.
        checker = HumanoidChecker(before.skeleton)
        ends = frozenset().union(*checker.self_collision_pairs(
            np.stack([a, after.posture_deg[0]])))
        assert not checker.self_collision_pairs(result.key_posture_deg)[0] - ends
        assert result.diagnostics["key_admissible"] == 1.0
        long_way_seen |= result.diagnostics["long_way_dofs"] > 0
    assert long_way_seen


def test_the_checker_agrees_with_the_study(data_dir):
    """HumanoidChecker's pairs are the study's (controller.checks.validity on the subject's model)
    on real frames with and without self-collision."""
    from humanoid_xml import catalog_model_path, load_model

    catalog = catalog_of(data_dir)
    motion = catalog.load("05_11")
    frames = motion.frames(0, 400)
    study = check_motion(load_model(catalog_model_path(catalog, "05_11")), frames)
    expected = [frozenset(p) for p in study.self_pairs()]
    found = HumanoidChecker(motion.skeleton).self_collision_pairs(frames.posture_deg)
    assert any(expected) and not all(expected)
    assert found == expected


def test_the_checker_finds_the_studys_floor_penetration(data_dir):
    """With the root, HumanoidChecker's floor check is the study's on a clip that goes
    below the floor, deeper than its body classes allow, on some frames (131_04: a toe
    6 cm down)."""
    from humanoid_xml import catalog_model_path, load_model

    catalog = catalog_of(data_dir)
    motion = catalog.load("131_04")
    study = check_motion(load_model(catalog_model_path(catalog, "131_04")), motion)
    colliding, floor = HumanoidChecker(motion.skeleton).frame_checks(
        motion.posture_deg, motion.root, names=False)
    assert study.floor_penetration.any() and not study.floor_penetration.all()
    np.testing.assert_array_equal(floor, study.floor_penetration)
    np.testing.assert_array_equal(colliding, study.self_collision)


def _study_invalid_frames(data_dir, result) -> int:
    """Window frames the study finds in self-collision or below the floor."""
    from humanoid_xml import catalog_model_path, load_model

    model = load_model(catalog_model_path(catalog_of(data_dir), "02_01"))
    frames = result.motion.frames(result.a_index, result.b_index + 1)
    validity = check_motion(model, frames, (slice(1, result.frames + 1),))
    return int((validity.self_collision | validity.floor_penetration)[1:-1].sum())


def test_the_window_check_counts_what_the_study_counts_and_keeps_the_better_window(
        data_dir, monkeypatch):
    """02_01@200 -> 02_03@20: the window check counts the frames the study counts, for the
    first candidate key's window and for the one feasible keeps; it keeps the better
    (under the calibrated verdict the first candidate's window is already clean: a heel
    pad on the floor is no longer a foot through it, so it keeps that one)."""
    before, after = pair(data_dir, 0)
    feasible = sources(data_dir)["feasible"]
    chosen = transition("feasible", before, after, 20, 0.5, feasible)
    monkeypatch.setattr(feasible_module, "WINDOW_TRIES", 1)
    nearest = transition("feasible", before, after, 20, 0.5, feasible)
    for result in (chosen, nearest):
        assert result.diagnostics["floor_checked"] == 1.0
        assert result.diagnostics["window_invalid_frames"] == _study_invalid_frames(
            data_dir, result)
    assert _study_invalid_frames(data_dir, chosen) <= _study_invalid_frames(data_dir, nearest)
    if _study_invalid_frames(data_dir, nearest) == 0:
        assert chosen.diagnostics["key_candidate"] == 0.0
    assert _added_excess_deg(chosen).max() <= 1e-6


def test_where_the_upm_window_breaks_a_coupled_rule_feasible_does_not(data_dir):
    before, after = _pair(data_dir, UPM_BEYOND_RULES)
    upm = transition("upm", before, after, 20, 0.5, sources(data_dir)["upm"])
    feasible = transition("feasible", before, after, 20, 0.5, sources(data_dir)["feasible"])
    assert _added_excess_deg(upm).max() <= 1e-6  # inside every box: only the rule sees it
    assert _added_rule_excess_deg(upm).max() > 10.0
    assert feasible.diagnostics["key_admissible"] == 1.0
    assert feasible.diagnostics["window_invalid_frames"] == 0
    assert _added_rule_excess_deg(feasible).max() <= 1e-6
    assert _added_excess_deg(feasible).max() <= 1e-6


def test_without_a_checker_the_range_still_holds(data_dir):
    before, after = _pair(data_dir, LONG_WAY)
    bare = FeasibleKeys(sources(data_dir)["upm"])
    result = transition("feasible", before, after, 20, 0.5, bare)
    assert result.diagnostics["kinematic_checks"] == 0.0
    assert _added_excess_deg(result).max() <= 1e-6
    assert result.diagnostics["long_way_dofs"] >= 1


def test_the_long_way_is_taken_only_where_the_short_way_leaves_the_range(data_dir):
    before, after = _pair(data_dir, LONG_WAY)
    problem = make_problem(before, after, 20, 0.5)
    turns = long_way_turns(problem)
    dof = int(np.flatnonzero(turns)[0])
    linear = transition("linear", before, after, 20)
    boxes = range_boxes_deg(before.skeleton)
    assert limit_excess(linear.window_posture_deg, boxes)[:, dof].max() > (
        allowed_range(problem)[3][dof] + 10.0)
    moved = dataclasses.replace(problem, after_deg=problem.after_deg + 360.0 * turns)
    assert allowed_range(moved)[2][dof]


@pytest.mark.parametrize("frames", [1, 2, 4])
def test_short_windows_stay_feasible(data_dir, frames):
    """With one to four frames the joins and the range fight over few coefficients: the
    method still answers, in range (soft range only if the QP finds no solution)."""
    before, after = pair(data_dir, 0)
    result = transition("feasible", before, after, frames, 0.5, sources(data_dir)["feasible"])
    assert np.isfinite(result.window_posture_deg).all()
    if result.diagnostics["soft_range_dofs"] == 0:
        assert _added_excess_deg(result).max() <= 1e-6


def test_upm_stays_free_of_mujoco():
    code = ("import sys; from upm.transitions import METHODS, transition; "
            "import upm.transitions.feasible; assert 'feasible' in METHODS; "
            "assert 'mujoco' not in sys.modules and 'controller' not in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)
