"""BVH in and out, on the real files of ``../shared/data/bvh`` and the CMU clips: every
file reads (frames, joints, rates as documented), reading then writing then reading keeps
every joint position, a motion written as BVH on its ASF converts back to the same
postures, an independent reader (the ``bvh`` package, with scipy's rotations) finds our
joints where the ASF kinematics put them, and malformed files are one-line errors naming
the file."""

import random

import numpy as np
import pytest

from upm.bvh import joint_positions, motion_from_bvh, motion_to_bvh, read_bvh, write_bvh
from upm.core.errors import DataFileError
from upm.motion.kinematics import forward_kinematics, global_transforms

#: (frames, joints, fps) as stated in the files' headers (shared/data/bvh/README.md).
FILES = {
    "02_01.bvh": (343, 31, 120), "05_01.bvh": (599, 31, 120), "05_02.bvh": (1124, 31, 120),
    "05_06.bvh": (886, 31, 120), "05_06_alt.bvh": (885, 31, 120),
    "05_11.bvh": (592, 31, 120), "05_11_daz.bvh": (592, 43, 120),
    "05_16.bvh": (526, 31, 120), "141_01.bvh": (75, 43, 120), "141_04.bvh": (548, 43, 120),
    "mixamo_test_freebvh.bvh": (69, 55, 30), "mocapbank_test.bvh": (455, 19, 30),
}


@pytest.fixture(scope="module")
def bvh_dir(data_dir):
    path = data_dir.parent / "bvh"
    if not path.is_dir():
        pytest.skip(f"no BVH data beside {data_dir}")
    return path


@pytest.mark.parametrize("name", sorted(FILES))
def test_every_real_file_reads_and_rewrites_to_the_same_joints(bvh_dir, tmp_path, name):
    bvh = read_bvh(bvh_dir / name)
    frames, joints, fps = FILES[name]
    assert (bvh.n_frames, bvh.skeleton.n_joints) == (frames, joints)
    assert bvh.fps == pytest.approx(fps, rel=1e-4)
    pos, ends = joint_positions(bvh)
    assert np.isfinite(pos).all() and np.isfinite(ends).any()
    write_bvh(tmp_path / name, bvh)
    again = read_bvh(tmp_path / name)
    assert again.skeleton.names == bvh.skeleton.names
    assert again.skeleton.channels == bvh.skeleton.channels
    pos2, ends2 = joint_positions(again)
    scale = np.abs(pos).max()
    np.testing.assert_allclose(pos2, pos, atol=1e-6 * scale)
    np.testing.assert_allclose(ends2, ends, atol=1e-6 * scale)


@pytest.mark.parametrize("clip", ["02_01", "05_11"])
def test_amc_to_bvh_to_amc_gives_the_same_postures(catalog, tmp_path, clip):
    motion = catalog.load(clip)
    write_bvh(tmp_path / "m.bvh", motion_to_bvh(motion))
    bvh = read_bvh(tmp_path / "m.bvh")
    # the joints stand where the ASF kinematics put each bone's start (cm)
    _, ends_m = global_transforms(motion.skeleton, motion.posture_deg, motion.root)
    pos, _ = joint_positions(bvh)
    parents = motion.skeleton.parents
    np.testing.assert_allclose(pos[:, 1:] / 100.0, ends_m[:, parents[1:]], atol=1e-6)
    back = motion_from_bvh(bvh, motion.skeleton)
    declared = motion.skeleton.declared
    diff = (back.posture_deg - motion.posture_deg + 180.0) % 360.0 - 180.0
    assert np.abs(diff[:, declared]).max() < 1e-5
    np.testing.assert_allclose(forward_kinematics(back), forward_kinematics(motion),
                               atol=1e-6)
    assert back.fps == pytest.approx(motion.fps)


def _independent_joint_positions(parsed) -> dict:
    """Joint positions (file units) of every frame of a file read by the ``bvh`` package,
    by plain forward kinematics with scipy's rotations (each joint's own channel order):
    ``{name: ndarray (T, 3)}``."""
    from scipy.spatial.transform import Rotation

    names = parsed.get_joints_names()
    out = {name: np.empty((parsed.nframes, 3)) for name in names}
    for t in range(parsed.nframes):
        world = {}
        for name in names:
            channels = parsed.joint_channels(name)
            rot = dict(zip(channels, parsed.frame_joint_channels(t, name, channels),
                           strict=True))
            order = "".join(c[0] for c in channels if c.endswith("rotation"))
            local = Rotation.from_euler(order, [rot[f"{a}rotation"] for a in order],
                                        degrees=True)
            offset = np.array([float(v) for v in parsed.joint_offset(name)])
            if "Xposition" in rot:
                offset = np.array([rot["Xposition"], rot["Yposition"], rot["Zposition"]])
            parent = parsed.joint_parent(name)
            if parent is None:
                world[name] = (local, offset)
            else:
                prot, ppos = world[parent.name]
                world[name] = (prot * local, ppos + prot.apply(offset))
            out[name][t] = world[name][1]
    return out


def test_an_independent_reader_finds_our_joints_within_a_millimetre(catalog, tmp_path):
    bvh_package = pytest.importorskip("bvh")

    motion = catalog.load("05_11").frames(0, 60)
    write_bvh(tmp_path / "m.bvh", motion_to_bvh(motion))
    parsed = bvh_package.Bvh((tmp_path / "m.bvh").read_text())
    assert parsed.get_joints_names() == list(motion.skeleton.bone_names)
    assert all(parsed.joint_channels(n)[-3:] == ["Zrotation", "Yrotation", "Xrotation"]
               for n in parsed.get_joints_names())
    _, ends_m = global_transforms(motion.skeleton, motion.posture_deg, motion.root)
    positions = _independent_joint_positions(parsed)
    for name, pos in positions.items():
        b = motion.skeleton.bone_index(name)
        if b:
            start_m = ends_m[:, motion.skeleton.parents[b]]
            assert np.linalg.norm(pos / 100.0 - start_m, axis=1).max() < 1e-3, name


@pytest.mark.parametrize("text, message, line", [
    ("MOTION\n", "starts with HIERARCHY", 1),
    ("HIERARCHY\nROOT hips\n{\n\tOFFSET 0 0\n}\n", "OFFSET needs 3 numbers", 4),
    ("HIERARCHY\nROOT hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 1 Wrotation\n}\n",
     "unknown channel", 5),
    ("HIERARCHY\nROOT hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 1 Xrotation\n}\nMOTION\n"
     "Frames: 2\nFrame Time: 0.01\n1\n", "'Frames: 2' but 1 frame lines", 8),
    ("HIERARCHY\nROOT hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 1 Xrotation\n}\nMOTION\n"
     "Frames:\t2\nFrame Time: 0.01\n1\ninf\n", "finite", 11),
    ("HIERARCHY\nROOT hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 1 Xrotation\n}\nMOTION\n"
     "Frames: 1\nFrame Time: 0\n1\n", "Frame Time", 9),
    ("HIERARCHY\nROOT hips\n{\n\tOFFSET 0 0 0\n", "ends inside the hierarchy", 4),
])
def test_malformed_bvh_names_the_file_and_line(tmp_path, text, message, line):
    path = tmp_path / "bad.bvh"
    path.write_text(text)
    with pytest.raises(DataFileError, match=message) as info:
        read_bvh(path)
    assert info.value.path == str(path) and info.value.line == line
    assert "\n" not in str(info.value)


def test_a_deep_hierarchy_is_refused(tmp_path):
    depth = 300
    text = "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 0\n"
    text += "".join(f"JOINT j{k}\n{{\nOFFSET 0 1 0\nCHANNELS 0\n" for k in range(1, depth))
    text += "}\n" * depth + "MOTION\nFrames: 1\nFrame Time: 0.1\n\n"
    path = tmp_path / "deep.bvh"
    path.write_text(text)
    with pytest.raises(DataFileError, match="deeper than"):
        read_bvh(path)


def test_mutated_bvh_is_read_or_refused_naming_it(bvh_dir, tmp_path):
    from tests.fuzz_mutations import mutate

    lines = (bvh_dir / "mocapbank_test.bvh").read_bytes().split(b"\n")
    source = b"\n".join(lines[:140]) + b"\n"
    head = read_bvh(bvh_dir / "mocapbank_test.bvh")
    assert head.n_frames > 40
    rng = random.Random(14)
    outcomes = {"read": 0, "refused": 0}
    for case in range(200):
        path = tmp_path / f"case{case}.bvh"
        path.write_bytes(mutate(source, rng))
        try:
            bvh = read_bvh(path)
            pos, _ = joint_positions(bvh)
        except DataFileError as exc:
            assert exc.path == str(path) and "\n" not in str(exc)
            outcomes["refused"] += 1
            continue
        assert np.isfinite(pos).all()
        outcomes["read"] += 1
    assert outcomes["refused"] > 50, outcomes


def test_convert_and_transition_write_bvh(data_dir, tmp_path, capsys):
    from upm.cli import main

    out = tmp_path / "walk.bvh"
    assert main(["convert", "--data", str(data_dir), "02_01@0:50", str(out)]) == 0
    assert read_bvh(out).n_frames == 50
    amc = tmp_path / "walk.amc"
    assert main(["convert", str(out), str(amc), "--skeleton",
                 str(data_dir / "02" / "02.asf")]) == 0
    assert amc.read_text().count("\nlfemur ") == 50
    assert main(["transition", "--data", str(data_dir), "--method", "linear", "--from",
                 "02_01", "--to", "02_03", "--out", str(tmp_path / "t.bvh")]) == 0
    assert read_bvh(tmp_path / "t.bvh").skeleton.names[0] == "root"
    capsys.readouterr()
    for args, message in [
        (["02_01", str(tmp_path / "x.fbx")], "ending in .amc or .bvh"),
        ([str(tmp_path / "missing.bvh"), str(tmp_path / "x.amc")], "no such file"),
    ]:
        assert main(["convert", "--data", str(data_dir), *args]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "x.amc").exists()
    if (data_dir.parent / "bvh").is_dir():
        assert main(["convert", "--data", str(data_dir), str(data_dir.parent / "bvh" /
                     "05_01.bvh"), str(amc), "--skeleton", str(data_dir / "05" / "05.asf")]) == 0
        assert amc.read_text().count("\nlfemur ") == 598  # the T-pose frame dropped


@pytest.mark.parametrize("take", ["05_01", "05_02", "05_06", "05_11", "05_16"])
def test_cgspeed_takes_retarget_onto_subject_05_within_a_centimetre(catalog, bvh_dir, take):
    """The cgspeed conversions (on subject 05's own bones, an added T-pose first frame)
    put every 21-joint bone end where the AMC of the same take does (measured worst:
    0.005 mm)."""
    from upm.bvh.retarget import added_tpose, retarget_cmu
    from upm.motion.skeleton import JOINTS

    amc = catalog.load(take)
    bvh = read_bvh(bvh_dir / f"{take}.bvh")
    assert added_tpose(bvh)
    motion = retarget_cmu(bvh, amc.skeleton, fps=amc.fps)
    assert motion.n_frames == amc.n_frames
    bones = [amc.skeleton.bone_index(j) for j in JOINTS]
    error_m = np.linalg.norm(forward_kinematics(motion)[:, bones]
                             - forward_kinematics(amc)[:, bones], axis=-1)
    assert error_m.max() < 0.01
    # keeping the T-pose frame shifts the take by one frame: the check can fail
    kept = retarget_cmu(bvh, amc.skeleton, drop_tpose=False)
    shifted = np.linalg.norm(forward_kinematics(kept)[1:, bones]
                             - forward_kinematics(amc)[:, bones], axis=-1)
    assert shifted.max() < 0.01 and kept.n_frames == amc.n_frames + 1


def test_other_skeletons_are_refused_naming_the_file(catalog, bvh_dir):
    from upm.bvh.retarget import retarget_cmu

    for name in ("05_11_daz.bvh", "mixamo_test_freebvh.bvh", "mocapbank_test.bvh"):
        with pytest.raises(DataFileError, match="not a CMU 31-joint BVH") as info:
            retarget_cmu(read_bvh(bvh_dir / name), catalog.skeleton("05"))
        assert info.value.path.endswith(name)


def test_a_transition_written_as_bvh_stands_upright_in_an_independent_reader(data_dir,
                                                                             tmp_path):
    """`upm transition --out t.bvh`, read by the `bvh` package with plain forward kinematics
    (Y up, as DCC tools import BVH): on every frame the head is above the hips, the hips
    above both feet, and the feet on a floor near Y = 0."""
    bvh_package = pytest.importorskip("bvh")

    from upm.cli import main

    out = tmp_path / "t.bvh"
    assert main(["transition", "--data", str(data_dir), "--method", "linear", "--from",
                 "02_01@200", "--to", "02_03@20", "--out", str(out)]) == 0
    positions = _independent_joint_positions(bvh_package.Bvh(out.read_text()))
    y = {name: positions[name][:, 1] for name in ("root", "head", "lfoot", "rfoot")}
    assert np.all(y["head"] > y["root"] + 30.0)  # cm
    assert np.all(y["root"] > np.maximum(y["lfoot"], y["rfoot"]) + 30.0)
    assert np.abs(np.minimum(y["lfoot"], y["rfoot"]).min()) < 20.0
