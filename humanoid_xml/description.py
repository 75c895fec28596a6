"""Skeletons the project owns, described in JSON (``upm-skeleton/1``), turned into a
:class:`upm.motion.skeleton.Skeleton` like one read from an ASF.

The format::

    {"format": "upm-skeleton/1", "name": ..., "stature_m": H,
     "root": {"order": ["tx", "ty", "tz", "rx", "ry", "rz"], "axis_order": "XYZ"},
     "bones": [{"name", "parent", "direction": [x, y, z], "length_H",
                "axis_deg": [ax, ay, az], "axis_order", "dofs": [...],
                "limits_deg": [[lo, hi], ...]}, ...]}

Bones are listed parents first, in the ASF world frame (y up, x the subject's left, z
forward); a bone's length is ``length_H * stature_m`` metres. Other keys (sources,
``length_basis``, ``range_basis``) document where each number comes from and are not
read.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from upm.core.errors import DataFileError
from upm.motion.skeleton import JOINTS, ROOT_CHANNELS, Skeleton
from upm.ops.rotations import euler_to_matrix

FORMAT = "upm-skeleton/1"
GENERIC_ADULT_JSON = Path(__file__).resolve().parent / "generic_adult.json"


def _require(path, mapping: dict, key: str, where: str):
    if key not in mapping:
        raise DataFileError(path, f"{where} has no {key!r}")
    return mapping[key]


def _numbers(path, values, count: int, what: str) -> list[float]:
    if not isinstance(values, list) or len(values) != count:
        raise DataFileError(path, f"{what} must be a list of {count} numbers")
    try:
        out = [float(v) for v in values]
    except (TypeError, ValueError):
        raise DataFileError(path, f"{what} must be a list of {count} numbers") from None
    if not all(math.isfinite(v) for v in out):
        raise DataFileError(path, f"{what} has a NaN or infinite value")
    return out


def read_skeleton_description(path: str | os.PathLike) -> Skeleton:
    """Read a JSON skeleton description.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    Skeleton
        ``source`` is the file's name (not its full path).

    Raises
    ------
    DataFileError
        For malformed JSON or content, naming the file and what is wrong.
    """
    try:
        with open(path, encoding="utf-8") as handle:
            doc = json.load(handle)
    except json.JSONDecodeError as exc:
        raise DataFileError(path, f"not valid JSON: {exc.msg}", exc.lineno) from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise DataFileError(path, f"not a skeleton description (format must be {FORMAT!r})")
    stature = float(_require(path, doc, "stature_m", "the description"))
    if not stature > 0:
        raise DataFileError(path, "stature_m must be positive")
    root = _require(path, doc, "root", "the description")
    order = tuple(str(c).lower() for c in _require(path, root, "order", "root"))
    if sorted(order) != sorted(ROOT_CHANNELS):
        raise DataFileError(path, "root order must list tx ty tz rx ry rz once each")
    root_axis = str(root.get("axis_order", "XYZ")).upper()
    if sorted(root_axis) != ["X", "Y", "Z"]:
        raise DataFileError(path, f"root axis_order {root_axis!r} is not a permutation of XYZ")

    names, parents = ["root"], [-1]
    directions, lengths, axis_deg = [np.zeros(3)], [0.0], [np.zeros(3)]
    axis_orders, dofs, limits = ["XYZ"], [()], [np.zeros((0, 2))]
    for k, bone in enumerate(_require(path, doc, "bones", "the description")):
        name = str(_require(path, bone, "name", f"bone {k + 1}"))
        where = f"bone {name!r}"
        if name in names:
            raise DataFileError(path, f"{where} is listed twice")
        parent = str(_require(path, bone, "parent", where))
        if parent not in names:
            raise DataFileError(path, f"{where}: parent {parent!r} is not listed before it")
        direction = np.array(_numbers(path, _require(path, bone, "direction", where), 3,
                                      f"{where} direction"))
        norm = float(np.linalg.norm(direction))
        length = float(_require(path, bone, "length_H", where)) * stature
        if norm < 1e-9 or not length > 0:
            raise DataFileError(path, f"{where} needs a non-zero direction and a positive "
                                      "length_H")
        axis = _numbers(path, _require(path, bone, "axis_deg", where), 3, f"{where} axis_deg")
        axis_order = str(bone.get("axis_order", "XYZ")).upper()
        if sorted(axis_order) != ["X", "Y", "Z"]:
            raise DataFileError(path, f"{where} axis_order {axis_order!r} is not a "
                                      "permutation of XYZ")
        bone_dofs = tuple(str(d).lower() for d in bone.get("dofs", []))
        if any(d not in ("rx", "ry", "rz") for d in bone_dofs) or \
                len(set(bone_dofs)) != len(bone_dofs):
            raise DataFileError(path, f"{where} dofs must be distinct rx, ry, rz")
        bone_limits = [_numbers(path, pair, 2, f"{where} limits_deg")
                       for pair in bone.get("limits_deg", [])]
        if len(bone_limits) != len(bone_dofs):
            raise DataFileError(path, f"{where} declares {len(bone_dofs)} dofs but "
                                      f"{len(bone_limits)} limits")
        if any(lo > hi for lo, hi in bone_limits):
            raise DataFileError(path, f"{where} has a limit whose lower end is above its upper")
        names.append(name)
        parents.append(names.index(parent))
        directions.append(direction / norm)
        lengths.append(length)
        axis_deg.append(np.array(axis))
        axis_orders.append(axis_order)
        dofs.append(bone_dofs)
        limits.append(np.array(bone_limits, dtype=float).reshape(-1, 2))
    missing = [j for j in JOINTS if j not in names]
    if missing:
        raise DataFileError(path, f"no bone {missing[0]!r}: the 21-joint model needs the CMU "
                                  "bone set")
    axis_matrices = np.stack([euler_to_matrix(a, o) for a, o in zip(axis_deg, axis_orders,
                                                                      strict=True)])
    axis_matrices[0] = np.eye(3)
    return Skeleton(
        name=str(doc.get("name", Path(path).stem)),
        source=Path(path).name,
        bone_names=tuple(names),
        parents=np.array(parents, dtype=int),
        directions=np.array(directions),
        lengths_m=np.array(lengths),
        axis_deg=np.array(axis_deg),
        axis_order=tuple(axis_orders),
        axis_matrices=axis_matrices,
        dofs=tuple(dofs),
        dof_limits_deg=tuple(limits),
        root_order=order,
        root_axis_order=root_axis,
        length_to_m=1.0,
        angle_unit="deg",
    )


def generic_skeleton() -> Skeleton:
    """The generic adult of ``generic_adult.json`` (stature 1.75 m), as a Skeleton."""
    return read_skeleton_description(GENERIC_ADULT_JSON)
