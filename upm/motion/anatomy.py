"""Anatomical joint angles of postures, whatever each subject's ASF axis frames.

The ASF gives every bone its own ``axis`` frame C, so ``femur.rx`` is not "hip flexion"
(and differs between subjects). Here each of the 21 joints' rotation relative to its
parent, ``L = C M C^T`` (the world frame at rest: x the subject's left, y up, z forward),
is described in the same anatomical terms for every subject. Right-side joints are
mirrored through the sagittal plane first (``L' = S L S``, ``S = diag(-1, 1, 1)``), so that
one table of ranges serves both sides.

Per joint kind (:data:`JOINT_KIND`):

- **hinge** (knee, elbow, toes): the rotation angle of L, degrees, signed by the side of
  the anatomical hinge axis its rotation axis lies on: positive in flexion (knee, elbow)
  or in extension (toes: the toes bent up).
- **ball** (hip, shoulder): the limb's direction ``u = L d`` (``d`` the bone's rest
  direction) as *elevation* (degrees away from the neutral direction) in a *plane*
  (the azimuth of that swing, degrees), and the *twist* about the limb: the rotation
  left once the minimal swing from neutral to ``u`` is taken off (swing-twist). Both
  neutrals are the limb hanging straight down (plane 0 forward, 90 outward); the
  shoulder's twist is zero with the arm brought down from the ASF rest (held out
  sideways) by the shortest swing: the palm towards the thigh.
- **euler** (spine, neck, head, clavicle, ankle, wrist): anatomical Euler angles of L in
  the world axes: about x (flexion), y (axial), z (lateral), in the joint's order.
"""

from __future__ import annotations

import numpy as np

from upm.motion.skeleton import JOINTS, Skeleton
from upm.ops.rotations import euler_to_matrix, matrix_to_euler_deg, rotation_log

#: How each joint's rotation is described (see the module docstring).
JOINT_KIND: dict[str, str] = {
    **{j: "euler" for j in ("lclavicle", "rclavicle", "thorax", "upperback", "lowerback",
                            "lowerneck", "head", "lfoot", "rfoot", "lhand", "rhand")},
    **{j: "ball" for j in ("lhumerus", "rhumerus", "lfemur", "rfemur")},
    **{j: "hinge" for j in ("ltibia", "rtibia", "lradius", "rradius", "ltoes", "rtoes")},
}

#: The world axes at rest (the ASF's): x left, y up, z forward.
LEFT, UP, FORWARD = np.eye(3)
#: Reflection through the sagittal plane (x -> -x): right-side joints are mirrored by it.
SAGITTAL_MIRROR = np.diag([-1.0, 1.0, 1.0])

#: Hinge axes (left side, world rest frame), signed so that a positive angle is flexion
#: for the knee and elbow (the shank swings back; the forearm, arm held out sideways with
#: the palm down, swings forward) and extension (toes up) for the toes.
HINGE_AXIS: dict[str, np.ndarray] = {"tibia": LEFT, "radius": -UP, "toes": -LEFT}

#: The Euler order of each "euler" joint's anatomical angles (first letter applied first).
EULER_ORDER: dict[str, str] = {"clavicle": "ZYX", "thorax": "XZY", "upperback": "XZY",
                               "lowerback": "XZY", "lowerneck": "XZY", "head": "XZY",
                               "foot": "XZY", "hand": "ZYX"}


def base_name(joint: str) -> str:
    """The joint without its side: ``"lfemur"`` -> ``"femur"``."""
    return joint[1:] if joint[0] in "lr" and joint[1:] in _SIDED else joint


_SIDED = {"clavicle", "humerus", "femur", "tibia", "radius", "foot", "toes", "hand"}


def is_right(joint: str) -> bool:
    return joint[0] == "r" and joint[1:] in _SIDED


def joint_rotations(skeleton: Skeleton, posture_deg) -> np.ndarray:
    """Each joint's rotation relative to its parent, in the world frame at rest.

    Parameters
    ----------
    skeleton : Skeleton
    posture_deg : array_like, shape (T, 63)

    Returns
    -------
    ndarray, shape (T, 21, 3, 3)
        ``L = C M C^T`` per joint, in :data:`upm.motion.skeleton.JOINTS` order; right-side
        joints mirrored (``S L S``).
    """
    posture = np.atleast_2d(np.asarray(posture_deg, dtype=float))
    m = euler_to_matrix(posture.reshape(-1, len(JOINTS), 3), "XYZ")
    c = np.stack([skeleton.axis_matrices[skeleton.bone_index(j)] for j in JOINTS])
    local = c @ m @ np.swapaxes(c, -1, -2)
    right = np.array([is_right(j) for j in JOINTS])
    local[:, right] = SAGITTAL_MIRROR @ local[:, right] @ SAGITTAL_MIRROR
    return local


def rest_direction(skeleton: Skeleton, joint: str) -> np.ndarray:
    """A bone's unit rest direction, world frame, mirrored for right-side bones, (3,)."""
    d = np.asarray(skeleton.directions[skeleton.bone_index(joint)], dtype=float)
    if is_right(joint):
        d = SAGITTAL_MIRROR @ d
    return d / max(np.linalg.norm(d), 1e-12)


def hinge_angle_deg(local: np.ndarray, joint: str) -> np.ndarray:
    """Hinge angle of (T, 3, 3) joint rotations, (T,) degrees (see :data:`HINGE_AXIS`)."""
    rotvec = rotation_log(local)
    side = np.where(rotvec @ HINGE_AXIS[base_name(joint)] < 0, -1.0, 1.0)
    return np.rad2deg(np.linalg.norm(rotvec, axis=-1)) * side


def euler_angles_deg(local: np.ndarray, joint: str) -> np.ndarray:
    """Anatomical Euler angles about x, y, z of (T, 3, 3) rotations, (T, 3) degrees."""
    return matrix_to_euler_deg(local, EULER_ORDER[base_name(joint)])


def _minimal_swing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotations taking unit vectors a to b by the shortest arc, (T, 3, 3)."""
    axis = np.cross(a, b)
    sin = np.linalg.norm(axis, axis=-1)
    cos = np.einsum("...i,...i->...", a, b)
    angle = np.arctan2(sin, cos)
    unit = axis / np.maximum(sin, 1e-12)[..., None]
    from upm.ops.rotations import rotation_exp

    return rotation_exp(unit * angle[..., None])


def ball_angles_deg(local: np.ndarray, rest_dir: np.ndarray, joint: str) -> np.ndarray:
    """Elevation, plane and twist of a hip or shoulder, (T, 3) degrees.

    Parameters
    ----------
    local : ndarray, shape (T, 3, 3)
        The joint's rotations (:func:`joint_rotations`; a right joint mirrored).
    rest_dir : ndarray, shape (3,)
        The bone's rest direction (:func:`rest_direction`).
    joint : str

    Returns
    -------
    ndarray, shape (T, 3)
        ``elevation`` in [0, 180] from hanging straight down; ``plane`` in (-180, 180]:
        0 forward (flexion), 90 outward (abduction), -90 across the body, 180 back
        (extension); ``twist`` in (-180, 180], positive outward (external rotation).
    """
    u = local @ rest_dir
    elevation = np.rad2deg(np.arccos(np.clip(-u[:, 1], -1.0, 1.0)))
    plane = np.rad2deg(np.arctan2(u[:, 0], u[:, 2]))
    # twist: the rotation left after the minimal swing from the twist reference to u
    reference = np.broadcast_to(_twist_reference(rest_dir, joint), u.shape)
    neutral = _minimal_swing(np.broadcast_to(rest_dir, u.shape), reference)
    relative = local @ np.swapaxes(neutral, -1, -2)  # takes `reference` to u
    swing = _minimal_swing(reference, u)
    twist_rot = np.swapaxes(swing, -1, -2) @ relative  # about `reference`
    twist = np.rad2deg(rotation_log(twist_rot) @ reference[0])
    return np.stack([elevation, plane, -twist], axis=-1)


def _twist_reference(rest_dir: np.ndarray, joint: str) -> np.ndarray:
    """The direction the twist is measured about: the limb hanging straight down (the
    twist is undefined only with the limb straight up; see
    :data:`upm.motion.human_rom.TWIST_MAX_ELEVATION_DEG`)."""
    return -UP


def anatomical_angles_deg(skeleton: Skeleton, posture_deg) -> dict[str, np.ndarray]:
    """Every joint's anatomical angles, by joint name.

    Returns
    -------
    dict of str to ndarray
        hinge joints (T,) degrees; ball joints (T, 3) elevation, plane, twist; euler joints
        (T, 3) about x, y, z.
    """
    local = joint_rotations(skeleton, posture_deg)
    return {joint: joint_angles_deg(skeleton, joint, local[:, j])
            for j, joint in enumerate(JOINTS)}


def joint_angles_deg(skeleton: Skeleton, joint: str, local: np.ndarray) -> np.ndarray:
    """One joint's anatomical angles from its (T, 3, 3) rotations (mirrored for a right
    joint, as :func:`joint_rotations` gives them): (T,) for a hinge, (T, 3) otherwise."""
    kind = JOINT_KIND[joint]
    if kind == "hinge":
        return hinge_angle_deg(local, joint)
    if kind == "ball":
        return ball_angles_deg(local, rest_direction(skeleton, joint), joint)
    return euler_angles_deg(local, joint)


def hinge_sign(skeleton: Skeleton, joint: str) -> float:
    """+1 where a hinge joint's ASF rx turns it the anatomical way (:data:`HINGE_AXIS`),
    -1 where it turns it the other way (a rotation axis mirrors as a pseudovector)."""
    axis = skeleton.axis_matrices[skeleton.bone_index(joint)][:, 0]
    if is_right(joint):
        axis = -SAGITTAL_MIRROR @ axis
    return -1.0 if axis @ HINGE_AXIS[base_name(joint)] < 0 else 1.0
