"""The study's metrics on constructed cases: a window that is an exact real segment scores
what the real data scores; a frozen pose has no jerk and no foot skate where a foot is
planted (and a sliding one has); a window forced through the torso is in self-collision;
the pure metric functions on known inputs."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from eval.metrics import (
    METRICS,
    foot_skate_mps,
    horizontal_speed_mps,
    nearest_rms_deg,
    pose_distance_rms_deg,
    third_difference,
    unwrap_time_deg,
    window_jerk_rms,
)
from eval.pairs import RealWindow, Segment, real_exclusion_zone
from eval.realdata import RealPostures, load_test_clips
from eval.scoring import added_self_collision, feet_over_frames, score_window
from upm.motion.motion import Motion
from upm.motion.skeleton import joint_dof_index

FPS = 120.0


@pytest.fixture(scope="module")
def test_clips(catalog):
    return load_test_clips(catalog)


@pytest.fixture(scope="module")
def real(test_clips):
    return RealPostures.of(test_clips)


@pytest.fixture(scope="module")
def model(catalog):
    from humanoid_xml import catalog_model_path, load_model

    return load_model(catalog_model_path(catalog, "02"))


def _joined(before: Motion, window_posture, window_root, after: Motion) -> Motion:
    """A 'transition': clip 1, the given window frames, clip 2 (no method involved)."""
    return before.replace(posture_deg=np.concatenate([before.posture_deg, window_posture,
                                                      after.posture_deg]),
                          root=np.concatenate([before.root, window_root, after.root]),
                          extra_deg=None)


# --- a window that is an exact real segment ------------------------------------------------

@pytest.fixture(scope="module")
def real_segment(test_clips, real, model):
    walk = test_clips["02_01"]
    w0, w1 = 150, 170
    joined = _joined(walk.frames(0, w0), walk.posture_deg[w0:w1], walk.root[w0:w1],
                     walk.frames(w1, None))
    zones = real_exclusion_zone(RealWindow(0, "02_01", w0, w1 - w0), {"02_01": walk.n_frames})
    return {"walk": walk, "window": slice(w0, w1), "joined": joined,
            "own": score_window(model, joined, slice(w0, w1), real, []),
            "excluded": score_window(model, joined, slice(w0, w1), real, zones),
            "zones": zones}


def test_every_metric_is_scored(real_segment):
    assert list(real_segment["own"]) == list(METRICS)
    assert all(np.isfinite(v) for v in real_segment["own"].values())


def test_real_segment_scores_the_real_kinematics(real_segment, model):
    from controller.checks.validity import check_motion

    walk, window, scores = real_segment["walk"], real_segment["window"], real_segment["own"]
    validity = check_motion(model, walk, (window,))
    assert scores["valid_pct"] == pytest.approx(100 * validity.valid_beyond_ends[window].mean())
    assert scores["raw_valid_pct"] == pytest.approx(100 * validity.valid[window].mean())
    assert scores["self_collision_pct"] == pytest.approx(
        100 * validity.self_collision[window].mean())
    assert scores["added_limit_max_deg"] == pytest.approx(
        validity.added_excess_deg[window].max(), abs=1e-6)


def test_real_segment_is_its_own_nearest_real_posture(real_segment, real):
    """Its frames are in the bank: distance 0; with its zone excluded, the distance is the
    brute-force minimum over the rest of the bank."""
    assert real_segment["own"]["nearest_real_mean_deg"] == 0.0
    assert real_segment["own"]["nearest_real_max_deg"] == 0.0
    excluded = real_segment["excluded"]
    assert excluded["nearest_real_mean_deg"] > 0.5
    walk, window = real_segment["walk"], real_segment["window"]
    keep = real.allowed(real_segment["zones"])
    # 02_01 has 343 frames: all within 200 frames of the window, so all excluded.
    assert (~keep).sum() == walk.n_frames
    bank = real.postures_deg[keep]
    frames = walk.posture_deg[window][:, real.dofs]
    diff = (frames[:, None, :] - bank[None] + 180.0) % 360.0 - 180.0
    expected = np.sqrt((diff ** 2).mean(axis=2).min(axis=1))
    assert excluded["nearest_real_mean_deg"] == pytest.approx(expected.mean(), abs=1e-5)
    assert excluded["nearest_real_max_deg"] == pytest.approx(expected.max(), abs=1e-5)


def test_real_segment_jerk_and_dynamics(real_segment, model, real):
    from controller.checks.dynamics import root_residual
    from controller.qpos import to_qpos

    walk, window, scores = real_segment["walk"], real_segment["window"], real_segment["own"]
    angles = np.unwrap(walk.posture_deg[147:173][:, real.dofs], period=360.0, axis=0)
    jerk = np.diff(angles, n=3, axis=0) * FPS ** 3
    assert scores["jerk_rms_deg_s3"] == pytest.approx(np.sqrt(np.mean(jerk ** 2)), rel=1e-6)
    # The whole clip's inverse dynamics, read on the window: the 30 context frames give
    # the filter what it needs.
    whole = root_residual(model, to_qpos(model, walk), FPS).force_bw[window]
    assert scores["residual_force_mean_bw"] == pytest.approx(whole.mean(), abs=0.01)
    # A real walk barely needs a hand of god.
    assert scores["residual_force_mean_bw"] < 0.15
    # Foot skating read on the window is the whole clip's (the speeds at the window's
    # edges use the real frames beside it).
    centres, bottoms, foot = feet_over_frames(model, to_qpos(model, walk))
    skate = foot_skate_mps(centres, bottoms, foot, FPS)[window]
    assert scores["foot_skate_mps"] == pytest.approx(skate.mean(), abs=1e-6)


# --- a frozen pose -------------------------------------------------------------------------

def _standing(walk, model, frames: int, speed_mps: float = 0.0) -> Motion:
    """Frame 0 of the walk held still, lowered until its lowest foot geom is 1 cm above the
    floor, optionally sliding forward at ``speed_mps``."""
    from controller.qpos import to_qpos

    pose = walk.frames(0, 1)
    _, bottoms, _ = feet_over_frames(model, to_qpos(model, pose))
    root = np.repeat(pose.root, frames, axis=0)
    root[:, 1] -= bottoms.min() - 0.01
    root[:, 0] += speed_mps * np.arange(frames) / FPS
    return pose.replace(posture_deg=np.repeat(pose.posture_deg, frames, axis=0), root=root,
                        extra_deg=None)


def test_frozen_pose_has_no_jerk_and_no_foot_skate(test_clips, model, real):
    from controller.qpos import to_qpos

    still = _standing(test_clips["02_01"], model, 100)
    _, bottoms, foot = feet_over_frames(model, to_qpos(model, still))
    assert (bottoms.min(axis=1) < 0.05).all()  # a foot is planted: the zero is not vacuous
    scores = score_window(model, still, slice(40, 60), real, [])
    assert scores["jerk_rms_deg_s3"] == 0.0
    assert scores["foot_skate_mps"] == 0.0
    assert scores["added_limit_mean_deg"] == 0.0


def test_a_sliding_frozen_pose_skates_at_its_speed(test_clips, model, real):
    from controller.qpos import to_qpos

    slide = _standing(test_clips["02_01"], model, 100, speed_mps=0.8)
    scores = score_window(model, slide, slice(40, 60), real, [])
    _, bottoms, foot = feet_over_frames(model, to_qpos(model, slide))
    planted_feet = np.mean([(bottoms[40:60, foot == f].min(axis=1) < 0.05).mean()
                            for f in (0, 1)])
    assert scores["foot_skate_mps"] == pytest.approx(0.8 * planted_feet, rel=1e-3)
    assert scores["foot_skate_mps"] > 0.3
    assert scores["jerk_rms_deg_s3"] == 0.0


# --- a window forced through the torso ----------------------------------------------------

def test_window_through_the_torso_is_self_collision(test_clips, model, real):
    """The right arm swung in (rhumerus rz to -150 deg: deep into the upper back, past the
    5 cm the soft tissue of an arm on the torso allows) and out again inside the window;
    the ends are a clean walking pose."""
    pose = _standing(test_clips["02_01"], model, 1)  # feet 1 cm above the floor
    length = 20
    column = joint_dof_index("rhumerus", "rz")
    window = np.repeat(pose.posture_deg, length, axis=0)
    start = window[0, column]
    ramp = 1.0 - np.abs(np.linspace(-1.0, 1.0, length))
    window[:, column] = start + ramp * (-150.0 - start)
    held = pose.replace(posture_deg=np.repeat(pose.posture_deg, 40, axis=0),
                        root=np.repeat(pose.root, 40, axis=0), extra_deg=None)
    joined = _joined(held, window, np.repeat(pose.root, length, axis=0), held)
    scores = score_window(model, joined, slice(40, 40 + length), real, [])
    assert scores["self_collision_pct"] > 30.0
    assert scores["self_collision_added_pct"] == scores["self_collision_pct"]
    assert scores["self_depth_max_mm"] > 60.0
    assert scores["valid_pct"] < 70.0
    calm = score_window(model, held, slice(10, 30), real, [])
    assert calm["self_collision_pct"] == 0.0 and calm["valid_pct"] == 100.0


def test_added_self_collision_ignores_pairs_the_ends_have():
    frames = [{"a-b": 0.01}, {"a-b": 0.02}, {"a-b": 0.02, "c-d": 0.01}, {}, {"a-b": 0.005}]
    assert added_self_collision(frames).tolist() == [False, True, False]


# --- pure functions ------------------------------------------------------------------------

def test_third_difference_of_a_cubic_is_constant():
    t = np.arange(12) / FPS
    values = (2.0 * t ** 3 - t ** 2 + 5.0)[:, None]
    assert np.allclose(third_difference(values, FPS), 12.0)


def test_window_jerk_counts_the_stencils_touching_the_window():
    posture = np.zeros((30, 63))
    posture[10:, 0] = 1.0  # a step at frame 10: stencils starting at 7, 8, 9 see it
    dofs = np.zeros(63, dtype=bool)
    dofs[0] = True
    assert window_jerk_rms(posture, slice(20, 25), FPS, dofs) == 0.0
    assert window_jerk_rms(posture, slice(10, 15), FPS, dofs) > 0.0
    assert window_jerk_rms(posture, slice(5, 8), FPS, dofs) > 0.0  # stencil 7: frames 7-10


def test_unwrap_time_crosses_180_without_a_jump():
    angles = np.array([[170.0], [178.0], [-174.0], [-166.0]])
    assert np.allclose(unwrap_time_deg(angles)[:, 0], [170, 178, 186, 194])
    assert third_difference(unwrap_time_deg(angles), FPS) == pytest.approx(0.0)


def test_horizontal_speed_ignores_height():
    t = np.arange(10) / FPS
    points = np.stack([0.5 * t, 0.0 * t, 3.0 * t], axis=1)[:, None, :]
    assert np.allclose(horizontal_speed_mps(points, FPS), 0.5)


def test_foot_skate_uses_the_lowest_geom_of_each_foot():
    t = np.arange(5) / FPS
    centres = np.zeros((5, 3, 3))
    centres[:, 0, 0] = 1.0 * t   # foot 0, geom 0 slides at 1 m/s
    centres[:, 1, 0] = 2.0 * t   # foot 0, geom 1 at 2 m/s
    centres[:, 2, 1] = 3.0 * t   # foot 1 at 3 m/s, always in the air
    bottoms = np.array([[0.01, 0.02, 0.2]] * 5)
    bottoms[3:, 1] = 0.0  # geom 1 becomes the lowest
    skate = foot_skate_mps(centres, bottoms, [0, 0, 1], FPS)
    assert np.allclose(skate[:3, 0], 1.0) and np.allclose(skate[3:, 0], 2.0)
    assert np.allclose(skate[:, 1], 0.0)


angles = st.floats(-720, 720, allow_nan=False, allow_infinity=False)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(angles, angles, angles), min_size=1, max_size=6),
       st.lists(st.tuples(angles, angles, angles), min_size=1, max_size=4),
       st.integers(-2, 2))
def test_nearest_rms_is_exact_and_periodic(bank, points, turns):
    bank, points = np.array(bank), np.array(points)
    got = nearest_rms_deg(points, bank, chunk_bytes=64)
    brute = np.array([min(pose_distance_rms_deg(p, b) for b in bank) for p in points])
    assert np.allclose(got, brute, atol=1e-9)
    assert np.allclose(nearest_rms_deg(points + 360.0 * turns, bank), got, atol=1e-9)


def test_real_postures_zones(real, test_clips):
    n = sum(m.n_frames for m in test_clips.values())
    assert real.postures_deg.shape == (n, 45) and real.dofs.sum() == 45
    keep = real.allowed([Segment("02_03", 0, 10**6), Segment("02_01", 100, 120)])
    assert (~keep).sum() == test_clips["02_03"].n_frames + 20


def test_foot_geom_bottoms_match_mujoco_distance_to_the_floor(test_clips, model):
    import mujoco

    from controller.qpos import to_qpos
    from eval.scoring import foot_geoms

    qpos = to_qpos(model, test_clips["02_01"])[::37]
    centres, bottoms, _ = feet_over_frames(model, qpos)
    geoms, _ = foot_geoms(model)
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    data = mujoco.MjData(model)
    for t, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        for k, g in enumerate(geoms):
            distance = mujoco.mj_geomDistance(model, data, floor, int(g), 1.0, None)
            assert bottoms[t, k] == pytest.approx(distance, abs=1e-6)
