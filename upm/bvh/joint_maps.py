"""Joint maps: which BVH joints stand for which ASF posture bones.

A joint map says, for the ASF ``root`` and each of the 21 posture joints, where its
counterpart is in a BVH hierarchy:

- ``"root": "Hips"``: the BVH joint whose world rotation the ASF root takes, and whose
  position (scaled) carries the root translation.
- ``"lfemur": ["LeftUpLeg", "LeftLeg"]``: the bone points from the first joint to the
  second (any joint, not only a child; ``"End Site"`` as the second names the first
  joint's end site), and twists as the first joint turns.
- ``"head": ["Head"]``: one joint: the bone turns exactly as that joint turns from its
  rest pose (for segments without a joint or end site beyond them to point at).
- ``"ltoes": null`` or absent: no counterpart; the bone keeps its rest angles.

The built-in maps cover the DAZ-style 43-joint figure (``hip``, ``abdomen``, ``lThigh``
...), Mixamo's ``mixamorig:`` rig and the 19-joint ``Hips``/``Chest``/``LeftHip``
figure. A user map is the same structure as a JSON file (:func:`read_joint_map`):
``{"root": ..., "bones": {ASF joint: [...] | null}}``; :data:`REQUIRED` must be mapped.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass

from upm.core.errors import DataFileError
from upm.motion.skeleton import JOINTS

#: The second element of a bone entry that names the first joint's end site.
END_SITE = "End Site"
#: Posture joints a map must carry: the limbs and the chest (a figure without them is
#: not a body this retarget can place).
REQUIRED = ("thorax", "lfemur", "ltibia", "rfemur", "rtibia", "lhumerus", "lradius",
            "rhumerus", "rradius")
MAX_MAP_BYTES = 1024 ** 2


@dataclass(frozen=True)
class JointMap:
    """A validated joint map.

    Attributes
    ----------
    name : str
        What it is for messages (a built-in's name or the JSON file).
    root : str
        The BVH joint of the ASF root.
    bones : dict of str to tuple of str
        Posture joint -> ``(start, end)`` (a direction) or ``(joint,)`` (a rotation);
        joints without a counterpart are absent.
    """

    name: str
    root: str
    bones: dict[str, tuple[str, ...]]

    def bvh_joints(self) -> list[str]:
        """Every BVH joint the map refers to (root first; no duplicates)."""
        names = [self.root]
        for entry in self.bones.values():
            names += [n for n in entry if n != END_SITE and n not in names]
        return names

    def missing_in(self, bvh_skeleton) -> list[str]:
        """The joints the map refers to that ``bvh_skeleton`` lacks (end sites included
        as ``"joint End Site"``)."""
        index = {n: j for j, n in enumerate(bvh_skeleton.names)}
        missing = [n for n in self.bvh_joints() if n not in index]
        for entry in self.bones.values():
            if len(entry) == 2 and entry[1] == END_SITE and entry[0] in index:
                ends = bvh_skeleton.end_sites[index[entry[0]]]
                if not (ends == ends).all():
                    missing.append(f"{entry[0]} {END_SITE}")
        return missing


def _sided(template: dict[str, object], left: str, right: str) -> dict[str, object]:
    """``l``/``r`` ASF joints from one template whose BVH names hold ``{s}``."""
    out = {}
    for bone, entry in template.items():
        for side, word in (("l", left), ("r", right)):
            out[side + bone] = None if entry is None else [
                e.format(s=word) for e in entry]
    return out


_DAZ = {"root": "hip", "bones": {
    "lowerback": ["abdomen", "chest"], "upperback": ["abdomen", "chest"],
    "thorax": ["chest", "neck"], "lowerneck": ["neck", "head"], "head": ["head"],
    **_sided({"clavicle": ["{s}Collar", "{s}Shldr"], "humerus": ["{s}Shldr", "{s}ForeArm"],
              "radius": ["{s}ForeArm", "{s}Hand"], "hand": ["{s}Hand", "{s}Mid1"],
              "femur": ["{s}Thigh", "{s}Shin"], "tibia": ["{s}Shin", "{s}Foot"],
              "foot": ["{s}Foot", END_SITE], "toes": None}, "l", "r"),
}}

_MIXAMO = {"root": "mixamorig:Hips", "bones": {
    "lowerback": ["mixamorig:Spine", "mixamorig:Spine1"],
    "upperback": ["mixamorig:Spine1", "mixamorig:Spine2"],
    "thorax": ["mixamorig:Spine2", "mixamorig:Neck"],
    "lowerneck": ["mixamorig:Neck", "mixamorig:Head"],
    "head": ["mixamorig:Head", "mixamorig:HeadTop_End"],
    **_sided({"clavicle": ["mixamorig:{s}Shoulder", "mixamorig:{s}Arm"],
              "humerus": ["mixamorig:{s}Arm", "mixamorig:{s}ForeArm"],
              "radius": ["mixamorig:{s}ForeArm", "mixamorig:{s}Hand"],
              "hand": ["mixamorig:{s}Hand", "mixamorig:{s}HandMiddle1"],
              "femur": ["mixamorig:{s}UpLeg", "mixamorig:{s}Leg"],
              "tibia": ["mixamorig:{s}Leg", "mixamorig:{s}Foot"],
              "foot": ["mixamorig:{s}Foot", "mixamorig:{s}ToeBase"],
              "toes": ["mixamorig:{s}ToeBase", END_SITE]}, "Left", "Right"),
}}

_BODY_19 = {"root": "Hips", "bones": {
    "lowerback": ["Chest", "Chest2"], "upperback": ["Chest", "Chest2"],
    "thorax": ["Chest2", "Neck"], "lowerneck": ["Neck", "Head"],
    "head": ["Head", END_SITE],
    **_sided({"clavicle": ["{s}Collar", "{s}Shoulder"],
              "humerus": ["{s}Shoulder", "{s}Elbow"], "radius": ["{s}Elbow", "{s}Wrist"],
              "hand": ["{s}Wrist", END_SITE], "femur": ["{s}Hip", "{s}Knee"],
              "tibia": ["{s}Knee", "{s}Ankle"], "foot": ["{s}Ankle", END_SITE],
              "toes": None}, "Left", "Right"),
}}


def _builtin(name: str, raw: dict) -> JointMap:
    return parse_joint_map(raw, name)


def builtin_maps() -> dict[str, JointMap]:
    """The built-in maps by name: ``daz43``, ``mixamo``, ``body19``."""
    return {"daz43": _builtin("daz43", _DAZ), "mixamo": _builtin("mixamo", _MIXAMO),
            "body19": _builtin("body19", _BODY_19)}


def find_builtin_map(bvh) -> JointMap:
    """The built-in map whose joints the BVH has.

    Raises
    ------
    DataFileError
        Naming the file and the joints it lacks of the closest built-in map (the one
        whose root it has, else the one it shares most joints with).
    """
    names = set(bvh.skeleton.names)
    best, best_missing = None, None
    for joint_map in builtin_maps().values():
        missing = joint_map.missing_in(bvh.skeleton)
        if not missing:
            return joint_map
        key = (joint_map.root not in names, len(missing))
        if best is None or key < best[0]:
            best, best_missing = (key, joint_map), missing
    _, joint_map = best
    shown = ", ".join(repr(n) for n in best_missing[:6])
    more = f" and {len(best_missing) - 6} more" if len(best_missing) > 6 else ""
    raise DataFileError(bvh.source, f"no built-in joint map fits (closest: {joint_map.name}, "
                                    f"which needs {shown}{more}); give one with --map "
                                    "JOINTS.json")


def parse_joint_map(raw, source: str, text: str = "") -> JointMap:
    """Validate a joint map's structure (not yet against a BVH).

    Parameters
    ----------
    raw : object
        The decoded JSON.
    source : str
        Its file (or a built-in's name), for messages.
    text : str, optional
        The JSON text, to name the line of a bad entry.

    Raises
    ------
    DataFileError
        Not an object with ``root`` and ``bones``, an unknown ASF joint, a required
        joint missing, or an entry that is not ``[start, end]``, ``[joint]`` or null.
    """
    def fail(message, token=None):
        raise DataFileError(source, message, _line_of(text, token))

    if not isinstance(raw, dict):
        fail("a joint map is a JSON object {\"root\": ..., \"bones\": {...}}")
    unknown = sorted(set(raw) - {"root", "bones", "comment"})
    if unknown:
        fail(f"unknown key {unknown[0]!r} (keys: root, bones, comment)", unknown[0])
    root, bones = raw.get("root"), raw.get("bones")
    if not isinstance(root, str) or not root:
        fail("\"root\" must name the BVH joint of the ASF root", "root")
    if not isinstance(bones, dict):
        fail("\"bones\" must be an object {ASF joint: [start, end] | [joint] | null}",
             "bones")
    out = {}
    for bone, entry in bones.items():
        if bone not in JOINTS:
            fail(f"unknown ASF joint {bone!r} (the 21 posture joints: "
                 f"{', '.join(JOINTS)})", bone)
        if entry is None:
            continue
        if (not isinstance(entry, list) or len(entry) not in (1, 2)
                or not all(isinstance(e, str) and e for e in entry)):
            fail(f"{bone!r}: give [start joint, end joint], [joint] or null", bone)
        if entry[0] == END_SITE:
            fail(f"{bone!r}: {END_SITE!r} can only be the second name", bone)
        out[bone] = tuple(entry)
    missing = [b for b in REQUIRED if b not in out]
    if missing:
        fail(f"required joint {missing[0]!r} is not mapped (required: "
             f"{', '.join(REQUIRED)})")
    return JointMap(str(source), root, out)


def read_joint_map(path: str | os.PathLike) -> JointMap:
    """A user joint map from a JSON file (see the module docstring for the format).

    Raises
    ------
    DataFileError
        Missing or unreadable file, bad JSON (with its line), or a bad map.
    """
    try:
        size = os.path.getsize(path)
        if size > MAX_MAP_BYTES:
            raise DataFileError(path, f"joint map of {size} bytes is over the limit of "
                                      f"{MAX_MAP_BYTES} bytes")
        with open(path, "rb") as handle:
            data = handle.read()
    except OSError as exc:
        raise DataFileError(path, f"cannot read the joint map: {exc.strerror}") from None
    try:
        text = data.decode("utf-8-sig")
        raw = json.loads(text)
    except UnicodeDecodeError:
        raise DataFileError(path, "a joint map is UTF-8 JSON text") from None
    except json.JSONDecodeError as exc:
        raise DataFileError(path, f"not valid JSON: {exc.msg}", exc.lineno) from None
    except RecursionError:
        raise DataFileError(path, "not valid JSON: nested too deeply") from None
    return parse_joint_map(raw, os.fspath(path), text)


def check_map_against(joint_map: JointMap, bvh) -> None:
    """Refuse a map that names joints the BVH lacks (one line naming both files)."""
    missing = joint_map.missing_in(bvh.skeleton)
    if missing:
        shown = ", ".join(repr(n) for n in missing[:6])
        more = f" and {len(missing) - 6} more" if len(missing) > 6 else ""
        raise DataFileError(bvh.source, f"joint map {joint_map.name} names joints this "
                                        f"file does not have: {shown}{more}")


def _line_of(text: str, token: str | None) -> int | None:
    """The 1-based line where ``"token"`` first appears in ``text`` (None if unknown)."""
    if not text or token is None:
        return None
    at = text.find(json.dumps(token))
    return text.count("\n", 0, at) + 1 if at >= 0 else None
