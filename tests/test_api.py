"""The stable Python API of SPEC section 9: the names scripts and checks import."""

import mujoco
import numpy as np

import controller
import humanoid_xml
import upm


def test_spec_section_9_contract(tmp_path, data_dir):
    skeleton = upm.read_asf(data_dir / "02" / "02.asf")
    assert skeleton.bone_names[0] == "root" and skeleton.limits_deg.shape == (63, 2)
    motion = upm.read_amc(data_dir / "02" / "02_01.amc", skeleton, fps=120.0)
    assert motion.posture_deg.shape == (343, 63) and motion.root.shape == (343, 6)
    assert motion.fps == 120.0 and motion.skeleton is skeleton
    assert upm.forward_kinematics(motion).shape == (343, len(skeleton.bone_names), 3)
    upm.write_amc(tmp_path / "copy.amc", motion)

    umap = upm.UniformPostureMap().fit(motion.posture_deg)
    key = umap.key_posture(motion.posture_deg[0], motion.posture_deg[200], 0.5)
    assert key.shape == (63,)
    umap.save(tmp_path / "map.npz")
    again = upm.UniformPostureMap.load(tmp_path / "map.npz")
    assert np.array_equal(again.key_posture(motion.posture_deg[0], motion.posture_deg[200], 0.5),
                          key)

    assert humanoid_xml.default_model_path().is_file()
    xml = humanoid_xml.build_mjcf(skeleton)
    assert isinstance(xml, str)
    model = mujoco.MjModel.from_xml_string(xml)
    assert controller.to_qpos(model, motion).shape == (343, model.nq)
