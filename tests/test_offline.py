"""The offline effort (controller.offline): a standing clip and a dance segment the servos
alone fall on are performed without a fall, the same seed gives the same run bit for bit
(whatever the threads), no force but the servos' moves the body, and ``upm simulate
--effort offline`` writes the report of the usual shape with its effort."""

import json

import mujoco
import numpy as np
import pytest

from controller import to_qpos
from controller.config import DEFAULT
from controller.offline import perform
from controller.offline.rollouts import Roller
from controller.offline.samcon import segment_bounds, servo_sigma_rad, upper_body_servos
from controller.tracking.plan import plan_tracking
from controller.tracking.servo import track_qpos
from upm.cli import main

pytestmark = pytest.mark.physics  # free-root runs

#: A small search from the reference's targets (the warm start has its own tests,
#: test_offline_warm.py): a test's run takes seconds, not minutes.
SMALL = DEFAULT.updated({"offline": {"samples": 32, "keep": 4, "warm_start": False}})


@pytest.fixture(scope="module")
def model05(catalog):
    from humanoid_xml import build_mjcf

    return mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("05")))


def _reference(catalog, model, clip, a, b):
    motion = catalog.load(clip)
    return to_qpos(model, motion)[a:b], motion.fps


@pytest.mark.parametrize("clip, frames, subject", [
    ("02_10", (0, 180), "02"),  # wash self: standing, both feet down
    ("05_16", (0, 130), "05"),  # dance: coupe dessous
])
def test_a_segment_the_servos_fall_on_is_performed(catalog, model02, model05, clip,
                                                    frames, subject):
    """The servos alone fall at 1.35 s (02_10) and 0.88 s (05_16); with 48 samples the
    search stood on both, 3.3 and 8.7 deg RMS."""
    model = model02 if subject == "02" else model05
    qpos, fps = _reference(catalog, model, clip, *frames)
    alone = track_qpos(model, qpos, fps, "free")
    assert alone.fell
    result = perform(model, qpos, fps, SMALL)
    assert not result.fell and result.fall_time_s is None
    assert result.qpos.shape == qpos.shape and np.all(np.isfinite(result.qpos))
    assert result.summary()["error_deg_rms"] < 10.0
    assert 0 <= result.saturation_share < 0.2
    assert result.samples == result.outcome.rollouts >= SMALL.offline.samples
    assert result.outcome.passes <= SMALL.offline.budget + 1e-9
    # the result is the replay of the targets chosen: its first frame is the start
    np.testing.assert_allclose(result.qpos[0, 7:], qpos[0, 7:], atol=1e-9)


def test_the_same_seed_is_the_same_run_whatever_the_threads(catalog, model02):
    qpos, fps = _reference(catalog, model02, "02_01", 0, 60)
    one = perform(model02, qpos, fps, SMALL.with_threads(1))
    two = perform(model02, qpos, fps, SMALL.with_threads(2))
    assert np.array_equal(one.qpos, two.qpos)
    assert np.array_equal(one.outcome.ctrl, two.outcome.ctrl)
    other = perform(model02, qpos, fps, SMALL.updated({"offline": {"seed": 1}}))
    assert not np.array_equal(other.outcome.ctrl, one.outcome.ctrl)


def test_only_the_servos_move_the_body(catalog, model02):
    """No actuator on the root (every actuator drives a hinge) and nothing applied: after
    rollouts, xfrc_applied and qfrc_applied are zero in every thread's data."""
    hinge = mujoco.mjtJoint.mjJNT_HINGE
    assert np.all(model02.jnt_type[model02.actuator_trnid[:, 0]] == hinge)
    qpos, fps = _reference(catalog, model02, "02_01", 0, 30)
    plan = plan_tracking(model02, qpos, fps, "free")
    with Roller(plan.model, threads=2) as roller:
        start = roller.state_of(plan.start_qpos, plan.start_qvel)
        states = roller.run(np.repeat(start[None], 4, axis=0),
                            np.repeat(plan.ctrl[None], 4, axis=0))
        assert np.all(np.isfinite(states))
        for data in roller.datas:
            assert not data.xfrc_applied.any() and not data.qfrc_applied.any()


def test_segments_cover_the_motion():
    assert segment_bounds(10, 120, 0.025) == [0, 3, 6, 9]
    assert segment_bounds(2, 120, 0.2) == [0, 1]
    assert segment_bounds(50, 120, 0.2) == [0, 24, 48, 49]


def test_the_upper_body_servos_are_those_with_no_foot_below_or_above(model02):
    upper = upper_body_servos(model02)
    joints = [mujoco.mj_id2name(model02, mujoco.mjtObj.mjOBJ_JOINT, int(j))
              for j in model02.actuator_trnid[:, 0]]
    legs = {f"{side}{dof}" for side in "lr" for dof in (
        "femur_rx", "femur_ry", "femur_rz", "tibia_rx", "foot_rx", "foot_rz", "toes_rx")}
    assert {j for j, up in zip(joints, upper, strict=True) if not up} == legs
    assert upper.sum() == len(joints) - len(legs) > 0
    sigma = servo_sigma_rad(model02, 2.0, 0.25)
    assert sigma.shape == (model02.nu,)
    np.testing.assert_allclose(sigma[~upper], np.radians(2.0))
    np.testing.assert_allclose(sigma[upper], np.radians(0.5))


def test_simulate_with_the_offline_effort_writes_its_report(tmp_path, data_dir, capsys):
    config = tmp_path / "small.toml"
    config.write_text("[offline]\nsamples = 16\nkeep = 4\n")
    report = tmp_path / "r.json"
    assert main(["simulate", "--data", str(data_dir), "--method", "linear",
                 "--sequence", "02_01@0:30", "02_02@0:30", "--frames", "10",
                 "--modes", "free", "--no-window-runs", "--effort", "offline",
                 "--config", str(config), "--threads", "1", "--report", str(report)]) == 0
    out = json.loads(report.read_text())
    assert out["effort"] == "offline"
    assert out["settings"]["tracking"]["free_controller"] == "offline"
    assert out["settings"]["controller_config"]["offline"]["samples"] == 16
    free = out["totals"]["tracking"]["free"]
    assert free["effort"] == "offline" and free["search_rollouts"] > 0
    assert {"fell", "error_deg_rms", "body_error_mm_mean",
            "torque_saturation_share"} <= set(free)
    assert out["windows"][0]["tracking"]["free"]["frames"] == 10
    # the real-time controller's run the search started from (its warm start), beside it
    realtime = free["realtime"]
    assert set(realtime) == {"fell", "fall_time_s", "ends_in_trouble", "error_deg_rms",
                             "body_error_mm_mean"}
    assert (realtime["fall_time_s"] is None) == (not realtime["fell"])
    assert realtime["fell"] or 0.0 < realtime["error_deg_rms"] < 15.0
    assert "the real-time controller, whose run the search started from: " in \
        capsys.readouterr().out


def test_the_real_time_line_says_how_the_search_s_start_ended():
    from upm.commands.simulate_summary import realtime_line

    assert realtime_line({"fell": True, "fall_time_s": 1.234, "ends_in_trouble": False,
                          "error_deg_rms": 3.21, "body_error_mm_mean": 40.0}).endswith(
        "started from: falls at 1.23 s, joint error 3.2 deg RMS")
    assert realtime_line({"fell": False, "fall_time_s": None, "ends_in_trouble": True,
                          "error_deg_rms": None, "body_error_mm_mean": None}).endswith(
        "started from: does not fall but ends in trouble")
