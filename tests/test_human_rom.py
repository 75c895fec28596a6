"""The human range of motion: anatomical angles on each subject's ASF axes, the ranges,
range files, and the calibration harness's impossible families."""

import json

import numpy as np
import pytest

from upm.motion import human_rom
from upm.motion.anatomy import anatomical_angles_deg
from upm.motion.impossible import FAMILIES, _set_hinge, _set_rotation, _swing_to
from upm.motion.kinematics import global_transforms
from upm.motion.range_models import range_model
from upm.motion.skeleton import JOINTS

SUBJECTS = ("02", "05", "141")


def _ends(skeleton, posture):
    """World positions of every bone's distal end with the root at rest, (B, 3)."""
    root = np.zeros((1, 6))
    return global_transforms(skeleton, posture[None], root)[1][0]


@pytest.mark.parametrize("subject", SUBJECTS)
def test_known_poses_land_where_anatomy_says(catalog, subject):
    """Each joint's anatomical angle moves the limb the way anatomy names it, on every
    subject's own axes (x left, y up, z forward)."""
    sk = catalog.skeleton(subject)
    i = {name: sk.bone_index(name) for name in sk.bone_names}
    rest = np.zeros((1, 63))
    # knee flexion 90: the ankle goes behind the knee
    p = rest.copy()
    _set_hinge(sk, p, "ltibia", 90.0)
    ends = _ends(sk, p[0])
    assert ends[i["ltibia"], 2] < ends[i["lfemur"], 2] - 0.2
    assert anatomical_angles_deg(sk, p)["ltibia"][0] == pytest.approx(90.0, abs=1.0)
    # right elbow flexion 90, arm held out sideways: the hand comes forward
    p = rest.copy()
    _set_hinge(sk, p, "rradius", 90.0)
    ends = _ends(sk, p[0])
    assert ends[i["rradius"], 2] > ends[i["rhumerus"], 2] + 0.08
    # hip flexion 90: the knee in front of the hip, elevation 90 in the forward plane
    for side in "lr":
        p = rest.copy()
        _set_rotation(sk, p, f"{side}femur", _swing_to(sk, f"{side}femur",
                                                       np.array([0.0, 0.0, 1.0]), 1))
        ends = _ends(sk, p[0])
        assert ends[i[f"{side}femur"], 2] > ends[i[f"{side}hipjoint"], 2] + 0.3
        elevation, plane, _ = anatomical_angles_deg(sk, p)[f"{side}femur"][0]
        assert elevation == pytest.approx(90.0, abs=1.0) and abs(plane) < 1.0
        # abduction: the knee goes outward (left +x, right -x), plane 90 on both sides
        p = rest.copy()
        outward = np.array([np.sin(np.deg2rad(40.0)), -np.cos(np.deg2rad(40.0)), 0.0])
        _set_rotation(sk, p, f"{side}femur", _swing_to(sk, f"{side}femur", outward, 1))
        ends = _ends(sk, p[0])
        sign = 1 if side == "l" else -1
        assert sign * ends[i[f"{side}femur"], 0] > sign * ends[i[f"{side}hipjoint"], 0] + 0.2
        assert anatomical_angles_deg(sk, p)[f"{side}femur"][0, 1] == pytest.approx(90, abs=1)
    # the arm hanging down at the side: shoulder elevation 0
    p = rest.copy()
    _set_rotation(sk, p, "lhumerus", _swing_to(sk, "lhumerus", np.array([0.0, -1, 0]), 1))
    assert anatomical_angles_deg(sk, p)["lhumerus"][0, 0] == pytest.approx(0.0, abs=1.0)


def test_the_rest_pose_and_real_walks_are_inside_the_human_range(catalog):
    for clip in ("02_01", "16_15"):
        motion = catalog.load(clip)
        assert human_rom.human_excess_deg(motion.skeleton, motion.posture_deg).max() == 0.0
    sk = catalog.skeleton("02")
    assert human_rom.human_excess_deg(sk, np.zeros((1, 63))).max() == 0.0
    assert len(human_rom.RULES) == 47 and len(set(human_rom.RULES)) == 47


def test_the_train_widened_table_is_what_the_train_split_gives(catalog):
    """The committed TRAIN_WIDENED is refine() of the train split, and never wider than
    MAX_WIDEN_DEG beyond the literature."""
    from upm.motion.rom_refine import refine

    assert refine(catalog.load(n) for n in catalog.names("train")) == human_rom.TRAIN_WIDENED
    for rule, (low, high) in human_rom.TRAIN_WIDENED.items():
        if "@" in rule:
            continue
        lit_low, lit_high = human_rom.literature_box(rule)
        assert lit_low - human_rom.MAX_WIDEN_DEG <= low <= lit_low
        assert lit_high <= high <= lit_high + human_rom.MAX_WIDEN_DEG


def test_range_files_replace_rules_and_bad_files_are_one_line_errors(tmp_path, catalog):
    from upm.core.errors import UsageError

    motion = catalog.load("02_01")
    tight = tmp_path / "tight.json"
    tight.write_text(json.dumps({"model": "human", "ranges": {"ltibia.flexion": [0, 20]}}))
    excess = range_model(str(tight)).excess_deg(motion.skeleton, motion.posture_deg)
    column = human_rom.RULES.index("ltibia.flexion")
    assert excess[:, column].max() > 10 and np.delete(excess, column, axis=1).max() == 0
    for text, message in (("{", "not a JSON range file"),
                          ('{"model": "nope"}', "'model' must be"),
                          ('{"ranges": {"knee": [0, 1]}}', "no human rule 'knee'"),
                          ('{"ranges": {"ltibia.flexion": [5, 1]}}', "low <= high")):
        bad = tmp_path / "bad.json"
        bad.write_text(text)
        with pytest.raises(UsageError, match=message):
            range_model(str(bad))


def test_every_impossible_family_is_judged_invalid_and_real_frames_valid(catalog):
    """A small case of the harness: 02_01 (a walk) and 141_04 (jumps) every 25th frame;
    each family >= 95 % invalid, by the cause it was made for."""
    from eval.calibration import sensitivity

    result = sensitivity(catalog, ["02_01", "141_04"], every=25)
    assert set(result) == set(FAMILIES)
    for family, row in result.items():
        assert row["frames"] == 14 + 22
        assert row["invalid_pct"] >= 95, family
    assert result["limbs_through"]["self_frames"] == result["limbs_through"]["frames"]
    assert result["sunk"]["floor_frames"] == result["sunk"]["frames"]
    assert result["knee_hyperextension"]["limit_frames"] == result["knee_hyperextension"][
        "frames"]


def test_touching_is_allowed_and_interpenetration_is_not(catalog, model02):
    """Real 02_01 touches itself (legs brushing) in some frames and is valid; the same
    frames with the thighs swung through each other are not."""
    from controller.checks.validity import check_motion
    from upm.motion.impossible import make_family

    walk = catalog.load("02_01")
    validity = check_motion(model02, walk)
    assert validity.self_touch.sum() > 5 and validity.valid.all()
    assert JOINTS  # the posture layout the families write into
    posture, root = make_family("limbs_through", walk.skeleton, walk.posture_deg, walk.root)
    through = check_motion(model02, walk.replace(posture_deg=posture, root=root))
    assert through.self_collision.all()
    assert through.self_excess_m.min() > 0.02


def test_the_calibrate_command_reports_both_figures(data_dir, tmp_path, capsys):
    """upm calibrate on one clip: its JSON has the specificity (human and ASF verdicts)
    and every family's sensitivity; the report, its Markdown table and the figure are
    written; bad input is a one-line error."""
    from upm.cli import main

    report, figure = tmp_path / "cal.json", tmp_path / "cal.png"
    assert main(["calibrate", "02_01", "--data", str(data_dir), "--every", "60", "--json",
                 "--report", str(report), "--figure", str(figure)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert json.loads(report.read_text()) == result
    assert result["specificity"]["totals"]["valid_pct"] == 100.0
    assert result["specificity"]["asf_totals"]["valid_pct"] < 70
    assert set(result["sensitivity"]) == set(FAMILIES)
    assert all(row["invalid_pct"] == 100.0 for row in result["sensitivity"].values())
    assert "| knee_hyperextension |" in report.with_suffix(".md").read_text()
    assert figure.read_bytes()[:4] == b"\x89PNG"
    assert main(["calibrate", "02_01", "--data", str(data_dir), "--every", "0"]) == 2
    assert "--every must be at least 1" in capsys.readouterr().err
    assert main(["calibrate", "99_99", "--data", str(data_dir)]) == 2
    assert "no clip '99_99'" in capsys.readouterr().err
