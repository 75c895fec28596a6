"""Tracking simulations: a real walk with the root driven is followed closely, the free
root stays finite and its fall is detected, joint limits and MuJoCo's warnings are
reported, and the step plan interpolates as documented."""

import copy

import mujoco
import numpy as np
import pytest

from controller import to_qpos
from controller.config import DEFAULT
from controller.qpos import joint_layout
from controller.tracking.servo import (
    physics_substeps,
    plan_tracking,
    servo_lead_s,
    track,
    track_qpos,
)
from upm.motion.skeleton import joint_dof_index

pytestmark = pytest.mark.physics  # free-root runs

FALL_FRACTION = DEFAULT.falls.fraction


@pytest.fixture(scope="module")
def walk_segment(walk):
    return walk.frames(0, 240)  # 2 s of 02_01


@pytest.fixture(scope="module")
def driven(model02, walk_segment):
    return track(model02, walk_segment, "driven")


@pytest.fixture(scope="module")
def free(model02, walk_segment):
    return track(model02, walk_segment, "free")


def test_driven_root_follows_a_real_walk_closely(driven, walk_segment):
    """Measured on 02_01 frames 0-239: 0.78 degrees RMS over the 45 hinges, every frame
    under 1.9 degrees (1.1 and 2.5 with the inertia-only gains of generator 1)."""
    assert driven.diverged_frame is None and driven.warnings == {}
    assert np.all(np.isfinite(driven.qpos))
    assert driven.n_frames == walk_segment.n_frames
    assert not driven.fell
    summary = driven.summary()
    assert summary["error_deg_rms"] < 2.0
    assert summary["error_deg_peak"] < 4.0
    assert driven.error_deg[0] == pytest.approx(0.0, abs=1e-9)  # starts on the reference
    assert summary["self_collision_frames"] <= 5


def test_servo_lead_removes_the_lag(model02, walk_segment, driven):
    """Targets taken kv/kp ahead act as a velocity reference for the servos' damping:
    53 ms (2 / w, w = 2 pi 6 Hz) for the servos whose gains come from the inertia they
    move, less for the stiffer ones that carry the body in stance (ankle 4 ms). Without
    the lead the servos trail the walk (measured 2.3 against 0.78 degrees RMS)."""
    lead = servo_lead_s(model02)
    limit = 2.0 / (2 * np.pi * 6.0)
    assert np.all(lead <= limit * 1.03) and lead.max() == pytest.approx(limit, rel=0.03)
    ankle = mujoco.mj_name2id(model02, mujoco.mjtObj.mjOBJ_ACTUATOR, "lfoot_rx")
    assert lead[ankle] < 0.1 * limit
    lagging = track(model02, walk_segment, "driven", lead=False)
    assert lagging.summary()["error_deg_rms"] > 2 * driven.summary()["error_deg_rms"]


def test_free_root_simulation_is_finite_and_its_fall_is_detected(free, walk_segment):
    """Position servos without a balance controller: the character does not walk on its
    own (measured: it falls at 1.4 s; 1.0 s with generator 1's gains and no heel).
    Whatever happens, the state stays finite and the fall frame is where the pelvis or
    head first drops below half its standing height while the reference's does not."""
    assert free.diverged_frame is None and free.warnings == {}
    assert np.all(np.isfinite(free.qpos))
    if free.fell:
        f = free.fall_frame
        low = ((free.pelvis_height_m[f] < FALL_FRACTION * free.standing_pelvis_m)
               or (free.head_height_m[f] < FALL_FRACTION * free.standing_head_m))
        assert low
        before = slice(0, f)
        assert np.all(free.pelvis_height_m[before] >= FALL_FRACTION * free.standing_pelvis_m)
        assert np.all(free.head_height_m[before] >= FALL_FRACTION * free.standing_head_m)
        assert free.fall_time_s == pytest.approx(f / walk_segment.fps)
        assert free.fallen[f:].all() and not free.fallen[:f].any()
    run = free.run_summary()
    assert run["fell"] == free.fell and run["steps"] == free.steps
    assert run["warnings"] == {} and run["diverged_frame"] is None


def test_reference_that_lies_down_is_not_a_fall(model02):
    """A reference lying 25 cm above the floor: pelvis and head are low, but so are the
    reference's. Pushed down onto its own rigid legs instead, the body folds: that is a
    fall (the head drops while the reference's stays up)."""
    lying = np.tile(model02.qpos0, (60, 1))
    lying[:, 2] = 0.25
    lying[:, 3:7] = [np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0]  # 90 degrees about x
    result = track_qpos(model02, lying, 120.0, "driven")
    assert result.pelvis_height_m[-1] < FALL_FRACTION * result.standing_pelvis_m
    assert result.head_height_m[-1] < FALL_FRACTION * result.standing_head_m
    assert not result.fell
    squashed = np.tile(model02.qpos0, (60, 1))
    squashed[:, 2] = np.linspace(squashed[0, 2], 0.3, 60)
    result = track_qpos(model02, squashed, 120.0, "driven")
    assert result.fell
    f = result.fall_frame
    assert result.head_height_m[f] < FALL_FRACTION * result.standing_head_m
    assert result.reference_head_height_m[f] >= FALL_FRACTION * result.standing_head_m


def test_joint_limit_activity_names_the_joint(model02, catalog):
    """Driving ltibia.rx toward 20 degrees of hyperextension past its (human) limit: the
    servo's target is clamped to the range, so the joint stops short of it (error +20
    degrees). With the clamp off, the servo pushes into the limit and the limit rows say
    which joint."""
    from upm import Motion
    from upm.motion.human_boxes import human_dof_boxes

    skeleton = catalog.skeleton("02")
    dof = joint_dof_index("ltibia", "rx")
    lo = human_dof_boxes(skeleton)[dof, 0]
    posture = np.zeros((60, 63))
    posture[:, dof] = np.linspace(0.0, lo - 20.0, 60)
    root = np.tile([0.0, float(model02.qpos0[2]) + 0.1, 0.0, 0.0, 0.0, 0.0], (60, 1))
    motion = Motion(skeleton, posture, root, fps=120.0)
    layout = joint_layout(model02)
    hinge = layout.names.index("ltibia.rx")
    lo = np.deg2rad(lo)

    clamped = track(model02, motion, "driven")
    assert clamped.qpos[-1, layout.qpos_address[hinge]] >= lo - 1e-3
    assert clamped.dof_error_deg[-1, hinge] == pytest.approx(20, abs=3)
    # ... while the servo does reach the reachable target, the limit itself.
    assert abs(clamped.dof_reachable_error_deg[-1, hinge]) < 3
    assert (clamped.summary()["reachable_error_deg_rms"]
            < clamped.summary()["error_deg_rms"])
    # the human range holds the zero posture inside every hinge's range (the ASF's
    # boxes had the clavicles' rz on a limit at 0)
    assert "ltibia.rx" in clamped.limit_joint_frames
    assert not {"lclavicle.rz", "rclavicle.rz"} & set(clamped.limit_joint_frames)

    unclamped_model = copy.copy(model02)
    actuator = mujoco.mj_name2id(model02, mujoco.mjtObj.mjOBJ_ACTUATOR, "ltibia_rx")
    unclamped_model.actuator_ctrllimited[actuator] = 0
    pushed = track(unclamped_model, motion, "driven")
    assert pushed.limit_joint_frames.get("ltibia.rx", 0) > 5
    assert pushed.limit_rows[-5:].min() >= 1
    # The limit holds: the servo pushes at its full strength, the joint stays within a
    # degree of its limit (MuJoCo's default soft limit let it 9 degrees through).
    beyond = np.rad2deg(lo - pushed.qpos[-1, layout.qpos_address[hinge]])
    assert -0.01 < beyond < 1


def test_unstable_simulation_is_stopped_and_reported(model02, walk_segment):
    """Servo gains a hundred thousand times too stiff, without the strength limits, blow
    the explicit part of the step up: MuJoCo warns of a bad acceleration; the run stops
    there, says so, and keeps the message (nothing is printed or logged to a file)."""
    before = mujoco.get_mju_user_warning()
    stiff = copy.copy(model02)
    stiff.actuator_gainprm[:, 0] *= 1e5
    stiff.actuator_biasprm[:, 1] *= 1e5
    stiff.actuator_forcelimited[:] = 0
    result = track_qpos(stiff, to_qpos(stiff, walk_segment.frames(0, 30)), 120.0, "driven")
    assert result.diverged_frame is not None
    assert "mjWARN_BADQACC" in result.warnings
    assert any("unstable" in m for m in result.messages)
    assert np.isnan(result.qpos[result.diverged_frame:]).all()
    assert np.isfinite(result.qpos[:result.diverged_frame]).all()
    summary = result.run_summary()
    assert summary["diverged_frame"] == result.diverged_frame
    assert mujoco.get_mju_user_warning() is before  # the handler is restored


def test_plan_steps_divide_the_frame_and_interpolate(model02, walk_segment):
    assert physics_substeps(120.0) == 5 and physics_substeps(60.0) == 9
    qpos = to_qpos(model02, walk_segment.frames(0, 10))
    plan = plan_tracking(model02, qpos, 120.0, "driven")
    assert plan.model.opt.timestep == pytest.approx(1 / 600)
    assert model02.opt.timestep == pytest.approx(0.002)  # the caller's model is untouched
    assert plan.ctrl.shape == (9 * 5, model02.nu)
    np.testing.assert_allclose(plan.root_qpos[::5], qpos[:-1, :7], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(plan.root_qpos[:, 3:], axis=1), 1.0)
    assert np.all(np.abs(plan.ctrl) <= np.pi)
    free_plan = plan_tracking(model02, qpos, 120.0, "free")
    assert free_plan.root_qpos is None and free_plan.root_qvel is None
    # the longest step is the configuration's: 1 ms gives 9 steps per frame at 120 fps
    fine = plan_tracking(model02, qpos, 120.0, "driven",
                         config=DEFAULT.updated({"step": {"max_step_s": 0.001}}))
    assert fine.substeps == 9 and fine.ctrl.shape == (9 * 9, model02.nu)
    with pytest.raises(ValueError, match="unknown tracking mode"):
        plan_tracking(model02, qpos, 120.0, "flying")


@pytest.mark.parametrize("lift_m", [0.19, -0.03])
def test_a_free_plan_starts_on_the_floor_with_its_reference_shifted_alike(
        model02, walk_segment, lift_m):
    """A window that begins in the air or on a box (lifted 19 cm), or sunk 3 cm: the free
    plan's start has its lowest point just into the floor, and the reference is moved by
    the same height, so that the falls and the offline search judge heights the body can
    reach; the driven plan keeps the reference as it is."""
    from controller.grounding import floor_clearance

    qpos = to_qpos(model02, walk_segment.frames(0, 10))
    qpos[:, 2] += lift_m
    plan = plan_tracking(model02, qpos, 120.0, "free")
    depth = -floor_clearance(plan.model, mujoco.MjData(plan.model), plan.start_qpos)
    assert depth == pytest.approx(DEFAULT.reference.start_depth_m, abs=1e-6)
    np.testing.assert_array_equal(plan.start_qpos, plan.reference_qpos[0])
    shift = plan.reference_qpos[:, 2] - qpos[:, 2]
    np.testing.assert_allclose(shift, shift[0], atol=1e-12)
    assert -lift_m - 0.05 < shift[0] < -lift_m + 0.05
    np.testing.assert_array_equal(plan.reference_qpos[:, 3:], qpos[:, 3:])
    driven = plan_tracking(model02, qpos, 120.0, "driven")
    np.testing.assert_array_equal(driven.reference_qpos[:, :3], qpos[:, :3])
