"""A human range of motion: per joint, in anatomical terms (:mod:`upm.motion.anatomy`).

Every range starts from the literature (:data:`SOURCES`) and may be widened to what real
people of the train split did (:data:`TRAIN_WIDENED`, at most :data:`MAX_WIDEN_DEG`
beyond the literature; computed by :func:`upm.motion.rom_refine.refine` and checked
against the data by the tests). The test split and other subjects never refine it.

Rules (one column of the excess table each; :func:`rule_names`):

- hinge joints (knee, elbow, toes): ``ltibia.flexion`` ...: one box;
- hips and shoulders: ``lfemur.swing`` — the elevation beyond the largest the joint
  allows in that plane (:data:`BALL_ELEVATION_DEG`, interpolated between the eight
  planes: a coupled limit, the flexion allowed depends on the abduction) — and
  ``lfemur.twist``, the twist beyond its box;
- the other joints: three anatomical Euler angles (about x, y, z; named per joint by
  :data:`EULER_NAMES`, e.g. ``thorax.flexion``, ``lfoot.plantarflexion``), each a box.
"""

from __future__ import annotations

import numpy as np

from upm.motion.anatomy import JOINT_KIND, anatomical_angles_deg, base_name
from upm.motion.skeleton import JOINTS, Skeleton

#: Where the literature's numbers come from (named in docs/results/calibration.md).
SOURCES: dict[str, str] = {
    "AAOS": "American Academy of Orthopaedic Surgeons, Joint Motion: Method of Measuring "
            "and Recording (1965), as tabulated by Greene & Heckman, The Clinical "
            "Measurement of Joint Motion (AAOS, 1994)",
    "Soucie": "Soucie et al., Range of motion measurements: reference values and a database "
              "for comparison studies, Haemophilia 17 (2011) 500-507 (normal subjects)",
    "OpenSim": "Rajagopal et al., Full-body musculoskeletal model for muscle-driven "
               "simulation of human gait, IEEE TBME 63 (2016): the model's coordinate "
               "ranges (hip flexion -30..120, adduction -50..30, rotation -40..40; knee "
               "0..120 active)",
    "Bennell": "Bennell et al., Intra-rater and inter-rater reliability of a weight-bearing "
               "lunge measure of ankle dorsiflexion, Aust J Physiother 44 (1998): about 45 "
               "degrees weight-bearing dorsiflexion",
    "Hemmerich": "Hemmerich et al., Hip, knee, and ankle kinematics of high range of motion "
                 "activities of daily living, J Orthop Res 24 (2006): knee flexion to about "
                 "157 degrees squatting and kneeling",
}

#: Anatomical names of the three Euler angles (about x, y, z) of each "euler" joint.
EULER_NAMES: dict[str, tuple[str, str, str]] = {
    **{b: ("flexion", "axial", "lateral")
       for b in ("lowerback", "upperback", "thorax", "lowerneck", "head")},
    "clavicle": ("axial", "protraction", "elevation"),
    "foot": ("plantarflexion", "abduction", "inversion"),
    "hand": ("twist", "deviation", "flexion"),
}


def euler_names(joint: str) -> tuple[str, str, str]:
    """The names of a joint's three anatomical Euler angles (about x, y, z)."""
    return EULER_NAMES[base_name(joint)]

#: Literature ranges of the 1-DOF joints and of the Euler angles, degrees (left side;
#: right joints are mirrored), with their source key. Euler joints: (x, y, z) boxes.
LITERATURE: dict[str, tuple] = {
    # hinge: positive flexion (knee, elbow), extension (toes up)
    "tibia": ((-15.0, 155.0), "Soucie hyperextension to about 15 in normal subjects; "
                               "Hemmerich squat flexion"),
    "radius": ((-10.0, 150.0), "AAOS elbow 0-150, hyperextension to 10"),
    "toes": ((-45.0, 70.0), "AAOS hallux MTP flexion 45, extension 70"),
    # euler: x flexion (+ forward / plantarflexion), y axial, z lateral
    "lowerback": (((-25.0, 60.0), (-30.0, 30.0), (-25.0, 25.0)),
                  "AAOS thoracolumbar flexion 60, extension 25, rotation 30, lateral 25"),
    "upperback": (((-25.0, 40.0), (-35.0, 35.0), (-25.0, 25.0)),
                  "AAOS thoracic share of trunk flexion/extension, rotation, lateral"),
    "thorax": (((-25.0, 40.0), (-35.0, 35.0), (-25.0, 25.0)),
               "AAOS thoracic share of trunk flexion/extension, rotation, lateral"),
    "lowerneck": (((-45.0, 45.0), (-60.0, 60.0), (-45.0, 45.0)),
                  "AAOS cervical flexion 45, extension 45, rotation 60, lateral 45"),
    "head": (((-25.0, 25.0), (-40.0, 40.0), (-15.0, 15.0)),
             "upper cervical (C0-C2) flexion/extension 25, rotation 40, lateral 15"),
    "clavicle": (((-50.0, 50.0), (-30.0, 30.0), (-10.0, 45.0)),
                 "sternoclavicular axial rotation 50, protraction/retraction 30, "
                 "elevation 45, depression 10"),
    "foot": (((-45.0, 50.0), (-30.0, 30.0), (-35.0, 35.0)),
             "Bennell dorsiflexion 45; AAOS plantarflexion 50, inversion 35/eversion 15 "
             "(box 35 both ways), forefoot abduction/adduction 30"),
    "hand": (((-30.0, 30.0), (-30.0, 30.0), (-80.0, 80.0)),
             "AAOS wrist flexion 80/extension 70 (box 80), radial 20/ulnar 30 deviation "
             "(box 30); the residual twist the two wrist DOFs leave, 30"),
}

#: Hips and shoulders: the largest elevation (degrees from hanging straight down) in each
#: plane of elevation (0 forward, 90 outward, 180 back, -90 across), and the twist box.
BALL_PLANES_DEG = np.array([-135.0, -90.0, -45.0, 0.0, 45.0, 90.0, 135.0, 180.0])
BALL_LITERATURE: dict[str, tuple] = {
    "femur": ((30.0, 30.0, 80.0, 120.0, 90.0, 45.0, 35.0, 30.0), (-45.0, 45.0),
              "AAOS/OpenSim flexion 120, extension 30, abduction 45, adduction 30, "
              "rotation 45 each way"),
    "humerus": ((45.0, 45.0, 160.0, 180.0, 180.0, 180.0, 90.0, 60.0), (-100.0, 100.0),
                "AAOS flexion 180, extension 60, abduction 180, adduction 30-45, "
                "horizontal adduction 135; Soucie external rotation to about 100, internal "
                "70 plus the scapula's share (box 100 both ways)"),
}

#: How far the train split may widen a literature range, degrees.
MAX_WIDEN_DEG = 45.0
#: Above this elevation (the limb nearly straight up) the twist is not judged: it is
#: undefined at 180 and ill-conditioned near it, degrees.
TWIST_MAX_ELEVATION_DEG = 150.0

#: The literature ranges widened to the train split's real motion (the 0.05th and
#: 99.95th percentiles of its 25,358 frames, plus 2 degrees, at most MAX_WIDEN_DEG):
#: ``rule -> (low, high)``; rules not listed keep their literature range. Regenerate
#: with ``upm calibrate --refine``.
TRAIN_WIDENED: dict[str, tuple[float, float]] = {
    "thorax.flexion": (-48.0, 40.0),
    "thorax.lateral": (-29.3, 40.3),
    "upperback.axial": (-59.9, 35.0),
    "upperback.lateral": (-25.0, 31.5),
    "lowerback.flexion": (-42.1, 94.9),
    "lowerback.axial": (-37.9, 62.2),
    "lowerback.lateral": (-56.7, 31.8),
    "lowerneck.lateral": (-52.6, 45.0),
    "lhumerus.twist": (-128.3, 100.0),
    "lhumerus.swing@180": (0.0, 72.5),
    "rhumerus.twist": (-127.9, 130.0),
    "rhumerus.swing@135": (0.0, 92.8),
    "lfemur.twist": (-90.0, 66.8),
    "lfemur.swing@-135": (0.0, 75.0),
    "lfemur.swing@-90": (0.0, 60.6),
    "lfemur.swing@45": (0.0, 106.4),
    "lfemur.swing@90": (0.0, 52.9),
    "lfemur.swing@135": (0.0, 75.8),
    "lfemur.swing@180": (0.0, 72.9),
    "rfemur.twist": (-90.0, 90.0),
    "rfemur.swing@45": (0.0, 121.2),
    "rfemur.swing@90": (0.0, 90.0),
    "rfemur.swing@135": (0.0, 80.0),
    "rfemur.swing@180": (0.0, 75.0),
    "head.lateral": (-15.0, 20.9),
    "rradius.flexion": (-10.0, 151.9),
    "lfoot.plantarflexion": (-90.0, 95.0),
    "lfoot.abduction": (-75.0, 75.0),
    "rfoot.plantarflexion": (-90.0, 95.0),
    "rfoot.abduction": (-75.0, 75.0),
    "ltoes.extension": (-64.2, 70.0),
    "rtoes.extension": (-65.8, 70.0),
    "lhand.deviation": (-67.4, 74.4),
    "rhand.twist": (-75.0, 30.0),
    "rhand.deviation": (-75.0, 75.0),
    "rhand.flexion": (-111.5, 80.0),
}


def rule_names() -> tuple[str, ...]:
    """Every rule's name, in column order (a posture's 21 joints in posture order)."""
    names = []
    for joint in JOINTS:
        kind = JOINT_KIND[joint]
        if kind == "hinge":
            names.append(f"{joint}.flexion" if base_name(joint) != "toes"
                         else f"{joint}.extension")
        elif kind == "ball":
            names += [f"{joint}.swing", f"{joint}.twist"]
        else:
            names += [f"{joint}.{axis}" for axis in euler_names(joint)]
    return tuple(names)


RULES: tuple[str, ...] = rule_names()


def literature_box(rule: str) -> tuple[float, float]:
    """A box rule's literature range (low, high) degrees; swing rules have none."""
    joint, what = rule.split(".")
    base = base_name(joint)
    if JOINT_KIND[joint] == "ball":
        if what != "twist":
            raise KeyError(f"{rule} is a coupled rule, not a box")
        return BALL_LITERATURE[base][1]
    entry = LITERATURE[base][0]
    if JOINT_KIND[joint] == "hinge":
        return entry
    return entry[euler_names(joint).index(what)]


def rule_box(rule: str, ranges: dict | None = None) -> tuple[float, float]:
    """A box rule's range as used: ``ranges`` (default :data:`TRAIN_WIDENED`) if it lists
    the rule, else the literature's."""
    return (TRAIN_WIDENED if ranges is None else ranges).get(rule, literature_box(rule))


def swing_limits_deg(joint: str, ranges: dict | None = None) -> np.ndarray:
    """The largest elevation per plane of :data:`BALL_PLANES_DEG`, (8,) degrees: from
    ``ranges`` (default :data:`TRAIN_WIDENED`) where listed, else the literature's."""
    ranges = TRAIN_WIDENED if ranges is None else ranges
    values = np.array(BALL_LITERATURE[base_name(joint)][0], dtype=float)
    for k, plane in enumerate(BALL_PLANES_DEG):
        widened = ranges.get(swing_rule(joint, plane))
        if widened is not None:
            values[k] = widened[1]
    return values


def swing_rule(joint: str, plane_deg: float) -> str:
    """The key of one plane's elevation limit in :data:`TRAIN_WIDENED`:
    ``"lfemur.swing@45"``."""
    return f"{joint}.swing@{plane_deg:g}"


def allowed_elevation_deg(plane_deg, limits_deg) -> np.ndarray:
    """The largest elevation in each plane: periodic linear interpolation, (T,) degrees."""
    planes = np.concatenate([BALL_PLANES_DEG[-1:] - 360.0, BALL_PLANES_DEG])
    values = np.concatenate([limits_deg[-1:], limits_deg])
    return np.interp(np.asarray(plane_deg, dtype=float), planes, values)


def box_excess_deg(angle_deg, low: float, high: float) -> np.ndarray:
    """Degrees outside [low, high] of angles already in (-180, 180], (T,)."""
    a = np.asarray(angle_deg, dtype=float)
    return np.maximum(np.maximum(low - a, a - high), 0.0)


def human_excess_deg(skeleton: Skeleton, posture_deg, ranges: dict | None = None
                     ) -> np.ndarray:
    """Degrees beyond the human range, per frame and rule.

    Parameters
    ----------
    skeleton : Skeleton
    posture_deg : array_like, shape (T, 63)
    ranges : dict, optional
        Rule ranges in place of :data:`TRAIN_WIDENED` (rules it lacks: the literature's).

    Returns
    -------
    ndarray, shape (T, len(RULES))
        Non-negative degrees, columns in :data:`RULES` order.
    """
    angles = anatomical_angles_deg(skeleton, posture_deg)
    columns = [column for joint in JOINTS
               for column in joint_excess_deg(joint, angles[joint], ranges)]
    return np.stack(columns, axis=-1)


def joint_excess_deg(joint: str, angles_deg: np.ndarray, ranges: dict | None = None
                     ) -> list[np.ndarray]:
    """Degrees beyond each of one joint's rules, from its anatomical angles
    (:func:`upm.motion.anatomy.joint_angles_deg`): a list of (T,) arrays, in rule order."""
    kind, value = JOINT_KIND[joint], angles_deg
    if kind == "hinge":
        return [box_excess_deg(value, *rule_box(columns_rule(joint, "flexion"), ranges))]
    if kind == "ball":
        allowed = allowed_elevation_deg(value[:, 1], swing_limits_deg(joint, ranges))
        twist = box_excess_deg(value[:, 2], *rule_box(f"{joint}.twist", ranges))
        return [np.maximum(value[:, 0] - allowed, 0.0),
                np.where(value[:, 0] <= TWIST_MAX_ELEVATION_DEG, twist, 0.0)]
    return [box_excess_deg(value[:, k], *rule_box(f"{joint}.{axis}", ranges))
            for k, axis in enumerate(euler_names(joint))]


def columns_rule(joint: str, what: str) -> str:
    """The rule name of a hinge joint (the toes' is ``extension``)."""
    return f"{joint}.extension" if base_name(joint) == "toes" else f"{joint}.{what}"
