"""The balance controller: with the root free and no external force the humanoid walks
through the real clip 02_01 (where the position servos alone fall), the recorded torques
replay open-loop to the same motion, the same inputs give the same run, and a reference
that cannot be followed is reported as a fall with its time."""

import dataclasses
import math

import mujoco
import numpy as np
import pytest

from controller import to_qpos
from controller.balance.control import torque_model
from controller.balance.follow import follow
from controller.balance.run import WINDOW_KEYS, replay, window_summary
from controller.qpos import joint_layout
from controller.tracking.servo import track_qpos

pytestmark = pytest.mark.physics  # free-root runs


@pytest.fixture(scope="module")
def walk_qpos(model02, walk):
    return to_qpos(model02, walk)


@pytest.fixture(scope="module")
def walk_run(model02, walk_qpos, walk):
    return follow(model02, walk_qpos, walk.fps)


def test_model_has_no_root_actuator(model02):
    sim = torque_model(model02)
    free = np.flatnonzero(sim.jnt_type == mujoco.mjtJoint.mjJNT_FREE)
    assert sim.actuator_trntype.tolist() == [mujoco.mjtTrn.mjTRN_JOINT] * sim.nu
    assert not set(sim.actuator_trnid[:, 0]) & set(free)
    # the same strength as the servos it replaces
    np.testing.assert_array_equal(sim.actuator_forcerange, model02.actuator_forcerange)


def test_balance_walks_02_01_where_the_servos_fall(model02, walk, walk_qpos, walk_run):
    run = walk_run
    assert run.external_force_peak == 0.0
    assert np.all(np.isfinite(run.qpos))
    assert not run.fell and run.fall_time_s is None
    summary = window_summary(run, 0, walk.n_frames)
    assert summary["fell"] == 0.0
    assert summary["joint_error_deg_rms"] < 5.0
    assert summary["body_error_mm_mean"] < 50.0
    # the body carries its weight on the floor: about one body weight on average
    assert 0.8 < np.mean(run.contact_force_n) / run.weight_n < 1.2
    servo = track_qpos(model02, walk_qpos, walk.fps, "free")
    assert servo.fell


def test_recorded_torques_replay_to_the_same_motion(model02, walk, walk_qpos):
    run = follow(model02, walk_qpos[:120], walk.fps)
    assert run.ctrl.shape == (119 * run.substeps, model02.nu)
    again = replay(model02, run)
    np.testing.assert_allclose(again, run.qpos, atol=1e-9)
    # and the torques matter: replaying them without the first step's differs
    shifted = dataclasses.replace(run, ctrl=np.roll(run.ctrl, 1, axis=0))
    assert np.abs(replay(model02, shifted) - run.qpos).max() > 1e-4


def test_same_seed_same_run(model02, walk, walk_qpos):
    a = follow(model02, walk_qpos[:60], walk.fps, seed=3)
    b = follow(model02, walk_qpos[:60], walk.fps, seed=3)
    np.testing.assert_array_equal(a.qpos, b.qpos)
    np.testing.assert_array_equal(a.ctrl, b.ctrl)
    assert a.seed == b.seed == 3


def _feet_lifted(model):
    """A 3 s reference: standing in the rest pose for 0.5 s, then both feet drawn up
    (hips and knees flexed to their range's end: CMU's femur rx flexes negative, the
    tibia's rx positive) with the pelvis held at standing height for 2 s, then standing
    again."""
    layout = joint_layout(model)
    data = mujoco.MjData(model)
    lift = {}
    for name in ("lfemur.rx", "rfemur.rx", "ltibia.rx", "rtibia.rx"):
        k = layout.names.index(name)
        lift[layout.qpos_address[k]] = np.deg2rad(layout.range_deg[k])
    ankles = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in ("lfoot", "rfoot")]
    best, best_height = None, -np.inf
    for femur_end in (0,):
        for tibia_end in (1,):
            q = model.qpos0.copy()
            for address, (low_high) in lift.items():
                femur = address in (layout.qpos_address[layout.names.index("lfemur.rx")],
                                    layout.qpos_address[layout.names.index("rfemur.rx")])
                q[address] = low_high[femur_end if femur else tibia_end] * 0.95
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            height = data.xpos[ankles, 2].min()
            if height > best_height:
                best, best_height = q, height
    assert best_height > 0.3  # the feet are well off the floor
    fps = 120
    qpos = np.tile(model.qpos0, (3 * fps, 1))
    qpos[fps // 2:fps // 2 + 2 * fps] = best
    return qpos, fps


@pytest.fixture(scope="module")
def lifted(model02):
    """The run of :func:`_feet_lifted`'s reference: ``(qpos, fps, run)``."""
    qpos, fps = _feet_lifted(model02)
    return qpos, fps, follow(model02, qpos, fps)


def test_a_reference_it_cannot_follow_is_a_fall_with_its_time(lifted):
    qpos, fps, run = lifted
    assert run.fell
    assert 0.5 < run.fall_time_s < 2.5
    assert run.fall_frame == round(run.fall_time_s * fps)
    after = window_summary(run, run.fall_frame + 1, qpos.shape[0])
    assert set(after) == set(WINDOW_KEYS)
    assert after["fell"] == 1.0  # fell at or before the window's end
    assert after["fall_time_s"] == pytest.approx(run.fall_time_s)
    assert math.isnan(after["joint_error_deg_rms"]) and math.isnan(after["body_error_mm_mean"])
    before = window_summary(run, 0, run.fall_frame)
    assert before["fell"] == 0.0 and math.isnan(before["fall_time_s"])
    whole = window_summary(run, 0, qpos.shape[0])
    assert whole["fell"] == 1.0 and whole["fall_time_s"] == pytest.approx(run.fall_time_s)
    assert np.isfinite(whole["joint_error_deg_rms"])


def test_going_on_in_trouble_is_reported(model02, lifted, walk, walk_run):
    from controller.config import DEFAULT
    from controller.qpos import free_joint

    # with both feet drawn up the character goes down: the search spends its budget and
    # the run goes on in trouble until the fall, so the part that ends at the fall ends
    # in trouble
    qpos, fps, run = lifted
    before = window_summary(run, 0, run.fall_frame)
    trouble = np.flatnonzero(run.trouble[:run.fall_frame])
    assert trouble.size > 0
    assert before["trouble_time_s"] == pytest.approx(trouble.size / fps)
    assert before["ends_in_trouble"] == 1.0
    # recorded with the frame's own state: a pelvis tilted past the test is trouble there
    # (the character sits down before it falls and tips over after: the frames after the
    # fall, which the run goes on simulating, count too)
    sim = torque_model(model02)
    data = mujoco.MjData(sim)
    pelvis = sim.jnt_bodyid[free_joint(sim)]
    tilted = []
    for t in np.flatnonzero(np.isfinite(run.qpos[:, 0]))[1:]:
        data.qpos[:] = run.qpos[t]
        mujoco.mj_kinematics(sim, data)
        if data.xmat[pelvis, 8] < DEFAULT.search.trouble_up:
            tilted.append(t)
    assert tilted and run.trouble[tilted].all()
    # a walk it follows closely is never in trouble
    whole = window_summary(walk_run, 0, walk.n_frames)
    assert not walk_run.trouble.any()
    assert whole["trouble_time_s"] == 0.0 and whole["ends_in_trouble"] == 0.0


def test_pose_errors_leave_drift_and_heading_apart(model02, walk_qpos):
    from scipy.spatial.transform import Rotation

    from controller.pose_error import reference_errors

    ref = walk_qpos[:3]
    same = reference_errors(model02, ref, ref)
    for values in same:
        np.testing.assert_allclose(values, 0.0, atol=1e-9)
    moved = ref.copy()
    moved[:, :2] += [0.3, 0.4]  # drift only
    turn = Rotation.from_euler("z", 30, degrees=True)
    for t in range(3):  # and a heading change about the vertical through the pelvis
        w, x, y, z = moved[t, 3:7]
        moved[t, 3:7] = np.roll((turn * Rotation.from_quat([x, y, z, w])).as_quat(), 1)
    joint, body, drift, heading, com = reference_errors(model02, moved, ref)
    np.testing.assert_allclose(drift, 0.5, atol=1e-9)
    np.testing.assert_allclose(heading, 30.0, atol=1e-6)
    back = moved.copy()  # turned past the half turn: the error wraps to the short way
    for t in range(3):
        w, x, y, z = back[t, 3:7]
        turned = Rotation.from_euler("z", 170, degrees=True) * Rotation.from_quat([x, y, z, w])
        back[t, 3:7] = np.roll(turned.as_quat(), 1)
    np.testing.assert_allclose(reference_errors(model02, back, ref)[3], -160.0, atol=1e-6)
    np.testing.assert_allclose(body, 0.0, atol=1e-6)
    np.testing.assert_allclose(joint, 0.0, atol=1e-9)
    np.testing.assert_allclose(com, 0.0, atol=1e-9)
    bent = ref.copy()
    knee = joint_layout(model02).names.index("ltibia.rx")
    bent[:, joint_layout(model02).qpos_address[knee]] += np.deg2rad(20)
    joint, body, drift, heading, com = reference_errors(model02, bent, ref)
    assert np.all(joint > 0) and np.all(body > 5.0) and np.all(drift == 0)
    np.testing.assert_allclose(heading, 0.0, atol=1e-9)


def test_saturated_torques_are_the_torques_at_the_joints_strength(model02, walk_run):
    # the QP keeps its torques within each joint's strength, so a bound it leans on is
    # met to rounding: those frames count as saturated, whichever side of it rounding
    # put the planned torque, and the torque applied there is the strength itself
    run = walk_run
    low, high = torque_model(model02).actuator_forcerange.T
    tol = run.config.solver.at_bound_share * np.maximum(-low, high)
    up = np.all(np.isfinite(run.torque_nm), axis=1)
    up[0] = False
    torque = run.torque_nm[up]
    at_bound = (torque <= low + tol) | (torque >= high - tol)
    np.testing.assert_array_equal(run.torque_saturated[up], at_bound)
    assert 0 < at_bound.mean() < 0.2


def test_the_joint_velocity_is_recorded_with_the_torque(model02, walk_run):
    """Each actuator's velocity is its joint's, at the step its torque was applied: it
    follows the simulated angles' own rate, and the report's concentric share of the
    frames at full strength is the share at which torque and velocity have one sign."""
    from controller.balance.report import BalanceTracking

    run = walk_run
    sim = torque_model(model02)
    adr = sim.jnt_qposadr[sim.actuator_trnid[:, 0]]
    angle = run.qpos[:, adr]
    rate = (angle[2:] - angle[:-2]) * run.fps / 2.0  # central differences, rad/s
    velocity = run.actuator_velocity[1:-1]
    assert np.all(np.isfinite(velocity)) and np.all(run.actuator_velocity[0] == 0.0)
    # the step's velocity against the frame's rate: the same motion to the frame's blur
    assert np.corrcoef(velocity.ravel(), rate.ravel())[0, 1] > 0.99
    assert np.median(np.abs(velocity - rate)) < 0.1 * np.median(np.abs(rate))
    by_actuator = BalanceTracking(run).run_summary()["torque_by_actuator"]
    power = run.torque_nm * run.actuator_velocity
    seen = 0
    for i, name in enumerate(run.actuator_names):
        saturated = run.torque_saturated[:, i]
        got = by_actuator[name]["saturated_concentric_share"]
        if not saturated.any():
            assert got is None
            continue
        seen += 1
        assert got == pytest.approx(np.mean(power[saturated, i] > 0), abs=1e-5)
    assert seen > 0
