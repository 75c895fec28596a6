"""An outside check of the Acclaim convention: dm_control's CMU humanoid.

dm_control ships ``humanoid_CMU.xml`` (a generic CMU skeleton) and its own AMC converter
(``suite/utils/parse_amc.py``). Driven by the same clip, its bodies must turn exactly as
our bones do, up to a constant per-bone offset (its skeleton is generic, its body frames
rounded) and its fixed y-up -> z-up frame change. No CMU-specific code of ours is used on
its side, so agreement checks our Euler order, axis frames and root convention.
"""

import os

import numpy as np
import pytest

os.environ.setdefault("MUJOCO_GL", "osmesa")  # dm_control picks a GL backend on import

import mujoco  # noqa: E402
from dm_control import suite  # noqa: E402  (a dev dependency, for this check only)
from dm_control.suite.utils import parse_amc  # noqa: E402

from upm.motion.kinematics import global_transforms  # noqa: E402

#: dm_control's fixed frame change: (x, y, z)_asf -> (x, -z, y)_mujoco.
Y_UP_TO_Z_UP = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
#: Bones whose chain from the root holds only articulated joints (no upperneck, wrist).
CHAIN_OF_21 = ("root", "lowerback", "upperback", "thorax", "lowerneck", "lclavicle",
               "rclavicle", "lhumerus", "rhumerus", "lradius", "rradius", "lfemur", "rfemur",
               "ltibia", "rtibia", "lfoot", "rfoot", "ltoes", "rtoes")


@pytest.fixture(scope="module")
def offsets(data_dir, catalog):
    """Per bone, R_ours(t)^T F^T R_dm(t) for every frame of 02_01: (T, 3, 3) arrays."""
    model = mujoco.MjModel.from_xml_path(
        os.path.join(os.path.dirname(suite.__file__), "humanoid_CMU.xml"))
    data = mujoco.MjData(model)
    width = {0: 7, 1: 4, 2: 1, 3: 1}
    index2joint = {k: model.joint(j).name for j in range(model.njnt)
                   for k in range(model.jnt_qposadr[j],
                                  model.jnt_qposadr[j] + width[int(model.jnt_type[j])])}
    convert = parse_amc.Amcvals2qpos(index2joint, parse_amc._CMU_MOCAP_JOINT_ORDER)
    frames = parse_amc.parse(str(data_dir / "02" / "02_01.amc"))
    motion = catalog.load("02_01")
    assert len(frames) == motion.n_frames
    ours, _ = global_transforms(motion.skeleton, motion.posture_deg, motion.root)
    names = CHAIN_OF_21 + ("head", "lhand", "rhand")
    result = {name: np.empty((len(frames), 3, 3)) for name in names}
    for t, values in enumerate(frames):
        data.qpos[:] = convert(values)
        mujoco.mj_kinematics(model, data)
        for name in names:
            theirs = data.xmat[model.body(name).id].reshape(3, 3)
            mine = ours[t, motion.skeleton.bone_index(name)]
            result[name][t] = mine.T @ Y_UP_TO_Z_UP.T @ theirs
    return result


def test_bones_turn_as_dm_control_bodies(offsets):
    for name in CHAIN_OF_21:
        q = offsets[name]
        # A constant offset: dm_control's body frames are rounded to ~3 digits, ~0.3 deg.
        assert np.abs(q - q.mean(axis=0)).max() < 0.012, name


def test_non_articulated_bones_are_where_the_difference_lies(offsets):
    # dm_control articulates upperneck and the wrists; our 21-joint model does not, so the
    # head and hands (and only they) drift from a constant offset.
    for name in ("head", "lhand", "rhand"):
        q = offsets[name]
        assert np.abs(q - q.mean(axis=0)).max() > 0.05, name
