"""ASF reading: the real CMU skeletons, and malformed files."""

import numpy as np
import pytest

from tests.asf_builder import make_asf
from upm import read_asf
from upm.core.errors import DataFileError
from upm.motion.kinematics import standing_height_m
from upm.motion.skeleton import CLASS_SLICES, JOINTS, POSTURE_DOF_NAMES, joint_dof_index


def test_every_subject_skeleton(catalog):
    subjects = sorted({info.subject for info in catalog})
    assert len(subjects) == 12
    for subject in subjects:
        skeleton = catalog.skeleton(subject)
        assert skeleton.bone_names[0] == "root"
        assert len(skeleton.bone_names) == 31
        assert all(skeleton.parents[b] < b for b in range(1, 31))  # parents first
        assert skeleton.declared.sum() == 45  # the 21 joints declare 45 DOFs on CMU
        assert np.allclose(np.linalg.norm(skeleton.directions[1:], axis=1), 1.0)
        assert skeleton.length_to_m == pytest.approx(0.0254 / 0.45)
        assert 1.3 < standing_height_m(skeleton) < 2.0


def test_subject_02_details(catalog):
    s = catalog.skeleton("02")
    lfemur = s.bone_index("lfemur")
    assert s.bone_names[s.parents[lfemur]] == "lhipjoint"
    assert s.lengths_m[lfemur] == pytest.approx(7.59371 * 0.0254 / 0.45)
    np.testing.assert_allclose(s.axis_deg[lfemur], [0, 0, 20])
    assert s.dofs[s.bone_index("lclavicle")] == ("ry", "rz")
    # Limits land at the right posture index; undeclared DOFs are [0, 0].
    np.testing.assert_allclose(s.limits_deg[joint_dof_index("lfemur", "rz")], [-60, 70])
    np.testing.assert_allclose(s.limits_deg[joint_dof_index("lclavicle", "rx")], [0, 0])
    assert not s.declared[joint_dof_index("ltibia", "ry")]
    assert s.root_order == ("tx", "ty", "tz", "rx", "ry", "rz")


def test_posture_layout():
    assert len(JOINTS) == 21 and len(POSTURE_DOF_NAMES) == 63
    assert [CLASS_SLICES[c] for c in ("body", "global", "medium", "detail")] == [
        slice(0, 15), slice(15, 30), slice(30, 45), slice(45, 63)]
    assert POSTURE_DOF_NAMES[0] == "lclavicle.rx" and POSTURE_DOF_NAMES[-1] == "rhand.rz"


def test_crlf_and_lf_read_the_same(tmp_path, data_dir):
    text = (data_dir / "02" / "02.asf").read_bytes()
    assert b"\r\n" in text
    lf = tmp_path / "lf.asf"
    lf.write_bytes(text.replace(b"\r\n", b"\n"))
    a, b = read_asf(data_dir / "02" / "02.asf"), read_asf(lf)
    np.testing.assert_array_equal(a.limits_deg, b.limits_deg)
    np.testing.assert_array_equal(a.offsets_m, b.offsets_m)


GOOD = make_asf({"lowerback": {"direction": (0, 1, 0), "length": 1.0, "dof": ["rx", "ry"],
                               "limits": [(-10, 10), (-20, 20)]}})


def _break(old: str, new: str) -> str:
    assert old in GOOD
    return GOOD.replace(old, new, 1)


def _line_of(text: str, needle: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if needle in line)


@pytest.mark.parametrize("text, message, line_needle", [
    (_break(":hierarchy", ":hierarchyX"), "missing section :hierarchy", None),
    (_break(":bonedata", ":bonesX"), "missing section :bonedata", None),
    (_break("direction 0 1 0", "direction 0 one 0"), "non-numeric", "direction 0 one 0"),
    (_break("direction 0 1 0", "direction 0 1"), "direction needs 3 numbers", "direction 0 1\n"),
    (_break("length 1.0", "length nan"), "NaN or infinite", "length nan"),
    (_break("dof rx ry", "dof rx ry rz"), "declares 3 dofs but 2 limits", None),
    (_break("dof rx ry", "dof rx tx"), "unsupported dof 'tx'", "dof rx tx"),
    (_break("name lowerback", "name lowerback\n    colour red"), "unknown bone field 'colour'",
     "colour red"),
    (_break("name upperback", "name head"), "bone 'head' is defined twice", None),
    (_break("    root lowerback", "    root lowerback ghost"), "unknown bone 'ghost'",
     "root lowerback ghost"),
    (GOOD.replace("lclavicle", "lclav"), "no bone 'lclavicle'", None),
    (_break("order TX TY TZ RX RY RZ", "order TX TY RX RY RZ"), "root order", "order TX TY RX"),
])
def test_malformed_asf(tmp_path, text, message, line_needle):
    path = tmp_path / "bad.asf"
    path.write_text(text)
    with pytest.raises(DataFileError) as info:
        read_asf(path)
    assert message in str(info.value)
    assert str(path) in str(info.value)
    if line_needle is not None:
        assert info.value.line == _line_of(text, line_needle.rstrip("\n"))


@pytest.mark.parametrize("content, message", [
    (b"", "empty ASF file"),
    (b"\x00\x01\x02binary", "binary data"),
    (b"just some words\n", "text before the first ':' section"),
])
def test_not_an_asf(tmp_path, content, message):
    path = tmp_path / "x.asf"
    path.write_bytes(content)
    with pytest.raises(DataFileError, match=message):
        read_asf(path)


def test_missing_file(tmp_path):
    with pytest.raises(DataFileError, match="no such ASF file"):
        read_asf(tmp_path / "nope.asf")


# --- the synthetic skeletons (tests/synthetic.py) ---------------------------------------

@pytest.mark.parametrize("scale, newline", [(1.0, "\n"), (0.88, "\r\n")])
def test_generic_skeleton_written_as_asf_reads_back(tmp_path, scale, newline):
    from humanoid_xml.description import generic_skeleton
    from tests.synthetic import CMU_LENGTH_UNIT, asf_text

    generic = generic_skeleton()
    path = tmp_path / "generic.asf"
    path.write_bytes(asf_text(generic, name="g", scale=scale, newline=newline).encode())
    s = read_asf(path)
    assert s.name == "g" and s.bone_names == generic.bone_names
    np.testing.assert_array_equal(s.parents, generic.parents)
    np.testing.assert_allclose(s.directions, generic.directions, atol=1e-15)
    np.testing.assert_allclose(s.lengths_m, scale * generic.lengths_m, rtol=1e-12)
    assert s.length_to_m == pytest.approx(0.0254 / CMU_LENGTH_UNIT)
    np.testing.assert_array_equal(s.axis_deg, generic.axis_deg)
    assert s.axis_order == generic.axis_order and s.dofs == generic.dofs
    np.testing.assert_allclose(s.axis_matrices, generic.axis_matrices, atol=1e-15)
    np.testing.assert_array_equal(s.limits_deg, generic.limits_deg)
    np.testing.assert_array_equal(s.declared, generic.declared)
    assert s.root_order == generic.root_order and s.root_axis_order == "XYZ"
    assert standing_height_m(s) == pytest.approx(scale * standing_height_m(generic))
    assert s.bone_lines[s.bone_index("lfemur")] == _line_of(
        path.read_bytes().decode().replace("\r\n", "\n"), "name lfemur") - 2  # its "begin"


def test_synthetic_subjects(synthetic_catalog):
    """The two subjects of the synthetic folder: the CMU bone set, parents first, 45
    declared DOFs, 1.75 m and 0.88 x 1.75 m tall."""
    heights = {}
    for subject in ("81", "82"):
        s = synthetic_catalog.skeleton(subject)
        assert s.bone_names[0] == "root" and len(s.bone_names) == 31
        assert all(s.parents[b] < b for b in range(1, 31))
        assert s.declared.sum() == 45
        heights[subject] = standing_height_m(s)
    assert heights["82"] / heights["81"] == pytest.approx(0.88)


def test_crlf_and_lf_synthetic_asf_read_the_same(tmp_path, synthetic_dir):
    text = (synthetic_dir / "82" / "82.asf").read_bytes()
    assert b"\r\n" in text
    lf = tmp_path / "lf.asf"
    lf.write_bytes(text.replace(b"\r\n", b"\n"))
    a, b = read_asf(synthetic_dir / "82" / "82.asf"), read_asf(lf)
    np.testing.assert_array_equal(a.limits_deg, b.limits_deg)
    np.testing.assert_array_equal(a.offsets_m, b.offsets_m)
    assert a.bone_lines == b.bone_lines


@pytest.mark.parametrize("key, new, message", [
    ("limits", "limits (30.0 -120.0)", "lower above upper"),
    ("dof", "dof rx ry rz rx", "a dof is listed twice"),
    ("axis", "axis 0 0 20.0 XYW", "not a permutation of XYZ"),
    ("length", "length -6.7", "cannot be negative"),
    ("direction", "direction 0.3 -0.9", "direction needs 3 numbers, found 2"),
])
def test_errors_in_a_crlf_asf_name_the_file_and_line(tmp_path, synthetic_dir, key, new,
                                                     message):
    """Line numbers count CRLF lines as lines (the synthetic subject 82 has CRLF ends)."""
    lines = (synthetic_dir / "82" / "82.asf").read_bytes().decode().split("\r\n")
    bone = lines.index("     name lfemur")
    at = next(i for i in range(bone, len(lines)) if lines[i].split()[:1] == [key])
    lines[at] = "    " + new
    path = tmp_path / "82.asf"
    path.write_bytes("\r\n".join(lines).encode())
    with pytest.raises(DataFileError, match=message) as info:
        read_asf(path)
    assert info.value.path == str(path) and info.value.line == at + 1
