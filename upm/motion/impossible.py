"""Impossible postures made from real frames: the calibration harness's sensitivity suite.

Each family changes real frames so that they are impossible **by anatomy**, far past any
human's range — not past this project's thresholds:

- ``knee_hyperextension``, ``elbow_hyperextension``: the joint bent 60 degrees the wrong
  way (humans: 0-15);
- ``hip_hyperextension``: the thigh swung straight back, 90 degrees of extension
  (humans: 10-30);
- ``twist``: the thigh turned 135 degrees about itself on top of the real frame (the
  hip's whole rotation arc is about 90);
- ``limbs_through``: both thighs swung 60 degrees across the body, so that each passes
  through the other;
- ``sunk``: the body lowered until its lowest bone end is 15 cm under the floor;
- ``mix``: a knee bent 40 degrees the wrong way with the body 8 cm under the floor.
"""

from __future__ import annotations

import numpy as np

from upm.motion.anatomy import SAGITTAL_MIRROR, hinge_sign, is_right, joint_rotations
from upm.motion.kinematics import global_transforms
from upm.motion.skeleton import JOINTS, Skeleton
from upm.ops.rotations import matrix_to_euler_deg, rotation_exp

#: The families, in report order.
FAMILIES: tuple[str, ...] = ("knee_hyperextension", "elbow_hyperextension",
                             "hip_hyperextension", "twist", "limbs_through", "sunk", "mix")


def _set_hinge(skeleton: Skeleton, posture: np.ndarray, joint: str, angle_deg: float):
    """Set a 1-DOF joint to an anatomical angle (see :data:`upm.motion.anatomy.HINGE_AXIS`)."""
    posture[:, 3 * JOINTS.index(joint)] = angle_deg * hinge_sign(skeleton, joint)


def _set_rotation(skeleton: Skeleton, posture: np.ndarray, joint: str, local: np.ndarray):
    """Set a 3-DOF joint's rotation relative to its parent ((T, 3, 3), mirrored frame)."""
    if is_right(joint):
        local = SAGITTAL_MIRROR @ local @ SAGITTAL_MIRROR
    c = skeleton.axis_matrices[skeleton.bone_index(joint)]
    m = c.T @ local @ c
    j = 3 * JOINTS.index(joint)
    posture[:, j:j + 3] = matrix_to_euler_deg(m, "XYZ")


def _swing_to(skeleton: Skeleton, joint: str, direction: np.ndarray, n: int) -> np.ndarray:
    """The minimal swing taking the bone's rest direction to ``direction`` (mirrored
    frame), (n, 3, 3)."""
    from upm.motion.anatomy import rest_direction

    d = rest_direction(skeleton, joint)
    u = direction / np.linalg.norm(direction)
    axis = np.cross(d, u)
    angle = np.arctan2(np.linalg.norm(axis), d @ u)
    rot = rotation_exp(axis / max(np.linalg.norm(axis), 1e-12) * angle)
    return np.broadcast_to(rot, (n, 3, 3)).copy()


def _sink(skeleton: Skeleton, posture: np.ndarray, root: np.ndarray, depth_m: float):
    """Lower the root so that the lowest bone end is ``depth_m`` under the floor (y=0)."""
    _, positions = global_transforms(skeleton, posture, root)
    lowest = positions[..., 1].min(axis=1)
    root[:, 1] -= lowest + depth_m


def make_family(family: str, skeleton: Skeleton, posture_deg, root):
    """A family's impossible version of real frames.

    Parameters
    ----------
    family : str
        One of :data:`FAMILIES`.
    skeleton : Skeleton
    posture_deg : array_like, shape (T, 63)
    root : array_like, shape (T, 6)

    Returns
    -------
    posture_deg : ndarray, shape (T, 63)
    root : ndarray, shape (T, 6)
    """
    posture = np.array(posture_deg, dtype=float)
    root = np.array(root, dtype=float)
    n = posture.shape[0]
    if family == "knee_hyperextension":
        _set_hinge(skeleton, posture, "ltibia", -60.0)
    elif family == "elbow_hyperextension":
        _set_hinge(skeleton, posture, "rradius", -60.0)
    elif family == "hip_hyperextension":
        _set_rotation(skeleton, posture, "lfemur",
                      _swing_to(skeleton, "lfemur", np.array([0.0, -0.02, -1.0]), n))
    elif family == "twist":
        local = joint_rotations(skeleton, posture)[:, JOINTS.index("rfemur")]
        from upm.motion.anatomy import rest_direction

        limb = local @ rest_direction(skeleton, "rfemur")
        _set_rotation(skeleton, posture, "rfemur",
                      rotation_exp(limb * np.deg2rad(135.0)) @ local)
    elif family == "limbs_through":
        across = np.array([-np.sin(np.deg2rad(60.0)), -np.cos(np.deg2rad(60.0)), 0.0])
        for joint in ("lfemur", "rfemur"):
            _set_rotation(skeleton, posture, joint, _swing_to(skeleton, joint, across, n))
    elif family == "sunk":
        _sink(skeleton, posture, root, 0.15)
    elif family == "mix":
        _set_hinge(skeleton, posture, "rtibia", -40.0)
        _sink(skeleton, posture, root, 0.08)
    else:
        raise ValueError(f"no impossible family {family!r} (families: {', '.join(FAMILIES)})")
    return posture, root
