"""The skeleton: ASF bones, and the paper's 21-joint, 4-class, 63-value posture.

A posture is 21 joints x (rx, ry, rz) in degrees, in each bone's ASF axis frame, ordered
class by class (body 15, global 15, medium 15, detail 18). A DOF the ASF does not declare
for a bone is a constant 0 with limit [0, 0]. CMU bones outside the 21 joints (hip
joints, upperneck, wrists, fingers, thumbs) keep their offsets but are not articulated:
their rotations are taken as 0 for kinematics (their AMC values are still read and kept).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: The paper's joint classes (Table 2) on CMU bone names, in posture order.
#: The paper's ``lshoulderjoint``/``rshoulderjoint`` are CMU's ``lclavicle``/``rclavicle``.
JOINT_CLASSES: dict[str, tuple[str, ...]] = {
    "body": ("lclavicle", "rclavicle", "thorax", "upperback", "lowerback"),
    "global": ("lowerneck", "lhumerus", "rhumerus", "lfemur", "rfemur"),
    "medium": ("head", "ltibia", "rtibia", "lradius", "rradius"),
    "detail": ("lfoot", "rfoot", "ltoes", "rtoes", "lhand", "rhand"),
}
CLASS_NAMES: tuple[str, ...] = tuple(JOINT_CLASSES)
JOINTS: tuple[str, ...] = tuple(j for joints in JOINT_CLASSES.values() for j in joints)
AXES: tuple[str, ...] = ("rx", "ry", "rz")
N_JOINTS = len(JOINTS)  # 21
POSTURE_SIZE = 3 * N_JOINTS  # 63
#: Name of every posture DOF, e.g. ``"lclavicle.ry"``, shape (63,).
POSTURE_DOF_NAMES: tuple[str, ...] = tuple(f"{j}.{a}" for j in JOINTS for a in AXES)


def _class_slices() -> dict[str, slice]:
    slices, start = {}, 0
    for name, joints in JOINT_CLASSES.items():
        slices[name] = slice(start, start + 3 * len(joints))
        start += 3 * len(joints)
    return slices


#: Posture index range of each class: body 0:15, global 15:30, medium 30:45, detail 45:63.
CLASS_SLICES: dict[str, slice] = _class_slices()


def joint_dof_index(joint: str, axis: str) -> int:
    """Index in the 63-vector of ``joint``'s ``axis`` ("rx", "ry" or "rz")."""
    return 3 * JOINTS.index(joint) + AXES.index(axis)


ROOT_CHANNELS: tuple[str, ...] = ("tx", "ty", "tz", "rx", "ry", "rz")


@dataclass(frozen=True, eq=False)
class Skeleton:
    """An ASF skeleton: bone geometry, axes, DOFs and limits, and the posture layout.

    Array attributes are indexed by bone in ``bone_names`` order (``"root"`` first,
    parents before children). Lengths are in metres; angles in degrees; the world frame
    is the ASF's (y up).

    Attributes
    ----------
    name : str
        The ASF ``:name``.
    source : str
        The file it was read from (for messages).
    bone_names : tuple of str, length B
    parents : ndarray of int, shape (B,)
        Parent index of each bone, -1 for the root.
    directions : ndarray, shape (B, 3)
        Unit direction of each bone in the world frame at rest (root: zeros).
    lengths_m : ndarray, shape (B,)
        Bone lengths in metres (root: 0).
    axis_deg : ndarray, shape (B, 3)
        Each bone's ``axis`` angles (about X, Y, Z), degrees.
    axis_order : tuple of str, length B
        Each bone's axis rotation order (e.g. ``"XYZ"``; x applied first).
    axis_matrices : ndarray, shape (B, 3, 3)
        The axis frame C of each bone (``local = C M C^T``); identity for the root.
    dofs : tuple of tuple of str, length B
        Declared DOFs of each bone in ASF order (values in an AMC line follow it).
    dof_limits_deg : tuple of ndarray, length B
        ``(n_dof, 2)`` limits of each bone's declared DOFs, in ``dofs`` order.
    root_order : tuple of str
        The AMC order of the root channels, e.g. ``("tx", "ty", "tz", "rx", "ry", "rz")``.
    root_axis_order : str
        The root's rotation order (``axis XYZ``: x applied first).
    length_to_m : float
        Metres per ASF length unit (0.0254 / ``:units length``; 0.056444 for CMU).
    angle_unit : str
        ``"deg"`` or ``"rad"`` as declared by ``:units angle``.
    bone_lines : tuple of int
        Line of each bone's ``begin`` in ``source`` (for messages); empty when the
        skeleton was not read from an ASF.
    limits_deg : ndarray, shape (63, 2)
        Posture DOF limits, [0, 0] where a DOF is not declared.
    declared : ndarray of bool, shape (63,)
        Which posture DOFs the ASF declares.
    """

    name: str
    source: str
    bone_names: tuple[str, ...]
    parents: np.ndarray
    directions: np.ndarray
    lengths_m: np.ndarray
    axis_deg: np.ndarray
    axis_order: tuple[str, ...]
    axis_matrices: np.ndarray
    dofs: tuple[tuple[str, ...], ...]
    dof_limits_deg: tuple[np.ndarray, ...]
    root_order: tuple[str, ...]
    root_axis_order: str
    length_to_m: float
    angle_unit: str = "deg"
    bone_lines: tuple[int, ...] = ()
    limits_deg: np.ndarray = field(init=False)
    declared: np.ndarray = field(init=False)

    def __post_init__(self):
        limits = np.zeros((POSTURE_SIZE, 2))
        declared = np.zeros(POSTURE_SIZE, dtype=bool)
        for joint in JOINTS:
            b = self.bone_index(joint)
            for k, dof in enumerate(self.dofs[b]):
                i = joint_dof_index(joint, dof)
                limits[i] = self.dof_limits_deg[b][k]
                declared[i] = True
        limits.setflags(write=False)
        declared.setflags(write=False)
        object.__setattr__(self, "limits_deg", limits)
        object.__setattr__(self, "declared", declared)

    @property
    def n_bones(self) -> int:
        return len(self.bone_names)

    def bone_index(self, name: str) -> int:
        """Index of bone ``name`` in ``bone_names`` (KeyError naming the bone if absent)."""
        try:
            return self._index[name]
        except KeyError:
            raise KeyError(f"skeleton {self.source!r} has no bone {name!r}") from None

    @property
    def _index(self) -> dict[str, int]:
        cached = self.__dict__.get("_index_cache")
        if cached is None:
            cached = {n: i for i, n in enumerate(self.bone_names)}
            object.__setattr__(self, "_index_cache", cached)
        return cached

    @property
    def offsets_m(self) -> np.ndarray:
        """Rest vector from each bone's proximal to its distal end, world frame, metres.

        Shape (B, 3); zero for the root.
        """
        return self.directions * self.lengths_m[:, None]

    @property
    def extra_channels(self) -> tuple[tuple[str, str], ...]:
        """The declared DOFs of bones outside the 21 joints, as ``(bone, dof)`` pairs in
        ASF bone order: read from and written to AMC files, never articulated."""
        cached = self.__dict__.get("_extra_cache")
        if cached is None:  # asked for on every transition: built once
            joints = set(JOINTS)
            cached = tuple(
                (bone, dof)
                for bone, dofs in zip(self.bone_names[1:], self.dofs[1:], strict=True)
                if bone not in joints
                for dof in dofs
            )
            object.__setattr__(self, "_extra_cache", cached)
        return cached

    @property
    def extra_limits_deg(self) -> np.ndarray:
        """Limits of :attr:`extra_channels`, shape (E, 2)."""
        rows = [
            self.dof_limits_deg[b][k]
            for b, bone in enumerate(self.bone_names)
            if b > 0 and bone not in set(JOINTS)
            for k in range(len(self.dofs[b]))
        ]
        return np.array(rows, dtype=float).reshape(-1, 2)
