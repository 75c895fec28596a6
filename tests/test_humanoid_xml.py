"""The MJCF humanoid: forward kinematics equal to the project's on every real frame, ASF
joint ranges, a clean rest pose, real self-collision, masses, actuators, the default
model and the subject-model cache."""

import re
from pathlib import Path

import mujoco
import numpy as np
import pytest

import humanoid_xml
from controller import to_qpos
from controller.checks.contacts import collide, state_contacts
from humanoid_xml import build_mjcf, default_model_path, generic_skeleton, hinge_names
from humanoid_xml.body import BMI_KG_M2, SEGMENT_MASS_FRACTIONS, capsules, stature_m
from humanoid_xml.exclusions import EXCLUDED_PAIRS
from humanoid_xml.frames import ASF_TO_MJ, vectors_to_mj
from humanoid_xml.servos import SAG_DEG, SERVO_FREQUENCY_HZ, servo_gains
from tests.conftest import FLAT_WALK_RUN
from upm import Motion, read_amc, read_asf
from upm.core.errors import DataFileError
from upm.motion.human_boxes import human_dof_boxes
from upm.motion.kinematics import forward_kinematics, global_transforms
from upm.motion.skeleton import POSTURE_DOF_NAMES, joint_dof_index


def _subjects(catalog):
    return sorted({info.subject for info in catalog}, key=int)


@pytest.fixture(scope="module")
def skeletons(catalog):
    return {s: catalog.skeleton(s) for s in _subjects(catalog)}


@pytest.fixture(scope="module")
def xml_texts(skeletons):
    return {s: build_mjcf(sk) for s, sk in skeletons.items()}


@pytest.fixture(scope="module")
def models(xml_texts):
    return {s: mujoco.MjModel.from_xml_string(text) for s, text in xml_texts.items()}


@pytest.fixture(scope="module")
def generic_model():
    return mujoco.MjModel.from_xml_path(str(default_model_path()))


def _name(model, kind, i):
    return mujoco.mj_id2name(model, kind, i)


def _site_ids(model, skeleton):
    return [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"{b}_end")
            for b in skeleton.bone_names]


def test_frame_rotation_is_plus_90_about_x():
    np.testing.assert_array_equal(ASF_TO_MJ @ [0, 1, 0], [0, 0, 1])  # ASF up -> z up
    np.testing.assert_array_equal(ASF_TO_MJ @ [1, 0, 0], [1, 0, 0])  # left stays +x
    np.testing.assert_array_equal(ASF_TO_MJ @ [0, 0, 1], [0, -1, 0])  # forward -> -y
    assert np.linalg.det(ASF_TO_MJ) == pytest.approx(1.0)


def test_fk_equals_project_fk_on_every_frame_of_every_clip(all_motions, catalog, models):
    """Every bone end (a site) after mj_kinematics equals upm.forward_kinematics, rotated
    to z up, within 1 mm, on every frame of every clip, each on its own subject's model."""
    worst, frames = 0.0, 0
    for name, motion in all_motions.items():
        model = models[catalog.info(name).subject]
        data = mujoco.MjData(model)
        sites = _site_ids(model, motion.skeleton)
        qpos = to_qpos(model, motion)
        ours = vectors_to_mj(forward_kinematics(motion))
        theirs = np.empty_like(ours)
        for t in range(len(qpos)):
            data.qpos[:] = qpos[t]
            mujoco.mj_kinematics(model, data)
            theirs[t] = data.site_xpos[sites]
        error = float(np.abs(theirs - ours).max())
        assert error < 1e-3, f"{name}: MuJoCo and the project's FK differ by {error * 1000:.3f} mm"
        worst, frames = max(worst, error), frames + len(qpos)
    assert frames == sum(m.n_frames for m in all_motions.values()) > 28000
    assert worst < 1e-5  # in fact a few micrometres: the MJCF's 6-digit numbers


def test_body_rotations_equal_project_fk(walk, models):
    """Not only positions: every body's world rotation is the ASF bone's, conjugated."""
    model = models["02"]
    data = mujoco.MjData(model)
    rotations, _ = global_transforms(walk.skeleton, walk.posture_deg[::37], walk.root[::37])
    qpos = to_qpos(model, walk)[::37]
    bodies = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b)
              for b in walk.skeleton.bone_names]
    for t in range(len(qpos)):
        data.qpos[:] = qpos[t]
        mujoco.mj_kinematics(model, data)
        theirs = data.xmat[bodies].reshape(-1, 3, 3)
        np.testing.assert_allclose(theirs, ASF_TO_MJ @ rotations[t] @ ASF_TO_MJ.T, atol=1e-6)


def test_joint_ranges_are_the_human_range(skeletons, models, catalog):
    """The hinges' ranges are the human range's boxes (not the ASF's nominal ones), and
    they hold every real frame of the subject's walks and runs."""
    for subject, model in models.items():
        skeleton = skeletons[subject]
        hinges = {}
        for j in range(model.njnt):
            if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
                hinges[_name(model, mujoco.mjtObj.mjOBJ_JOINT, j)] = j
        assert list(hinges) != [] and set(hinges) == set(hinge_names(skeleton))
        assert len(hinges) == int(skeleton.declared.sum()) == 45
        for i, dof in enumerate(POSTURE_DOF_NAMES):
            name = dof.replace(".", "_")
            if not skeleton.declared[i]:
                assert name not in hinges, f"{subject}: undeclared {dof} has a hinge"
                continue
            j = hinges[name]
            assert model.jnt_limited[j]
            np.testing.assert_allclose(np.rad2deg(model.jnt_range[j]),
                                       human_dof_boxes(skeleton)[i], atol=1e-9)
        assert "ltibia_ry" not in hinges and "lclavicle_rx" not in hinges
        for clip in (c for c in FLAT_WALK_RUN if catalog.info(c).subject == subject):
            posture = (catalog.load(clip).posture_deg + 180.0) % 360.0 - 180.0
            boxes = human_dof_boxes(skeleton)
            inside = (posture >= boxes[:, 0] - 1e-6) & (posture <= boxes[:, 1] + 1e-6)
            assert inside[:, skeleton.declared].all(), clip  # the ASF boxes: 37-100 % out
        assert {"lfemur_rx", "lfemur_ry", "lfemur_rz"} <= set(hinges)
        # Bones outside the 21 joints carry no joint (they weld to their parent).
        for bone in ("lhipjoint", "upperneck", "lwrist", "lfingers", "lthumb"):
            b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, bone)
            assert model.body_jntnum[b] == 0 and model.body_weldid[b] != b


def test_a_dof_removed_from_the_asf_loses_its_hinge(tmp_path, data_dir):
    text = (data_dir / "02" / "02.asf").read_text()
    start = text.index("name lfemur")
    head, tail = text[:start], text[start:]
    tail = tail.replace("dof rx ry rz\n", "dof rx rz\n", 1)  # read_text gives LF endings
    tail = re.sub(r"limits \(-160.0 20.0\)\s*\(-70.0 70.0\)", "limits (-160.0 20.0)", tail,
                  count=1)
    path = tmp_path / "02.asf"
    path.write_text(head + tail)
    skeleton = read_asf(path)
    assert not skeleton.declared[joint_dof_index("lfemur", "ry")]
    model = mujoco.MjModel.from_xml_string(build_mjcf(skeleton))
    names = {_name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)}
    assert "lfemur_ry" not in names and {"lfemur_rx", "lfemur_rz"} <= names
    assert model.nu == 44


def test_rest_pose_touches_only_the_floor(models, generic_model):
    for subject, model in {**models, "generic": generic_model}.items():
        data = mujoco.MjData(model)
        collide(model, data, model.qpos0)
        self_contacts = [c for c in state_contacts(model, data) if c[0] != "world"]
        assert self_contacts == [], f"{subject}: {self_contacts}"
        # The root's rest height stands the lowest geom on the floor.
        lowest = min(_geom_bottom_z(model, data, g) for g in range(1, model.ngeom))
        assert abs(lowest) < 1e-5, subject  # 6-digit MJCF numbers


def _geom_bottom_z(model, data, g):
    half = model.geom_size[g, 1]
    axis_z = data.geom_xmat[g].reshape(3, 3)[2, 2]
    return data.geom_xpos[g, 2] - abs(axis_z) * half - model.geom_size[g, 0]


def test_every_excluded_pair_is_needed(xml_texts):
    """Without the <exclude> list, the rest pose of some subject makes every excluded pair
    touch, and no other pair: the list is exactly the pairs that touch by construction."""
    touching = set()
    for text in xml_texts.values():
        stripped = re.sub(r"\s*<exclude [^>]*/>", "", text)
        model = mujoco.MjModel.from_xml_string(stripped)
        data = mujoco.MjData(model)
        collide(model, data, model.qpos0)
        touching |= {frozenset((a, b)) for a, b, _ in state_contacts(model, data)
                     if a != "world"}
    assert touching == {frozenset((a, b)) for a, b, _ in EXCLUDED_PAIRS}


def test_excluded_pairs_name_real_bodies_with_reasons(models):
    model = models["02"]
    for a, b, reason in EXCLUDED_PAIRS:
        for body in (a, b):
            assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body) >= 0
        assert len(reason) > 20
    assert model.nexclude == len(EXCLUDED_PAIRS) <= 15


def _folded_arm(skeleton):
    posture = np.zeros((1, 63))
    for (joint, axis), value in {("lhumerus", "rx"): -30, ("lhumerus", "ry"): 60,
                                 ("lhumerus", "rz"): 90, ("lradius", "rx"): 90}.items():
        posture[0, joint_dof_index(joint, axis)] = value
    return Motion(skeleton, posture, np.array([[0.0, 1.0, 0.0, 0.0, 0.0, 0.0]]))


def test_self_collision_is_detected(skeletons, models, generic_model):
    """An arm folded into the torso (within the ASF limits) collides with it."""
    for subject, model in {"02": models["02"], "83": models["83"],
                           "generic": generic_model}.items():
        skeleton = skeletons.get(subject) or generic_skeleton()
        motion = _folded_arm(skeleton)
        lo, hi = skeleton.limits_deg.T
        assert np.all((lo <= motion.posture_deg[0]) & (motion.posture_deg[0] <= hi))
        data = mujoco.MjData(model)
        collide(model, data, to_qpos(model, motion)[0])
        arm_torso = [(a, b, d) for a, b, d in state_contacts(model, data)
                     if {a, b} & {"lhumerus", "lradius"}
                     and {a, b} & {"thorax", "upperback", "lowerback"}]
        assert arm_torso and max(d for _, _, d in arm_torso) > 0.01, subject


def test_masses_are_plausible_adults(models, generic_model):
    for subject, model in {**models, "generic": generic_model}.items():
        mass = float(model.body_mass.sum())
        assert 45 < mass < 120, f"{subject}: {mass:.1f} kg"
    # Segment shares follow de Leva: both thighs together are 28.3 % of the body.
    model = models["02"]
    thighs = sum(model.body_mass[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b)]
                 for b in ("lfemur", "rfemur"))
    assert thighs / model.body_mass.sum() == pytest.approx(
        2 * SEGMENT_MASS_FRACTIONS["l_thigh"][0], rel=1e-4)


def test_mass_is_bmi_times_stature_squared(skeletons, models):
    statures = {}
    for subject, model in models.items():
        stature = stature_m(skeletons[subject], capsules(skeletons[subject]))
        assert 1.4 < stature < 2.0
        assert float(model.body_mass.sum()) == pytest.approx(BMI_KG_M2 * stature ** 2,
                                                             rel=1e-4)
        statures[subject] = stature
    assert max(statures.values()) - min(statures.values()) > 0.1  # the subjects differ


def test_actuators_drive_every_hinge_with_load_scaled_gains(skeletons, models):
    """kp = max(I w^2, min(m g l, strength) / theta_sag), kv = 2 sqrt(kp I): the arms'
    gains come from the inertia they move (as in generator 1), the stance joints' from
    the body they carry: the ankle reaches its full strength within 2 degrees (it had
    23 N m/rad)."""
    model, skeleton = models["02"], skeletons["02"]
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    names = [_name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(model.nu)]
    assert names == hinge_names(skeleton)  # posture order
    strength = {_name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a): (-lo, hi)
                for a, (lo, hi) in enumerate(model.actuator_forcerange)}
    gains = servo_gains(model, strength)
    omega = 2 * np.pi * SERVO_FREQUENCY_HZ
    sag = np.deg2rad(SAG_DEG)
    kp = {}
    for a, name in enumerate(names):
        joint = model.actuator_trnid[a, 0]
        assert _name(model, mujoco.mjtObj.mjOBJ_JOINT, joint) == name
        # ctrlrange is the joint range in radians (not degrees).
        np.testing.assert_allclose(model.actuator_ctrlrange[a], model.jnt_range[joint])
        assert model.actuator_ctrllimited[a]
        kp[name] = model.actuator_gainprm[a, 0]
        kv = -model.actuator_biasprm[a, 2]
        g = gains[name]
        assert kp[name] == g.kp and kv == g.kv
        assert g.strength_nm == max(strength[name])
        held = min(g.load_kg * 9.81 * g.lever_m, g.strength_nm)
        assert kp[name] == pytest.approx(max(g.inertia_kgm2 * omega ** 2, held / sag),
                                         rel=5e-3)
        assert kv == pytest.approx(2 * np.sqrt(kp[name] * g.inertia_kgm2), rel=5e-3)
    assert kp["lhumerus_rz"] > kp["lradius_rx"] > kp["lhand_rx"]  # what the arm moves
    assert {gains[n].rule for n in ("lhumerus_rz", "lradius_rx", "lhand_rx")} == {"inertia"}
    # The ankle carries everything but the foot, its centre about a metre above.
    foot = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "lfoot")
    ankle = gains["lfoot_rx"]
    assert ankle.rule == "load" and kp["lfoot_rx"] > 1000
    # ... more than its strength: the servo reaches its strength at theta_sag.
    assert ankle.load_torque_nm > ankle.strength_nm
    assert kp["lfoot_rx"] == pytest.approx(ankle.strength_nm / sag, rel=5e-3)
    assert ankle.load_kg == pytest.approx(model.body_mass.sum() - model.body_subtreemass[foot])
    assert 0.7 < ankle.lever_m < 1.1
    assert gains["ltibia_rx"].rule == "load"


def test_servo_holds_a_posture(models, walk):
    """A posture as a control vector: the position servos hold the root-fixed body near a
    real walking posture against gravity."""
    from controller import posture_to_ctrl

    text = build_mjcf(walk.skeleton).replace('<freejoint name="root"/>', "")
    model = mujoco.MjModel.from_xml_string(text)
    data = mujoco.MjData(model)
    target = walk.posture_deg[100]
    data.ctrl[:] = posture_to_ctrl(model, target)
    qpos_of_actuator = model.jnt_qposadr[model.actuator_trnid[:, 0]]
    data.qpos[qpos_of_actuator] = data.ctrl
    for _ in range(500):
        mujoco.mj_step(model, data)
    error_deg = np.rad2deg(np.abs(data.qpos[qpos_of_actuator] - data.ctrl))
    assert np.median(error_deg) < 2 and error_deg.max() < 15


def test_default_model_is_rebuilt_exactly():
    text = default_model_path().read_text(encoding="utf-8")
    assert build_mjcf(generic_skeleton()) == text
    # Names its description by file name only: no machine path in a committed file.
    assert "from the skeleton 'generic_adult.json'" in text
    assert str(Path.home()) not in text and str(Path(__file__).parents[1]) not in text


def test_default_model_opens(generic_model):
    # What `python -m mujoco.viewer --mjcf <it>` loads.
    assert (generic_model.nq, generic_model.nv, generic_model.nu) == (52, 51, 45)
    mass = float(generic_model.body_mass.sum())
    assert 60 < mass < 80


def test_a_cmu_clip_plays_on_the_default_model(data_dir, generic_model):
    """The generic adult has CMU's channels and axes: a CMU AMC reads with its skeleton and
    plays on the default model, its FK agreeing with the project's."""
    motion = read_amc(data_dir / "02" / "02_01.amc", generic_skeleton())
    data = mujoco.MjData(generic_model)
    sites = _site_ids(generic_model, motion.skeleton)
    ours = vectors_to_mj(forward_kinematics(motion))
    for t, q in enumerate(to_qpos(generic_model, motion)):
        data.qpos[:] = q
        mujoco.mj_kinematics(generic_model, data)
        np.testing.assert_allclose(data.site_xpos[sites], ours[t], atol=1e-5)


def test_generic_skeleton_shares_the_cmu_topology_and_axes(skeletons):
    generic, cmu = generic_skeleton(), skeletons["02"]
    assert generic.bone_names == cmu.bone_names
    np.testing.assert_array_equal(generic.parents, cmu.parents)
    assert generic.dofs == cmu.dofs and np.array_equal(generic.declared, cmu.declared)
    np.testing.assert_allclose(generic.axis_matrices, cmu.axis_matrices, atol=1e-9)
    # Anthropometric lengths (Drillis & Contini fractions of 1.75 m).
    lengths = dict(zip(generic.bone_names, generic.lengths_m, strict=True))
    assert lengths["lfemur"] == pytest.approx(0.245 * 1.75)
    assert lengths["lhumerus"] == pytest.approx(0.186 * 1.75)


def _end(skeleton, posture_values, bone):
    posture = np.zeros((1, 63))
    for (joint, axis), v in posture_values.items():
        posture[0, joint_dof_index(joint, axis)] = v
    _, positions = global_transforms(skeleton, posture, np.zeros((1, 6)))
    return positions[0, skeleton.bone_index(bone)]


def test_generic_ranges_mean_what_their_anatomy_says():
    """Signs of the anatomical ranges (ASF frame: x left, y up, z forward)."""
    sk = generic_skeleton()
    lim = {n: sk.limits_deg[i] for i, n in enumerate(POSTURE_DOF_NAMES)}
    assert tuple(lim["lfemur.rx"]) == (-120, 30)
    knee = _end(sk, {("lfemur", "rx"): -90, ("lfemur", "rz"): -20}, "lfemur")
    hip = _end(sk, {}, "lhipjoint")
    assert knee[2] - hip[2] > 0.3  # hip flexion (rx < 0) lifts the knee forward
    ankle = _end(sk, {("ltibia", "rx"): 90, ("lfemur", "rz"): -20}, "ltibia")
    assert ankle[2] < -0.3  # knee flexion (rx > 0) takes the ankle backward
    assert lim["lfemur.rz"][1] == 25 and lim["rfemur.rz"][0] == -25  # 45 abduction from -+20
    out = _end(sk, {("lfemur", "rz"): 25}, "lfemur") - _end(sk, {("lfemur", "rz"): -20}, "lfemur")
    assert out[0] > 0.2  # left abduction moves the knee to the left
    toes = _end(sk, {("lfoot", "rx"): 50}, "lfoot") - _end(sk, {}, "lfoot")
    assert toes[1] < -0.05  # plantar flexion (rx > 0, up to 50) lowers the toes
    fingers = _end(sk, {("lhand", "rx"): 80}, "lfingers") - _end(sk, {}, "lfingers")
    assert fingers[1] < -0.05  # wrist flexion turns the fingers to the palm (down in T-pose)
    head = _end(sk, {("lowerback", "rx"): 26.7}, "head") - _end(sk, {}, "head")
    assert head[2] > 0.2  # trunk flexion leans forward


def test_description_errors_are_clear(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(DataFileError, match="bad.json:1: not valid JSON"):
        humanoid_xml.read_skeleton_description(bad)
    text = humanoid_xml.description.GENERIC_ADULT_JSON.read_text()
    bad.write_text(text.replace('"parent": "lfemur"', '"parent": "nowhere"', 1))
    with pytest.raises(DataFileError, match="parent 'nowhere'"):
        humanoid_xml.read_skeleton_description(bad)
    bad.write_text(text.replace('"name": "head"', '"name": "skull"', 1))
    with pytest.raises(DataFileError, match="no bone 'head'"):
        humanoid_xml.read_skeleton_description(bad)
    bad.write_text(text.replace('"format": "upm-skeleton/1"', '"format": "x"'))
    with pytest.raises(DataFileError, match="not a skeleton description"):
        humanoid_xml.read_skeleton_description(bad)


def test_subject_models_are_cached_by_content(tmp_path, monkeypatch, data_dir, catalog):
    monkeypatch.setenv("UPM_CACHE", str(tmp_path / "cache"))
    asf = tmp_path / "02.asf"
    asf.write_bytes((data_dir / "02" / "02.asf").read_bytes())
    first = humanoid_xml.subject_model_path(asf)
    assert first.is_relative_to(tmp_path / "cache") and first.name.startswith("humanoid-02-")
    stamp = first.stat().st_mtime_ns
    assert humanoid_xml.subject_model_path(asf) == first and first.stat().st_mtime_ns == stamp
    assert first.read_text() == build_mjcf(read_asf(asf))
    assert humanoid_xml.catalog_model_path(catalog, "02_01").name == first.name
    asf.write_bytes(asf.read_bytes().replace(b"length 7.59371", b"length 7.6"))
    assert humanoid_xml.subject_model_path(asf) != first


def test_load_model_error_is_one_line(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><body><geom type='nope'/></body></worldbody></mujoco>")
    with pytest.raises(DataFileError) as info:
        humanoid_xml.load_model(bad)
    assert "bad.xml" in str(info.value) and "\n" not in str(info.value)


def test_load_model_multiplies_every_torque_limit_by_the_strength():
    base = humanoid_xml.load_model(default_model_path())
    stronger = humanoid_xml.load_model(default_model_path(), strength=1.5)
    assert np.all(base.actuator_forcelimited == 1)
    np.testing.assert_allclose(stronger.actuator_forcerange, 1.5 * base.actuator_forcerange)
    np.testing.assert_array_equal(stronger.actuator_gainprm, base.actuator_gainprm)
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="strength"):
            humanoid_xml.load_model(default_model_path(), strength=bad)


# --- the synthetic subjects (no CMU data) ------------------------------------------------

@pytest.fixture(scope="module")
def synthetic_models(synthetic_catalog):
    return {s: mujoco.MjModel.from_xml_string(build_mjcf(synthetic_catalog.skeleton(s)))
            for s in ("81", "82")}


def test_fk_equals_project_fk_on_the_synthetic_clips(synthetic_catalog, synthetic_models):
    """Every bone end (a site) after mj_kinematics equals upm.forward_kinematics, rotated
    to z up, within 1 mm, on every frame of every synthetic clip, each on its subject's
    humanoid (the generic skeleton at two statures, read from the ASF written for it)."""
    frames = 0
    for info in synthetic_catalog:
        motion = synthetic_catalog.load(info.name)
        model = synthetic_models[info.subject]
        data = mujoco.MjData(model)
        sites = _site_ids(model, motion.skeleton)
        assert min(sites) >= 0
        ours = vectors_to_mj(forward_kinematics(motion))
        theirs = np.empty_like(ours)
        for t, q in enumerate(to_qpos(model, motion)):
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            theirs[t] = data.site_xpos[sites]
        error = np.abs(theirs - ours).max(axis=(0, 2))  # per bone, over frames and axes
        worst = motion.skeleton.bone_names[int(error.argmax())]
        assert error.max() < 1e-3, f"{info.name}: {worst} differs by {error.max() * 1e3:.3f} mm"
        assert error.max() < 1e-5  # in fact micrometres: the MJCF's 6-digit numbers
        frames += motion.n_frames
    assert frames == sum(info.listed_frames for info in synthetic_catalog)


def test_body_rotations_equal_project_fk_on_a_synthetic_clip(synthetic_catalog,
                                                             synthetic_models):
    motion = synthetic_catalog.load("82_02")
    model = synthetic_models["82"]
    data = mujoco.MjData(model)
    rotations, _ = global_transforms(motion.skeleton, motion.posture_deg[::9],
                                     motion.root[::9])
    bodies = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b)
              for b in motion.skeleton.bone_names]
    for t, q in enumerate(to_qpos(model, motion)[::9]):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        theirs = data.xmat[bodies].reshape(-1, 3, 3)
        np.testing.assert_allclose(theirs, ASF_TO_MJ @ rotations[t] @ ASF_TO_MJ.T, atol=1e-6)


def test_synthetic_humanoids_have_the_asf_ranges_and_their_statures(synthetic_catalog,
                                                                    synthetic_models):
    statures = {}
    for subject, model in synthetic_models.items():
        skeleton = synthetic_catalog.skeleton(subject)
        names = hinge_names(skeleton)
        assert model.nu == len(names) == 45
        for name in names:
            j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            i = POSTURE_DOF_NAMES.index(name.replace("_", "."))
            np.testing.assert_allclose(np.rad2deg(model.jnt_range[j]),
                                       human_dof_boxes(skeleton)[i], atol=1e-9)
        statures[subject] = stature_m(skeleton, capsules(skeleton))
        assert float(model.body_mass.sum()) == pytest.approx(BMI_KG_M2 * statures[subject] ** 2,
                                                             rel=1e-4)
    assert statures["82"] / statures["81"] == pytest.approx(0.88, rel=1e-3)
