"""Kinematic validity per frame: hand-made postures flagged for exactly what is wrong with
them, the added excess of transition windows, and the calibration on the real clips (how
often real motion capture itself fails each check)."""

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from controller.checks.calibration import calibrate
from controller.checks.validity import (
    FLOOR_TOLERANCE_M,
    added_excess,
    check_motion,
    frame_records,
    summarize,
)
from humanoid_xml import build_mjcf
from tests.conftest import FLAT_WALK_RUN
from upm import Motion
from upm.motion.skeleton import joint_dof_index


@pytest.fixture(scope="module")
def skeleton02(catalog):
    return catalog.skeleton("02")


@pytest.fixture(scope="module")
def model02(skeleton02):
    return mujoco.MjModel.from_xml_string(build_mjcf(skeleton02))


@pytest.fixture(scope="module")
def calibration(catalog):
    return calibrate(catalog)


def _standing(skeleton, n: int = 2, height_m: float | None = None) -> Motion:
    """The rest posture on the floor (the model's rest root height), n frames."""
    model = mujoco.MjModel.from_xml_string(build_mjcf(skeleton))
    ty = float(model.qpos0[2]) if height_m is None else height_m
    root = np.tile([0.0, ty, 0.0, 0.0, 0.0, 0.0], (n, 1))
    return Motion(skeleton, np.zeros((n, 63)), root, fps=120.0, name="standing")


def test_rest_posture_on_the_floor_is_valid(model02, skeleton02):
    validity = check_motion(model02, _standing(skeleton02))
    assert validity.valid.all()
    assert not validity.limit_violation.any()
    assert validity.floor_depth_m.max() < 1e-4


def test_posture_20_degrees_past_a_limit_is_flagged_by_that_dof(model02, skeleton02):
    motion = _standing(skeleton02, 3)
    dof = joint_dof_index("lfemur", "rx")
    lo, hi = skeleton02.limits_deg[dof]
    posture = motion.posture_deg.copy()
    posture[1, dof] = hi + 20.0
    posture[2, dof] = lo - 20.0 + 360.0  # the same excess, written unwrapped
    validity = check_motion(model02, motion.replace(posture_deg=posture), limits="asf")
    assert list(validity.limit_violation) == [False, True, True]
    for frame in (1, 2):
        flagged = validity.violating_dofs(frame)
        assert list(flagged) == ["lfemur.rx"]
        assert flagged["lfemur.rx"] == pytest.approx(20.0, abs=1e-9)
    assert list(validity.valid) == [True, False, False]
    record = frame_records(validity)[1]
    assert record["limit_dofs"] == {"lfemur.rx": pytest.approx(20.0)}
    assert summarize(validity)["dofs"] == {"lfemur.rx": 2}


def test_arm_folded_through_the_torso_is_a_self_collision_of_those_bodies(model02,
                                                                          skeleton02):
    motion = _standing(skeleton02)
    posture = motion.posture_deg.copy()
    for (joint, axis), value in {("lhumerus", "rx"): -30, ("lhumerus", "ry"): 60,
                                 ("lhumerus", "rz"): 90, ("lradius", "rx"): 90}.items():
        posture[1, joint_dof_index(joint, axis)] = value
    validity = check_motion(model02, motion.replace(posture_deg=posture))
    assert list(validity.self_collision) == [False, True]
    assert not validity.limit_violation[1]  # inside the limits: only the collision is wrong
    pairs = validity.self_pairs()[1]
    assert any(p in pairs for p in ("thorax-lhumerus", "upperback-lhumerus",
                                    "thorax-lradius", "upperback-lradius"))
    assert all("lhumerus" in p or "lradius" in p or "lhand" in p for p in pairs)
    assert validity.self_depth_m[1] > 0.01
    assert list(validity.valid) == [True, False]


def test_root_sunk_10_cm_is_a_floor_penetration(model02, skeleton02):
    rest = float(model02.qpos0[2])
    motion = _standing(skeleton02, 3)
    root = motion.root.copy()
    root[1, 1] = rest - 0.10
    root[2, 1] = rest - 0.005  # 5 mm: within the 1 cm tolerance
    validity = check_motion(model02, motion.replace(root=root))
    np.testing.assert_allclose(validity.floor_depth_m, [0.0, 0.10, 0.005], atol=2e-4)
    assert list(validity.floor_penetration) == [False, True, False]
    assert list(validity.valid) == [True, False, True]
    assert not validity.self_collision.any()
    assert FLOOR_TOLERANCE_M == 0.01


def test_added_excess_counts_only_what_the_window_adds():
    excess = np.zeros((8, 3))
    excess[2] = [5.0, 0.0, 1.0]  # the frame before the window (clip 1's last)
    excess[3:6] = [[6.0, 2.0, 0.5], [4.0, 0.0, 0.0], [7.0, 3.0, 1.0]]
    excess[6] = [0.0, 2.5, 0.0]  # the frame after it (clip 2's first)
    added = added_excess(excess, [slice(3, 6)])
    np.testing.assert_allclose(added[3:6], [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0],
                                            [2.0, 0.5, 0.0]])
    assert not added[:3].any() and not added[6:].any()


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 6), st.integers(1, 4),
       st.lists(st.floats(0, 50, allow_nan=False), min_size=24, max_size=24))
def test_added_excess_is_never_negative_nor_above_the_excess(start, length, values):
    excess = np.array(values).reshape(8, 3)
    window = slice(start, min(start + length, 8))
    added = added_excess(excess, [window])
    assert np.all(added >= 0) and np.all(added <= excess + 1e-12)


def test_window_frames_are_marked_and_judged_beyond_their_ends(model02, skeleton02):
    motion = _standing(skeleton02, 6)
    dof = joint_dof_index("rtibia", "rx")
    lo = skeleton02.limits_deg[dof, 0]
    posture = motion.posture_deg.copy()
    posture[:, dof] = [0, lo - 10, lo - 12, lo - 9, lo - 10, 0]  # ends already 10 beyond
    validity = check_motion(model02, motion.replace(posture_deg=posture), [slice(2, 4)],
                            limits="asf")
    assert list(validity.in_window) == [-1, -1, 0, 0, -1, -1]
    np.testing.assert_allclose(validity.added_excess_deg[:, dof], [0, 0, 2, 0, 0, 0])
    assert list(validity.valid_beyond_ends) == [True, False, False, True, False, True]
    records = frame_records(validity)
    assert records[2]["window"] == 0 and records[2]["added_dofs"] == {"rtibia.rx": 2.0}
    assert "added_dofs" not in records[0]
    summary = summarize(validity, slice(2, 4))
    assert summary["added_limit_violation_frames"] == 1
    assert summary["added_excess_peak_deg"] == pytest.approx(2.0)


def test_calibration_on_the_test_split(calibration, catalog):
    """The calibrated verdict on the 3,079 test frames: measured 90.3 % valid (the ASF's
    boxes: 38.7 %, with 61.3 % of the frames beyond them, 05_11 nearly always)."""
    test = calibration.totals(catalog.names("test"))
    assert test["frames"] == 3079
    assert test["valid_pct"] > 88
    assert 50 < test["beyond_asf_pct"] < 75
    assert calibration.clips["05_11"]["beyond_asf_pct"] > 95
    assert calibration.clips["05_11"]["valid_pct"] > 85
    for clip in ("02_01", "02_03", "03_01", "16_15"):  # walks, a run, uneven ground
        assert calibration.clips[clip]["valid_pct"] == 100.0


def test_calibration_on_every_clip(calibration):
    """All 28,437 frames: 94.2 % valid under the human verdict; the ASF's boxes are broken
    in 73 % of them. What still fails is named: 05_06's cartwheel (its feet solved turned
    through 90-105 degrees, and through the floor), 05_16's twisted thigh, 131_04's hands
    deep in the pelvis."""
    total = calibration.totals()
    assert total["clips"] == 26 and total["frames"] == 28437
    assert total["valid_pct"] > 92
    assert 60 < total["beyond_asf_pct"] < 90
    walks = calibration.totals(FLAT_WALK_RUN)
    assert walks["valid_pct"] > 99
    assert calibration.clips["05_06"]["valid_pct"] < 20
    for row in calibration.clips.values():
        assert row["valid_frames"] <= row["frames"] - max(row["limit_violation_frames"],
                                                          row["self_collision_frames"],
                                                          row["floor_penetration_frames"])


def test_summaries_agree_with_frame_records(model02, walk):
    validity = check_motion(model02, walk)
    records = frame_records(validity)
    summary = summarize(validity)
    assert len(records) == walk.n_frames == summary["frames"]
    assert summary["valid_frames"] == sum(r["valid"] for r in records)
    assert summary["self_collision_frames"] == sum(bool(r["self_pairs"]) for r in records)
    assert summary["limit_violation_frames"] == sum(bool(r["limit_dofs"]) for r in records)
    for r in records:
        assert r["valid"] == (not r["limit_violation"] and not r["self_collision"]
                              and not r["floor_penetration"])
        assert set(r["limit_dofs"]) <= set(validity.rule_names)
