"""What a skeleton must satisfy before a humanoid is built from it.

The ASF reader accepts any well-formed skeleton with the 21 joints; the humanoid needs
more: the bones its segments are made of, a strength figure for every hinge, and bones
long enough to carry a capsule. Each failure is one :class:`upm.core.errors.DataFileError`
naming the skeleton's own file (and the bone's line when it was read from an ASF).
"""

from __future__ import annotations

from upm.core.errors import DataFileError
from upm.motion.skeleton import JOINTS, Skeleton

#: Shortest bone the humanoid accepts (MuJoCo refuses degenerate capsules), m. CMU's
#: shortest bone is about 2 cm.
MIN_BONE_LENGTH_M = 1e-3
#: Longest bone the humanoid accepts, m (volumes and masses stay finite and sane).
MAX_BONE_LENGTH_M = 5.0


def _line(skeleton: Skeleton, bone: int) -> int | None:
    return skeleton.bone_lines[bone] if bone < len(skeleton.bone_lines) else None


def check_skeleton(skeleton: Skeleton) -> None:
    """Refuse a skeleton the humanoid cannot be built from.

    Raises
    ------
    DataFileError
        Naming ``skeleton.source``: a bone a body segment needs is missing, a joint
        declares a DOF without a strength figure, or a bone is shorter than
        :data:`MIN_BONE_LENGTH_M` or longer than :data:`MAX_BONE_LENGTH_M`.
    """
    from humanoid_xml.strength import STRENGTH, side_less

    names = set(skeleton.bone_names)
    needed = {"lhipjoint", "rhipjoint", *JOINTS}
    missing = sorted(needed - names)
    if missing:
        raise DataFileError(skeleton.source, f"no bone {missing[0]!r}: the humanoid needs the "
                                             "CMU bone set")
    for joint in JOINTS:
        b = skeleton.bone_index(joint)
        for dof in skeleton.dofs[b]:
            if side_less(f"{joint}_{dof}") not in STRENGTH:
                raise DataFileError(
                    skeleton.source, f"bone {joint!r} declares dof {dof}, which the humanoid "
                                     "has no joint strength for (it can drive "
                                     f"{_known_dofs(joint, STRENGTH, side_less)})",
                    _line(skeleton, b))
    for b, name in enumerate(skeleton.bone_names[1:], start=1):
        length = float(skeleton.lengths_m[b])
        if not MIN_BONE_LENGTH_M <= length <= MAX_BONE_LENGTH_M:
            raise DataFileError(
                skeleton.source, f"bone {name!r} is {length:.3g} m long: the humanoid needs "
                                 f"{MIN_BONE_LENGTH_M:g} to {MAX_BONE_LENGTH_M:g} m",
                _line(skeleton, b))


def _known_dofs(joint: str, strength, side_less) -> str:
    dofs = [d for d in ("rx", "ry", "rz") if side_less(f"{joint}_{d}") in strength]
    return " ".join(dofs) or "none"
