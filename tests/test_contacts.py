"""Contact queries: self-contact and floor depth on chosen states, and the calibration on
real clips (flat walks and runs rarely touch themselves; the whole set sometimes does)."""

import os

import mujoco
import numpy as np
import pytest

from controller import to_qpos
from controller.checks.contacts import (
    SELF_COLLISION_DEPTH_M,
    collide,
    contacts_over_frames,
    state_contacts,
    survey_clips,
)
from humanoid_xml.exclusions import EXCLUDED_PAIRS
from tests.conftest import FLAT_WALK_RUN
from upm import Motion
from upm.motion.skeleton import joint_dof_index


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """Subject models built into a temporary cache for this module."""
    previous = os.environ.get("UPM_CACHE")
    os.environ["UPM_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    yield
    if previous is None:
        del os.environ["UPM_CACHE"]
    else:
        os.environ["UPM_CACHE"] = previous


@pytest.fixture(scope="module")
def survey(catalog, cache):
    return survey_clips(catalog)


def test_flat_walks_and_runs_rarely_touch_themselves(survey):
    frames = sum(survey.clip_frames[n][0] for n in FLAT_WALK_RUN)
    touching = sum(survey.clip_frames[n][1] for n in FLAT_WALK_RUN)
    assert frames > 2400
    assert touching / frames < 0.10, f"{100 * touching / frames:.1f} % of walk/run frames"


def test_real_motion_does_touch_itself(survey):
    """Hands on hips, arms against the chest, hands together, legs close in jumps: over all
    clips some frames are in self-collision, and the pairs are the expected ones."""
    assert survey.frames > 28000
    assert 0.02 < survey.share < 0.5
    pairs = set(survey.pair_frames)
    assert ("lhand", "rhand") in pairs  # hands together (salsa, swordplay)
    assert any({"thorax", "lhumerus"} == set(p) or {"thorax", "rhumerus"} == set(p)
               for p in pairs)  # arms against the chest
    report = survey.as_dict()
    assert report["frames"] == survey.frames and report["pairs"]
    assert all(0 <= c["self_collision_pct"] <= 100 for c in report["clips"].values())


def test_excluded_and_adjacent_pairs_never_appear(survey, model02):
    excluded = {frozenset((a, b)) for a, b, _ in EXCLUDED_PAIRS}
    parent = {mujoco.mj_id2name(model02, mujoco.mjtObj.mjOBJ_BODY, b):
              mujoco.mj_id2name(model02, mujoco.mjtObj.mjOBJ_BODY, model02.body_parentid[b])
              for b in range(1, model02.nbody)}
    for a, b in survey.pair_frames:
        assert frozenset((a, b)) not in excluded
        assert parent[a] != b and parent[b] != a


def test_floor_depth_is_measured(model02):
    data = mujoco.MjData(model02)
    qpos = np.tile(model02.qpos0, (3, 1))
    qpos[1, 2] -= 0.05  # the whole body 5 cm into the floor
    qpos[2, 2] += 0.05  # 5 cm above it
    table = contacts_over_frames(model02, qpos)
    np.testing.assert_allclose(table.floor_depth_m(), [0.0, 0.05, 0.0], atol=2e-5)
    assert not table.in_self_collision().any()
    collide(model02, data, qpos[1])
    assert {a for a, _, _ in state_contacts(model02, data)} == {"world"}


def test_folded_arm_is_a_self_collision(catalog, model02):
    skeleton = catalog.skeleton("02")
    posture = np.zeros((2, 63))
    for (joint, axis), value in {("lhumerus", "rx"): -30, ("lhumerus", "ry"): 60,
                                 ("lhumerus", "rz"): 90, ("lradius", "rx"): 90}.items():
        posture[1, joint_dof_index(joint, axis)] = value
    motion = Motion(skeleton, posture, np.array([[0, 1.2, 0, 0, 0, 0]] * 2, dtype=float))
    table = contacts_over_frames(model02, to_qpos(model02, motion))
    assert list(table.in_self_collision()) == [False, True]
    assert table.max_self_depth_m()[1] > 0.01
    pairs = table.pair_frames()
    assert ("upperback", "lhumerus") in pairs or ("thorax", "lhumerus") in pairs
    assert table.pair_frames(depth_m=1.0) == {}
    assert np.all(table.body1 <= table.body2)


def test_min_depth_filters_rows(model02, walk):
    qpos = to_qpos(model02, walk)
    every = contacts_over_frames(model02, qpos)
    deep = contacts_over_frames(model02, qpos, min_depth_m=SELF_COLLISION_DEPTH_M)
    assert len(deep.frame) <= len(every.frame)
    assert np.all(deep.depth_m >= SELF_COLLISION_DEPTH_M)
    np.testing.assert_array_equal(deep.in_self_collision(), every.in_self_collision())
