"""Motions into MuJoCo ``qpos`` and back, on a model made by :mod:`humanoid_xml`.

``to_qpos`` maps, per frame:

- the root translation ``(tx, ty, tz)`` (ASF frame, metres) to the free joint's position
  ``ASF_TO_MJ @ t`` (z up), absolute: the model's floor is the mocap floor (y = 0);
- the root rotation ``R = euler(rx, ry, rz)`` in the ASF root order to the free joint's
  quaternion of ``ASF_TO_MJ R ASF_TO_MJ^T``;
- each posture DOF that has a hinge (joint ``<bone>_<dof>``, found by name) to its
  ``qpos`` in radians, the angle first wrapped to [-180, 180) degrees (CMU angles are
  sometimes unwrapped past +-360; wrapping changes nothing kinematically). Undeclared
  DOFs have no hinge and are ignored (they are 0 in every CMU clip).

``from_qpos`` is the inverse: root angles come back as one Euler solution in
[-180, 180), posture angles wrapped; forward kinematics of the result equals the model's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from humanoid_xml.frames import ASF_TO_MJ, rotations_to_asf, rotations_to_mj
from upm.motion.motion import Motion
from upm.motion.skeleton import POSTURE_DOF_NAMES, POSTURE_SIZE, Skeleton
from upm.ops.angles import wrap_deg
from upm.ops.rotations import euler_to_matrix


@dataclass(frozen=True)
class JointLayout:
    """Where a humanoid's joints sit in ``qpos``, ``qvel`` and the posture.

    Attributes
    ----------
    posture_index : ndarray of int, shape (H,)
        For each hinge (in model joint order), its index in the 63-value posture.
    qpos_address : ndarray of int, shape (H,)
        Each hinge's ``qpos`` address.
    dof_address : ndarray of int, shape (H,)
        Each hinge's ``qvel`` (DOF) address.
    range_deg : ndarray, shape (H, 2)
        Each hinge's range (the ASF limits), degrees.
    free_qpos : int
        The free root joint's ``qpos`` address (7 values: position, quaternion w x y z).
    free_dof : int
        Its ``qvel`` address (6 values: linear velocity in the world frame, angular
        velocity in the root's own frame).
    names : tuple of str
        Each hinge's posture DOF name (``"lfemur.rx"``).
    """

    posture_index: np.ndarray
    qpos_address: np.ndarray
    dof_address: np.ndarray
    range_deg: np.ndarray
    free_qpos: int
    free_dof: int
    names: tuple[str, ...]


def joint_layout(model) -> JointLayout:
    """The :class:`JointLayout` of a model made by :func:`humanoid_xml.build_mjcf`.

    Raises
    ------
    ValueError
        If a hinge is not named after a posture DOF, or there is not exactly one free
        root joint.
    """
    import mujoco

    posture_index, qpos_address, dof_address, ranges, names = [], [], [], [], []
    free = free_joint(model)
    for j in range(model.njnt):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE:
            continue
        dof_name = name.replace("_", ".", 1) if name else ""
        # Bone names have no underscore; "lfemur_rx" -> "lfemur.rx".
        if dof_name not in POSTURE_DOF_NAMES:
            raise ValueError(f"model hinge {name!r} is not a posture DOF (<bone>_<rx|ry|rz>)")
        posture_index.append(POSTURE_DOF_NAMES.index(dof_name))
        qpos_address.append(int(model.jnt_qposadr[j]))
        dof_address.append(int(model.jnt_dofadr[j]))
        ranges.append(np.rad2deg(model.jnt_range[j]))
        names.append(dof_name)
    return JointLayout(posture_index=np.array(posture_index, dtype=int),
                       qpos_address=np.array(qpos_address, dtype=int),
                       dof_address=np.array(dof_address, dtype=int),
                       range_deg=np.array(ranges, dtype=float).reshape(-1, 2),
                       free_qpos=int(model.jnt_qposadr[free]),
                       free_dof=int(model.jnt_dofadr[free]), names=tuple(names))


def wrap_rad(x):
    """Angles wrapped to [-pi, pi)."""
    return np.mod(np.asarray(x) + np.pi, 2 * np.pi) - np.pi


def free_joint(model) -> int:
    """The id of the model's one free (root) joint.

    Raises
    ------
    ValueError
        If the model has no free joint or more than one.
    """
    import mujoco

    free = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_FREE)
    if free.size != 1:
        raise ValueError("the model needs exactly one free (root) joint")
    return int(free[0])


def _joint_map(model) -> tuple[np.ndarray, np.ndarray, int]:
    """Posture indices that have a hinge, their qpos addresses, and the free joint's."""
    layout = joint_layout(model)
    return layout.posture_index, layout.qpos_address, layout.free_qpos


def root_to_qpos(root, root_axis_order: str = "XYZ") -> np.ndarray:
    """Free-joint coordinates of AMC root values.

    Parameters
    ----------
    root : array_like, shape (T, 6)
        tx, ty, tz (metres), rx, ry, rz (degrees), ASF frame.
    root_axis_order : str
        The ASF root rotation order (x applied first for ``"XYZ"``).

    Returns
    -------
    ndarray, shape (T, 7)
        Position (z up) and unit quaternion (w, x, y, z), w >= 0.
    """
    root = np.atleast_2d(np.asarray(root, dtype=float))
    out = np.empty((root.shape[0], 7))
    out[:, :3] = root[:, :3] @ ASF_TO_MJ.T
    r_mj = rotations_to_mj(euler_to_matrix(root[:, 3:6], root_axis_order))
    xyzw = Rotation.from_matrix(r_mj).as_quat()
    quat = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
    quat *= np.where(quat[:, :1] < 0, -1.0, 1.0)
    out[:, 3:] = quat
    return out


def qpos_to_root(free_qpos, root_axis_order: str = "XYZ") -> np.ndarray:
    """AMC root values of free-joint coordinates (the inverse of :func:`root_to_qpos`).

    Parameters
    ----------
    free_qpos : array_like, shape (T, 7)
    root_axis_order : str

    Returns
    -------
    ndarray, shape (T, 6)
        tx, ty, tz (metres), rx, ry, rz (degrees, one Euler solution in [-180, 180)).
    """
    q = np.atleast_2d(np.asarray(free_qpos, dtype=float))
    out = np.empty((q.shape[0], 6))
    out[:, :3] = q[:, :3] @ ASF_TO_MJ
    xyzw = np.concatenate([q[:, 4:7], q[:, 3:4]], axis=1)
    r_asf = rotations_to_asf(Rotation.from_quat(xyzw).as_matrix())
    # scipy's lower-case sequences are extrinsic: "xyz" = x applied first = Acclaim "XYZ".
    angles = Rotation.from_matrix(r_asf).as_euler(root_axis_order.lower(), degrees=True)
    for k, axis in enumerate(root_axis_order.upper()):
        out[:, 3 + "XYZ".index(axis)] = angles[:, k]
    out[:, 3:] = wrap_deg(out[:, 3:])
    return out


def to_qpos(model, motion: Motion) -> np.ndarray:
    """Every frame of a motion as the model's ``qpos``.

    Parameters
    ----------
    model : mujoco.MjModel
        A humanoid made by :func:`humanoid_xml.build_mjcf` (ideally from the motion's own
        skeleton, so that the bone offsets match).
    motion : Motion

    Returns
    -------
    ndarray, shape (T, model.nq)
    """
    posture_index, qpos_address, free = _joint_map(model)
    qpos = np.tile(np.asarray(model.qpos0, dtype=float), (motion.n_frames, 1))
    qpos[:, free:free + 7] = root_to_qpos(motion.root, motion.skeleton.root_axis_order)
    qpos[:, qpos_address] = np.deg2rad(wrap_deg(motion.posture_deg[:, posture_index]))
    return qpos


def from_qpos(model, qpos, skeleton: Skeleton, fps: float = 120.0, name: str = "") -> Motion:
    """A motion from the model's ``qpos`` (the inverse of :func:`to_qpos`).

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : array_like, shape (T, model.nq)
    skeleton : Skeleton
        The skeleton the motion is for (its root axis order is used).
    fps : float
    name : str

    Returns
    -------
    Motion
        Posture DOFs without a hinge are 0; angles in [-180, 180).
    """
    qpos = np.atleast_2d(np.asarray(qpos, dtype=float))
    if qpos.shape[1] != model.nq:
        raise ValueError(f"qpos must have shape (T, {model.nq}), not {qpos.shape}")
    posture_index, qpos_address, free = _joint_map(model)
    posture = np.zeros((qpos.shape[0], POSTURE_SIZE))
    posture[:, posture_index] = wrap_deg(np.rad2deg(qpos[:, qpos_address]))
    root = qpos_to_root(qpos[:, free:free + 7], skeleton.root_axis_order)
    return Motion(skeleton=skeleton, posture_deg=posture, root=root, fps=fps, name=name)


def posture_to_ctrl(model, posture_deg) -> np.ndarray:
    """Position-actuator targets (radians) of postures: a posture is a control vector.

    Parameters
    ----------
    model : mujoco.MjModel
        Its actuators are named like the hinges they drive (``lfemur_rx``).
    posture_deg : array_like, shape (T, 63) or (63,)

    Returns
    -------
    ndarray, shape (T, model.nu) or (model.nu,)
        Angles wrapped to [-180, 180) degrees, then in radians, in actuator order (not
        clipped: MuJoCo clamps to each actuator's ``ctrlrange``, the joint range).
    """
    import mujoco

    posture = np.asarray(posture_deg, dtype=float)
    index = []
    for a in range(model.nu):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or ""
        dof_name = name.replace("_", ".", 1)
        if dof_name not in POSTURE_DOF_NAMES:
            raise ValueError(f"actuator {name!r} is not named after a posture DOF")
        index.append(POSTURE_DOF_NAMES.index(dof_name))
    return np.deg2rad(wrap_deg(posture[..., index]))
