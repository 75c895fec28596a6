"""Reader of Acclaim ASF skeleton files."""

from __future__ import annotations

import math
import os
import re

import numpy as np

from upm.core.errors import DataFileError
from upm.core.textfile import read_text_lines
from upm.motion.skeleton import JOINTS, Skeleton
from upm.ops.rotations import euler_to_matrix

_INCH_M = 0.0254
_ROTATION_DOFS = ("rx", "ry", "rz")
_ROOT_CHANNELS = ("tx", "ty", "tz", "rx", "ry", "rz")
#: Bounds on what an ASF may declare. Far beyond any real skeleton (CMU: 31 bones, 9
#: deep, bones under 0.5 m), tight enough that geometry and the humanoid stay finite.
MAX_BONES = 200
MAX_DEPTH = 64
MAX_ABS_NUMBER = 1e6
MAX_BONE_LENGTH_M = 100.0
LENGTH_UNIT_RANGE = (1e-6, 1e6)


def _floats(path, lineno: int, tokens: list[str], count: int, what: str) -> list[float]:
    if len(tokens) != count:
        raise DataFileError(path, f"{what} needs {count} numbers, found {len(tokens)}", lineno)
    try:
        values = [float(t) for t in tokens]
    except ValueError:
        raise DataFileError(path, f"{what} has a non-numeric value: {' '.join(tokens)}",
                            lineno) from None
    if not all(math.isfinite(v) for v in values):
        raise DataFileError(path, f"{what} has a NaN or infinite value", lineno)
    if any(abs(v) > MAX_ABS_NUMBER for v in values):
        raise DataFileError(path, f"{what} has a value beyond {MAX_ABS_NUMBER:g}: "
                                  f"{' '.join(tokens)}", lineno)
    return values


class _Bone:
    __slots__ = ("name", "line", "direction", "length", "axis", "axis_order", "dofs", "limits")

    def __init__(self, line: int):
        self.line = line
        self.name = None
        self.direction = None
        self.length = None
        self.axis = None
        self.axis_order = "XYZ"
        self.dofs: tuple[str, ...] = ()
        self.limits: list[tuple[float, float]] = []


def _sections(path, lines: list[str]) -> dict[str, list[tuple[int, str]]]:
    """Split the file into ``:keyword`` sections of (line number, stripped text)."""
    sections: dict[str, list[tuple[int, str]]] = {}
    current = None
    for lineno, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith(":"):
            keyword, _, rest = line[1:].partition(" ")
            current = keyword.lower()
            if current in sections and current not in ("documentation",):
                raise DataFileError(path, f"section :{keyword} appears twice", lineno)
            sections[current] = []
            if rest.strip():
                sections[current].append((lineno, rest.strip()))
            continue
        if current is None:
            raise DataFileError(path, f"text before the first ':' section: {line[:40]!r}", lineno)
        sections[current].append((lineno, line))
    return sections


def _parse_units(path, entries) -> tuple[float, str]:
    length_unit, angle_unit = 1.0, "deg"
    for lineno, line in entries:
        tokens = line.split()
        key = tokens[0].lower()
        if key == "length":
            (length_unit,) = _floats(path, lineno, tokens[1:], 1, "units length")
            low, high = LENGTH_UNIT_RANGE
            if not low <= length_unit <= high:
                raise DataFileError(path, f"units length {length_unit:g} is outside "
                                          f"[{low:g}, {high:g}]", lineno)
        elif key == "angle":
            if len(tokens) != 2 or tokens[1].lower() not in ("deg", "rad"):
                raise DataFileError(path, "units angle must be 'deg' or 'rad'", lineno)
            angle_unit = tokens[1].lower()
    return length_unit, angle_unit


def _parse_root(path, entries, root_line: int) -> tuple[tuple[str, ...], str]:
    order, axis = None, "XYZ"
    for lineno, line in entries:
        tokens = line.split()
        key = tokens[0].lower()
        if key == "order":
            order = tuple(t.lower() for t in tokens[1:])
            if sorted(order) != sorted(_ROOT_CHANNELS):
                raise DataFileError(
                    path, f"root order must list TX TY TZ RX RY RZ once each: {line}", lineno
                )
        elif key == "axis":
            if len(tokens) != 2 or sorted(tokens[1].upper()) != ["X", "Y", "Z"]:
                raise DataFileError(path, f"root axis must be an order such as XYZ: {line}", lineno)
            axis = tokens[1].upper()
    if order is None:
        raise DataFileError(path, "the :root section has no 'order' line", root_line)
    return order, axis


def _parse_bones(path, entries, angle_unit: str) -> list[_Bone]:
    bones: list[_Bone] = []
    bone = None
    in_limits = False
    for lineno, line in entries:
        tokens = line.split()
        key = tokens[0].lower()
        if key == "begin":
            if len(bones) >= MAX_BONES:
                raise DataFileError(path, f"more than {MAX_BONES} bones", lineno)
            if bone is not None:
                raise DataFileError(path, "'begin' inside a bone (missing 'end')", lineno)
            bone, in_limits = _Bone(lineno), False
            continue
        if bone is None:
            raise DataFileError(path, f"bone data outside begin/end: {line[:40]!r}", lineno)
        if key == "end":
            _finish_bone(path, bone, lineno)
            bones.append(bone)
            bone = None
            continue
        if line.startswith("(") or (key == "limits"):
            if key == "limits":
                in_limits = True
                line = line[len("limits"):]
            elif not in_limits:
                raise DataFileError(path, "a limits line outside a 'limits' entry", lineno)
            for pair in re.findall(r"\(([^)]*)\)", line):
                lo, hi = _floats(path, lineno, pair.split(), 2, "a limits pair")
                if angle_unit == "rad":
                    lo, hi = math.degrees(lo), math.degrees(hi)
                if lo > hi:
                    raise DataFileError(path, f"limits ({lo} {hi}): lower above upper", lineno)
                bone.limits.append((lo, hi))
            continue
        in_limits = False
        if key == "id":
            continue
        if key == "name":
            if len(tokens) != 2:
                raise DataFileError(path, "a bone name must be one word", lineno)
            bone.name = tokens[1]
        elif key == "direction":
            bone.direction = _floats(path, lineno, tokens[1:], 3, "direction")
        elif key == "length":
            (bone.length,) = _floats(path, lineno, tokens[1:], 1, "length")
            if bone.length < 0:
                raise DataFileError(path, "a bone length cannot be negative", lineno)
        elif key == "axis":
            if len(tokens) != 5:
                raise DataFileError(path, "axis needs 3 angles and an order (e.g. XYZ)", lineno)
            bone.axis = _floats(path, lineno, tokens[1:4], 3, "axis")
            if angle_unit == "rad":
                bone.axis = [math.degrees(a) for a in bone.axis]
            order = tokens[4].upper()
            if sorted(order) != ["X", "Y", "Z"]:
                raise DataFileError(path, f"axis order {tokens[4]!r} is not a permutation of XYZ",
                                    lineno)
            bone.axis_order = order
        elif key == "dof":
            dofs = tuple(t.lower() for t in tokens[1:])
            bad = [d for d in dofs if d not in _ROTATION_DOFS]
            if bad:
                raise DataFileError(path, f"unsupported dof {bad[0]!r} (only rx ry rz)", lineno)
            if len(set(dofs)) != len(dofs):
                raise DataFileError(path, "a dof is listed twice", lineno)
            bone.dofs = dofs
        elif key in ("bodymass", "cofmass"):
            continue
        else:
            raise DataFileError(path, f"unknown bone field {tokens[0]!r}", lineno)
    if bone is not None:
        raise DataFileError(path, f"bone {bone.name or '?'} has no 'end'", bone.line)
    return bones


def _finish_bone(path, bone: _Bone, lineno: int) -> None:
    where = f"bone {bone.name!r}" if bone.name else "a bone"
    for attribute in ("name", "direction", "length"):
        if getattr(bone, attribute) is None:
            raise DataFileError(path, f"{where} has no {attribute}", bone.line)
    if bone.axis is None:
        raise DataFileError(path, f"{where} has no axis", bone.line)
    if len(bone.limits) != len(bone.dofs):
        raise DataFileError(
            path, f"{where} declares {len(bone.dofs)} dofs but {len(bone.limits)} limits", lineno
        )
    norm = math.sqrt(sum(v * v for v in bone.direction))
    if norm < 1e-9 and bone.length > 0:
        raise DataFileError(path, f"{where} has a zero direction", bone.line)


def _parse_hierarchy(path, entries, names: set[str]) -> dict[str, list[str]]:
    children: dict[str, list[str]] = {}
    parent_of: dict[str, str] = {}
    for lineno, line in entries:
        tokens = line.split()
        if tokens[0].lower() in ("begin", "end"):
            continue
        parent, kids = tokens[0], tokens[1:]
        for name in [parent, *kids]:
            if name != "root" and name not in names:
                raise DataFileError(path, f"hierarchy names unknown bone {name!r}", lineno)
        for kid in kids:
            if kid in parent_of or kid == "root":
                raise DataFileError(path, f"bone {kid!r} has two parents", lineno)
            parent_of[kid] = parent
        children.setdefault(parent, []).extend(kids)
    return children


def read_asf(path: str | os.PathLike) -> Skeleton:
    """Read an Acclaim ASF skeleton.

    Lengths are converted to metres (``0.0254 / :units length`` per ASF unit: 0.056444
    for CMU); angles are kept in degrees (converted if the file declares ``angle rad``).

    Parameters
    ----------
    path : path-like

    Returns
    -------
    Skeleton

    Raises
    ------
    DataFileError
        Naming the file (and line) for any malformed or incomplete content.
    """
    lines = read_text_lines(path, "ASF")
    sections = _sections(path, lines)
    for required in ("root", "bonedata", "hierarchy"):
        if required not in sections:
            raise DataFileError(path, f"missing section :{required} (is this an ASF file?)")
    length_unit, angle_unit = _parse_units(path, sections.get("units", []))
    root_line = sections["root"][0][0] if sections["root"] else None
    root_order, root_axis = _parse_root(path, sections["root"], root_line)
    bones = _parse_bones(path, sections["bonedata"], angle_unit)
    by_name = {}
    for bone in bones:
        if bone.name in by_name or bone.name == "root":
            raise DataFileError(path, f"bone {bone.name!r} is defined twice", bone.line)
        by_name[bone.name] = bone
    children = _parse_hierarchy(path, sections["hierarchy"], set(by_name))

    order, parents, depths = ["root"], [-1], [0]
    stack = [(kid, 0) for kid in reversed(children.get("root", []))]
    while stack:
        name, parent_index = stack.pop()
        order.append(name)
        parents.append(parent_index)
        index = len(order) - 1
        depths.append(depths[parent_index] + 1)
        if depths[index] > MAX_DEPTH:
            raise DataFileError(path, f"bone {name!r} is more than {MAX_DEPTH} bones deep "
                                      "in :hierarchy", by_name[name].line)
        stack.extend((kid, index) for kid in reversed(children.get(name, [])))
    unreached = [b.name for b in bones if b.name not in set(order)]
    if unreached:
        raise DataFileError(path, f"bone {unreached[0]!r} is not reachable from the root "
                                  "in :hierarchy", by_name[unreached[0]].line)
    missing = [j for j in JOINTS if j not in by_name]
    if missing:
        raise DataFileError(path, f"no bone {missing[0]!r}: the 21-joint model needs the CMU "
                                  "bone set")

    length_to_m = _INCH_M / length_unit
    n = len(order)
    directions = np.zeros((n, 3))
    lengths = np.zeros(n)
    axis_deg = np.zeros((n, 3))
    axis_order = ["XYZ"] * n
    dofs: list[tuple[str, ...]] = [()] * n
    limits: list[np.ndarray] = [np.zeros((0, 2))] * n
    for i, name in enumerate(order[1:], start=1):
        bone = by_name[name]
        d = np.array(bone.direction, dtype=float)
        norm = np.linalg.norm(d)
        directions[i] = d / norm if norm > 0 else d
        lengths[i] = bone.length * length_to_m
        if lengths[i] > MAX_BONE_LENGTH_M:
            raise DataFileError(path, f"bone {name!r} is {lengths[i]:.3g} m long (more than "
                                      f"{MAX_BONE_LENGTH_M:g} m)", bone.line)
        axis_deg[i] = bone.axis
        axis_order[i] = bone.axis_order
        dofs[i] = bone.dofs
        limits[i] = np.array(bone.limits, dtype=float).reshape(-1, 2)
    axis_matrices = np.stack([euler_to_matrix(a, o) for a, o in zip(axis_deg, axis_order,
                                                                      strict=True)])
    axis_matrices[0] = np.eye(3)
    name_entries = sections.get("name", [])
    return Skeleton(
        name=name_entries[0][1] if name_entries else os.path.basename(os.fspath(path)),
        source=os.fspath(path),
        bone_names=tuple(order),
        parents=np.array(parents, dtype=int),
        directions=directions,
        lengths_m=lengths,
        axis_deg=axis_deg,
        axis_order=tuple(axis_order),
        axis_matrices=axis_matrices,
        dofs=tuple(dofs),
        dof_limits_deg=tuple(limits),
        root_order=root_order,
        root_axis_order=root_axis,
        length_to_m=length_to_m,
        angle_unit=angle_unit,
        bone_lines=(root_line or 0, *(by_name[name].line for name in order[1:])),
    )
