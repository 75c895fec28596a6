"""AMC reading and writing: every real clip, round trips, malformed files."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from tests.asf_builder import make_amc, make_asf
from upm import Motion, read_amc, read_asf, write_amc
from upm.core.errors import DataFileError


def test_every_clip_parses_with_listed_frame_count(all_motions, catalog):
    assert len(all_motions) == 26
    for name, motion in all_motions.items():
        info = catalog.info(name)
        assert motion.n_frames == info.listed_frames, name
        assert motion.fps == info.fps
        assert np.isfinite(motion.posture_deg).all() and np.isfinite(motion.root).all()
        # Undeclared DOFs are constant zeros.
        assert not motion.posture_deg[:, ~motion.skeleton.declared].any()


def test_units_of_the_first_frame(walk):
    # 02_01 frame 1: "root 10.4194 16.7048 -30.1003 -2.48972 -9.82194 -3.00914"
    np.testing.assert_allclose(walk.root[0, :3], np.array([10.4194, 16.7048, -30.1003]) * 0.0254
                               / 0.45)
    np.testing.assert_allclose(walk.root[0, 3:], [-2.48972, -9.82194, -3.00914])
    # "lfemur -28.0191 -1.02078 -20.1783" and "lclavicle -1.6201e-014 -1.43125e-014" (ry rz)
    from upm.motion.skeleton import joint_dof_index as ix
    assert walk.posture_deg[0, ix("lfemur", "rx")] == -28.0191
    assert walk.posture_deg[0, ix("lfemur", "rz")] == -20.1783
    assert walk.posture_deg[0, ix("lclavicle", "ry")] == -1.6201e-14
    assert walk.posture_deg[0, ix("lclavicle", "rx")] == 0.0


def test_cmu_file_read_written_read_again_is_the_same(tmp_path, catalog):
    for name in ("02_01", "60_10", "135_06"):  # CRLF, LF, a long unwrapped one
        motion = catalog.load(name)
        out = tmp_path / f"{name}.amc"
        write_amc(out, motion)
        again = read_amc(out, motion.skeleton, fps=motion.fps)
        np.testing.assert_allclose(again.posture_deg, motion.posture_deg, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(again.root, motion.root, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(again.extra_deg, motion.extra_deg, rtol=1e-9, atol=1e-9)


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.integers(1, 5).flatmap(lambda t: st.tuples(
    arrays(float, (t, 63), elements=st.floats(-1000, 1000, allow_subnormal=False)),
    arrays(float, (t, 6), elements=st.floats(-100, 100, allow_subnormal=False)))))
def test_write_read_round_trip_property(tmp_path, synthetic_catalog, arrays_pair):
    skeleton = synthetic_catalog.skeleton("81")  # the CMU channels, as an ASF
    posture, root = arrays_pair
    posture = np.where(skeleton.declared, posture, 0.0)
    motion = Motion(skeleton, posture, root, fps=120.0)
    path = tmp_path / "prop.amc"
    write_amc(path, motion)
    back = read_amc(path, skeleton)
    np.testing.assert_allclose(back.posture_deg, posture, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(back.root, root, rtol=1e-9, atol=1e-9)


def test_crlf_and_lf_and_radians(tmp_path, data_dir, walk):
    text = (data_dir / "02" / "02_01.amc").read_bytes()
    lf = tmp_path / "lf.amc"
    lf.write_bytes(text.replace(b"\r\n", b"\n"))
    np.testing.assert_array_equal(read_amc(lf, walk.skeleton).posture_deg, walk.posture_deg)


# --- malformed files -----------------------------------------------------------------

SKELETON_TEXT = make_asf({
    "lowerback": {"direction": (0, 1, 0), "length": 1.0, "dof": ["rx", "ry", "rz"]},
    "lfemur": {"direction": (0, -1, 0), "length": 1.0, "dof": ["rx"]},
})
ROOT = [0, 1, 0, 0, 0, 0]


def frame(**overrides):
    values = {"root": ROOT, "lowerback": [1, 2, 3], "lfemur": [4]}
    values.update(overrides)
    return values


GOOD = make_amc([frame(), frame(), frame()])


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    path = tmp_path_factory.mktemp("tiny") / "tiny.asf"
    path.write_text(SKELETON_TEXT)
    return read_asf(path)


def test_tiny_good_file(tmp_path, tiny):
    path = tmp_path / "good.amc"
    path.write_text(GOOD)
    motion = read_amc(path, tiny, fps=60)
    assert motion.n_frames == 3 and motion.fps == 60
    assert motion.root[0, 1] == pytest.approx(0.0254)


def _nth(text, old, new, n):
    parts = text.split(old)
    assert len(parts) > n
    return old.join(parts[:n]) + new + old.join(parts[n:]) if n else text.replace(old, new, 1)


TRUNCATED = GOOD[: GOOD.rindex("lfemur")]


@pytest.mark.parametrize("text, message, line", [
    (GOOD.replace("lowerback 1 2 3", "lowerbak 1 2 3", 1), "unknown bone 'lowerbak'", 6),
    (GOOD.replace("lowerback 1 2 3\n", "", 1), "frame 1 (line 4) lacks bone 'lowerback'", 7),
    (GOOD.replace("lfemur 4", "lfemur 4 5", 1), "bone 'lfemur' needs 1 values, found 2", 7),
    (GOOD.replace("lowerback 1 2 3", "lowerback 1 two 3", 1), "non-numeric value", 6),
    (GOOD.replace("lowerback 1 2 3", "lowerback 1 nan 3", 1), "NaN or infinite", 6),
    (GOOD.replace("lfemur 4", "lfemur inf", 1), "NaN or infinite", 7),
    (GOOD.replace("\n2\n", "\n3\n", 1), "frame 3 follows frame 1 (expected 2)", 8),
    (GOOD.replace("lfemur 4", "lfemur 4\nlowerback 1 2 3", 1), "appears twice in frame 1", 8),
    (TRUNCATED, "frame 3 (line 12) lacks bone 'lfemur'", 15),
    ("#!OML:ASF x\n:FULLY-SPECIFIED\n:DEGREES\n", "no frames", None),
    ("root 0 1 0 0 0 0\n", "expected a frame number", 1),
    (GOOD.replace("lfemur 4", "head 4", 1), "bone 'head' has values but no dofs", 7),
])
def test_malformed_amc(tmp_path, tiny, text, message, line):
    path = tmp_path / "bad.amc"
    path.write_text(text)
    with pytest.raises(DataFileError) as info:
        read_amc(path, tiny)
    assert message in str(info.value)
    assert str(path) in str(info.value)
    assert info.value.line == line


CUT_AT = GOOD[: GOOD.rindex("lowerback")]  # the last frame, cut before its lowerback line
TWELVE = make_amc([frame() for _ in range(12)])


@pytest.mark.parametrize("text, message, line", [
    (CUT_AT + "lo", "looks truncated: its last line ends in 'lo', the start of a bone name "
                    "('lowerback'?)", 14),
    (CUT_AT + "lo\n\n  \n", "looks truncated: its last line ends in 'lo'", 14),
    (CUT_AT + "lowerback 1 2", "looks truncated: its last line ends after 2 of the 3 values "
                               "of bone 'lowerback'", 14),
    (CUT_AT + "lowerback", "after 0 of the 3 values", 14),
    (TWELVE[: TWELVE.rindex("\n12\n") + 2], "looks truncated: its last line ends in frame "
                                             "number 1 (expected 12)", 48),
])
def test_amc_cut_mid_line_is_said_to_be_truncated(tmp_path, tiny, text, message, line):
    path = tmp_path / "cut.amc"
    path.write_text(text)
    with pytest.raises(DataFileError) as info:
        read_amc(path, tiny)
    assert message in str(info.value)
    assert str(path) in str(info.value) and "another skeleton" not in str(info.value)
    assert info.value.line == line


@pytest.mark.parametrize("text, message, line", [
    # the start of a bone name, but not on the last line: a wrong name, not a cut
    (GOOD.replace("lowerback 1 2 3", "lo", 1), "unknown bone 'lo' (not in tiny.asf", 6),
    (GOOD.replace("lowerback 1 2 3", "lowerback 1 2", 1), "needs 3 values, found 2", 6),
    # the last line, but not the start of any bone name
    (CUT_AT + "xy", "unknown bone 'xy' (not in tiny.asf: does this AMC belong to another", 14),
])
def test_amc_wrong_line_not_at_the_end_is_not_called_truncated(tmp_path, tiny, text, message,
                                                               line):
    path = tmp_path / "bad.amc"
    path.write_text(text)
    with pytest.raises(DataFileError) as info:
        read_amc(path, tiny)
    assert message in str(info.value) and "truncated" not in str(info.value)
    assert info.value.line == line


def test_amc_of_another_skeleton(synthetic_dir, tiny):
    expected = "bone 'upperback' has values but no dofs in tiny.asf.*another skeleton"
    with pytest.raises(DataFileError, match=expected):
        read_amc(synthetic_dir / "81" / "81_01.amc", tiny)


@pytest.mark.parametrize("content, message", [
    (b"", "empty AMC file"), (b"\x89PNG\r\n\x1a\n\x00\x00", "binary data")])
def test_not_an_amc(tmp_path, tiny, content, message):
    path = tmp_path / "x.amc"
    path.write_bytes(content)
    with pytest.raises(DataFileError, match=message):
        read_amc(path, tiny)


# --- the synthetic clips (tests/synthetic.py) -------------------------------------------

def test_synthetic_clips_read_as_they_were_made(synthetic_catalog):
    """Every clip of the synthetic folder, written by tests/synthetic.py's own AMC writer
    (LF for subject 81, CRLF for 82), reads back as the motion it was made from."""
    import dataclasses

    from tests.synthetic import SUBJECTS, clip_spec, walk_motion

    scale = {s.subject: s.scale for s in SUBJECTS}
    assert len(synthetic_catalog) == 5
    for info in synthetic_catalog:
        motion = synthetic_catalog.load(info.name)
        spec = clip_spec(info.name)
        made = walk_motion(motion.skeleton, dataclasses.replace(
            spec, speed_m_s=spec.speed_m_s * scale[info.subject]))
        assert motion.n_frames == made.n_frames == info.listed_frames
        assert motion.fps == spec.fps and motion.name == info.name
        np.testing.assert_allclose(motion.posture_deg, made.posture_deg, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(motion.root, made.root, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(motion.extra_deg, made.extra_deg, rtol=1e-9, atol=1e-9)
        assert not motion.posture_deg[:, ~motion.skeleton.declared].any()


def test_synthetic_clips_stay_inside_the_limits_and_walk_forward(synthetic_catalog):
    for info in synthetic_catalog:
        motion = synthetic_catalog.load(info.name)
        lo, hi = motion.skeleton.limits_deg.T
        assert np.all((lo <= motion.posture_deg) & (motion.posture_deg <= hi)), info.name
        travelled = np.linalg.norm(motion.root[-1, [0, 2]] - motion.root[0, [0, 2]])
        assert travelled > 0.8 * motion.duration_s, info.name  # at least 0.8 m/s
        steps = np.abs(np.diff(motion.posture_deg, axis=0)).max()
        assert 0 < steps < 500 / motion.fps, info.name  # smooth: under 500 deg/s


def test_written_synthetic_clip_reads_again_the_same(tmp_path, synthetic_catalog):
    for name in ("81_02", "82_01"):  # LF and CRLF sources
        motion = synthetic_catalog.load(name)
        out = tmp_path / f"{name}.amc"
        write_amc(out, motion)
        again = read_amc(out, motion.skeleton, fps=motion.fps)
        np.testing.assert_allclose(again.posture_deg, motion.posture_deg, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(again.root, motion.root, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(again.extra_deg, motion.extra_deg, rtol=1e-9, atol=1e-9)


def test_crlf_and_lf_synthetic_amc_read_the_same(tmp_path, synthetic_dir, synthetic_catalog):
    text = (synthetic_dir / "82" / "82_02.amc").read_bytes()
    assert b"\r\n" in text
    lf = tmp_path / "lf.amc"
    lf.write_bytes(text.replace(b"\r\n", b"\n"))
    skeleton = synthetic_catalog.skeleton("82")
    np.testing.assert_array_equal(read_amc(lf, skeleton).posture_deg,
                                  read_amc(synthetic_dir / "82" / "82_02.amc",
                                           skeleton).posture_deg)


@pytest.mark.parametrize("frame, bone, new, message", [
    (3, "lfemur", "lfemur 1 2", "bone 'lfemur' needs 3 values, found 2"),
    (40, "rtibia", "rtibia x", "non-numeric value"),
    (144, "head", "hed 0 0 0", "unknown bone 'hed'"),
])
def test_errors_in_a_crlf_amc_name_the_file_and_line(tmp_path, synthetic_dir,
                                                     synthetic_catalog, frame, bone, new,
                                                     message):
    lines = (synthetic_dir / "82" / "82_02.amc").read_bytes().decode().split("\r\n")
    start = lines.index(str(frame))
    at = next(i for i in range(start, len(lines)) if lines[i].split()[0] == bone)
    lines[at] = new
    path = tmp_path / "82_02.amc"
    path.write_bytes("\r\n".join(lines).encode())
    with pytest.raises(DataFileError, match=message) as info:
        read_amc(path, synthetic_catalog.skeleton("82"))
    assert info.value.path == str(path) and info.value.line == at + 1
