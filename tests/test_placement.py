"""The foot placement's capture-offset rule (controller.balance.placement) on the real run 09_06,
whose flights the character cuts short: a foot put down before the reference lands it, or
still down after the reference lifts it, is compared with the reference as it lands it or
last stood on it, not with the reference in the air."""

import mujoco
import numpy as np
import pytest

from controller import to_qpos
from controller.balance.placement import FootPlacement, capture_error_m


@pytest.fixture(scope="module")
def run_09_06(catalog):
    from humanoid_xml import build_mjcf

    motion = catalog.load("09_06")
    model = mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("09")))
    qpos = to_qpos(model, motion)
    return model, qpos, motion.fps, FootPlacement(model, qpos, motion.fps)


def _reference_state(model, qpos, fps, t):
    """An MjData in the reference's pose at frame ``t``, moving with its central
    difference."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos[t]
    mujoco.mj_differentiatePos(model, data.qvel, 2.0 / fps, qpos[t - 1], qpos[t + 1])
    mujoco.mj_forward(model, data)
    return data


def _capture_offset(placement, frame, stance, stance_frame):
    """The reference's capture offset at ``frame`` over its ankle ``stance`` where it is
    at ``stance_frame`` (2,)."""
    return ((placement.ref_com[frame] - placement.ref_ankle[stance_frame, stance])
            + placement.time_constant_s * placement.ref_com_vel[frame])[:2]


def test_a_foot_down_early_is_compared_with_the_reference_landing_it(run_09_06):
    model, qpos, fps, placement = run_09_06
    left = 0
    landing = int(np.flatnonzero(placement.ref_down[:, left])[0])
    early = landing - int(round(0.15 * fps))  # the character's flight 0.15 s shorter
    assert not placement.ref_down[early].any()  # the reference is in the air there
    assert placement.down_frame[early, left] == landing
    # the character is the reference at its landing, 0.15 s early: on its left foot, as
    # the reference will be, its right foot needs no shift
    data = _reference_state(model, qpos, fps, landing)
    floor = sorted(placement.foot_bodies[left])
    q = np.array(qpos[early])
    shift = placement.adjust(data, early, q, floor_bodies=floor)
    assert np.linalg.norm(shift) < 0.01
    # the reference in the air at that frame, over where it will land, is far from it:
    # compared with it, the foot would be moved most of the largest shift
    ahead = _capture_offset(placement, early, left, landing) - (
        (data.subtree_com[1] - data.xpos[placement.ankle[left]])
        + placement.time_constant_s * data.subtree_linvel[1])[:2]
    assert placement.gain * np.linalg.norm(ahead) > 0.1
    # the trunk hold reads the same small difference
    assert capture_error_m(data)[0] < 0.01 / placement.gain


def test_a_foot_lifted_late_is_compared_with_the_reference_last_standing_on_it(run_09_06):
    model, qpos, fps, placement = run_09_06
    right = 1
    last = int(np.flatnonzero(placement.ref_down[: len(qpos) // 2, right])[-1])
    late = last + int(round(0.1 * fps))  # the character still on its right foot 0.1 s on
    assert not placement.ref_down[late].any()  # the reference is in the air there
    assert placement.down_frame[late, right] == last
    data = _reference_state(model, qpos, fps, last)
    q = np.array(qpos[late])
    shift = placement.adjust(data, late, q, floor_bodies=sorted(placement.foot_bodies[right]))
    assert np.linalg.norm(shift) < 0.01
    # the reference in the air by then, ahead of where it stood, is far from it
    ahead = _capture_offset(placement, late, right, last) - (
        (data.subtree_com[1] - data.xpos[placement.ankle[right]])
        + placement.time_constant_s * data.subtree_linvel[1])[:2]
    assert placement.gain * np.linalg.norm(ahead) > 0.1
