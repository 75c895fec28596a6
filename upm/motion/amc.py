"""Reader and writer of Acclaim AMC motion files.

An AMC frame is a frame-number line followed by one line per bone with DOFs (root
first in CMU files, but any order is accepted): the bone name and its values in the
order the ASF declares (the root in its ``order``). Values are degrees (``:DEGREES``,
the default) or radians (``:RADIANS``); root translations are in ASF length units.
"""

from __future__ import annotations

import array
import math
import os
import re

import numpy as np

from upm.core.errors import DataFileError
from upm.core.fileio import atomic_open
from upm.core.textfile import iter_text_lines
from upm.motion.motion import Motion
from upm.motion.skeleton import JOINTS, ROOT_CHANNELS, Skeleton, joint_dof_index

#: Largest magnitude accepted for an AMC value (degrees, radians or ASF length units):
#: far beyond any real motion, small enough that kinematics and dynamics stay finite.
MAX_ABS_VALUE = 1e6
_FRAME_NUMBER = re.compile(r"[0-9]{1,9}")
#: Largest AMC file read (the longest CMU take is about 25 MB; 2 GB is 4.5 hours at 120 fps).
MAX_AMC_BYTES = 2 * 1024 ** 3


class ChannelLayout:
    """Where each bone's values sit in one AMC frame, and how they map to a Motion.

    Attributes
    ----------
    bones : list of (name, column, count)
        Every bone with values, root first, in ``skeleton.bone_names`` order.
    n_channels : int
        Values per frame (62 for CMU).
    root_columns : ndarray of int, shape (6,)
        Column of tx, ty, tz, rx, ry, rz.
    posture_columns : ndarray of int, shape (63,)
        Column of every posture DOF, -1 where undeclared.
    extra_columns : ndarray of int, shape (E,)
        Columns of ``skeleton.extra_channels``.
    """

    def __init__(self, skeleton: Skeleton):
        self.bones: list[tuple[str, int, int]] = [("root", 0, 6)]
        column = 6
        posture_columns = np.full(63, -1)
        extra_columns = []
        joints = set(JOINTS)
        for b, name in enumerate(skeleton.bone_names[1:], start=1):
            dofs = skeleton.dofs[b]
            if not dofs:
                continue
            self.bones.append((name, column, len(dofs)))
            for k, dof in enumerate(dofs):
                if name in joints:
                    posture_columns[joint_dof_index(name, dof)] = column + k
                else:
                    extra_columns.append(column + k)
            column += len(dofs)
        self.n_channels = column
        self.root_columns = np.array([skeleton.root_order.index(c) for c in ROOT_CHANNELS])
        self.posture_columns = posture_columns
        self.extra_columns = np.array(extra_columns, dtype=int)
        self.by_name = {name: (col, n) for name, col, n in self.bones}


def _to_motion(skeleton, layout, values, fps, radians, name) -> Motion:
    """(T, C) raw AMC values -> Motion."""
    rotation_scale = 180.0 / math.pi if radians else 1.0
    root = values[:, layout.root_columns].copy()
    root[:, :3] *= skeleton.length_to_m
    root[:, 3:] *= rotation_scale
    posture = np.zeros((values.shape[0], 63))
    declared = layout.posture_columns >= 0
    posture[:, declared] = values[:, layout.posture_columns[declared]] * rotation_scale
    extra = values[:, layout.extra_columns] * rotation_scale
    return Motion(skeleton, posture, root, fps=fps, extra_deg=extra, name=name)


def read_amc(path: str | os.PathLike, skeleton: Skeleton, fps: float = 120.0,
             name: str | None = None) -> Motion:
    """Read an AMC file with the skeleton of its subject.

    Parameters
    ----------
    path : path-like
    skeleton : Skeleton
        The subject's ASF (an AMC must be read with its own subject's skeleton).
    fps : float
        Frame rate; an AMC file carries none (CMU: 120, or 60 for some subjects).
    name : str, optional
        Label for the motion (default: the file name without extension).

    Returns
    -------
    Motion

    Notes
    -----
    The file is streamed: memory stays within about twice its size (values are kept
    as 8-byte doubles), and files over 64 MB show a progress bar on a terminal.

    Raises
    ------
    DataFileError
        Naming file and line: unknown bone, a bone missing from a frame or given twice,
        a file over :data:`MAX_AMC_BYTES`, a wrong number of values, a non-numeric,
        NaN or infinite value or one beyond
        :data:`MAX_ABS_VALUE`, a frame number that is not 1 to 9 ASCII digits, frame
        numbers out of order, a truncated last frame, no frames at all. A file cut
        mid-line (its last line the start of a bone name or of the next frame number,
        or a bone with too few values) is said to look truncated.
    """
    layout = ChannelLayout(skeleton)
    n_bones = len(layout.bones)
    by_name = layout.by_name
    asf_name = os.path.basename(skeleton.source)

    radians = False
    # Values go straight into a flat array of doubles (8 bytes a value, under the ~10
    # bytes of its text), so a file is read in about its own size in memory.
    values = array.array("d")
    row = array.array("d", bytes(8 * layout.n_channels))
    frame_lines = array.array("q")
    n_frames = 0
    in_frame = False
    seen: set[str] = set()
    frame_number = None
    frame_line = 0
    n_lines = 0

    def close_frame(at_line: int, at_end: bool = False) -> None:
        if len(seen) != n_bones:
            missing = [b for b, _, _ in layout.bones if b not in seen]
            raise DataFileError(
                path, f"frame {frame_number} (line {frame_line}) lacks bone {missing[0]!r}"
                f"{' and ' + str(len(missing) - 1) + ' more' if len(missing) > 1 else ''}"
                f"{' (truncated file?)' if at_end else ''}", at_line)
        values.extend(row)
        frame_lines.append(frame_line)

    lines = iter_text_lines(path, "AMC", max_bytes=MAX_AMC_BYTES)
    for lineno, raw in lines:
        n_lines = lineno
        parts = raw.split()
        if not parts or parts[0].startswith("#"):
            continue
        head = parts[0]
        if head.startswith(":"):
            if in_frame:
                raise DataFileError(path, f"keyword {head} after the first frame", lineno)
            keyword = head.upper()
            if keyword == ":RADIANS":
                radians = True
            elif keyword == ":DEGREES":
                radians = False
            continue
        if len(parts) == 1 and _FRAME_NUMBER.fullmatch(head):
            number = int(head)
            if in_frame:
                close_frame(lineno)
                n_frames += 1
                if number != frame_number + 1:
                    if str(frame_number + 1).startswith(head) and _at_end(lines):
                        raise _truncated(path, f"in frame number {head} (expected "
                                               f"{frame_number + 1})", lineno)
                    raise DataFileError(path, f"frame {number} follows frame {frame_number} "
                                              f"(expected {frame_number + 1})", lineno)
            frame_number, frame_line = number, lineno
            in_frame = True
            for k in range(len(row)):
                row[k] = 0.0
            seen = set()
            continue
        if not in_frame:
            raise DataFileError(path, f"expected a frame number, found {raw.strip()[:40]!r}",
                                lineno)
        entry = by_name.get(head)
        if entry is None:
            if head in skeleton.bone_names:
                raise DataFileError(path, f"bone {head!r} has values but no dofs in {asf_name} "
                                          "(does this AMC belong to another skeleton?)", lineno)
            if any(b.startswith(head) for b in skeleton.bone_names) and _at_end(lines):
                known = next(b for b in skeleton.bone_names if b.startswith(head))
                raise _truncated(path, f"in {head!r}, the start of a bone name ({known!r}?)",
                                 lineno)
            raise DataFileError(path, f"unknown bone {head[:40]!r} (not in {asf_name}: does "
                                      "this AMC belong to another skeleton?)", lineno)
        if head in seen:
            raise DataFileError(path, f"bone {head!r} appears twice in frame {frame_number}",
                                lineno)
        seen.add(head)
        column, count = entry
        if len(parts) - 1 != count:
            if len(parts) - 1 < count and _at_end(lines):
                raise _truncated(path, f"after {len(parts) - 1} of the {count} values of "
                                       f"bone {head!r}", lineno)
            raise DataFileError(path, f"bone {head!r} needs {count} values, found "
                                      f"{len(parts) - 1}", lineno)
        try:
            numbers = [float(v) for v in parts[1:]]
        except ValueError:
            raise DataFileError(path, f"non-numeric value for bone {head!r}: "
                                      f"{' '.join(parts[1:])[:80]}", lineno) from None
        row[column:column + count] = array.array("d", numbers)
    if not in_frame:
        raise DataFileError(path, "no frames (an AMC needs frame-number lines with bone values)")
    close_frame(n_lines + 1, at_end=True)
    n_frames += 1

    table = np.frombuffer(values, dtype=float).reshape(n_frames, layout.n_channels)
    _check_values(path, layout, table, frame_lines)
    label = name if name is not None else os.path.splitext(os.path.basename(path))[0]
    return _to_motion(skeleton, layout, table, fps, radians, label)


def _at_end(rest_of_file) -> bool:
    """Whether only blank lines are left (``rest_of_file``: the line iterator; read up to
    its next non-blank line, which is harmless as the file is being refused anyway)."""
    return all(not line.strip() for _, line in rest_of_file)


def _truncated(path, what: str, lineno: int) -> DataFileError:
    return DataFileError(path, f"the file looks truncated: its last line ends {what}", lineno)


def _check_values(path, layout: ChannelLayout, table: np.ndarray, frame_lines) -> None:
    """Refuse a NaN, infinite or over-:data:`MAX_ABS_VALUE` value, naming its line."""
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(table) <= MAX_ABS_VALUE)
    if not bad.any():
        return
    frame, column = np.argwhere(bad)[0]
    value = table[frame, column]
    bone = next(b for b, c, n in layout.bones if c <= column < c + n)
    lineno = frame_lines[frame]
    for number, line in iter_text_lines(path, "AMC"):
        parts = line.split()
        if number > frame_lines[frame] and parts and parts[0] == bone:
            lineno = number
            break
    if not np.isfinite(value):
        raise DataFileError(path, f"NaN or infinite value for bone {bone!r}", lineno)
    raise DataFileError(path, f"value {value:g} for bone {bone!r} is beyond the accepted "
                              f"magnitude {MAX_ABS_VALUE:g}", lineno)


def motion_channels(motion: Motion) -> np.ndarray:
    """A motion's values in AMC channel order and ASF units, shape (T, C)."""
    skeleton = motion.skeleton
    layout = ChannelLayout(skeleton)
    values = np.zeros((motion.n_frames, layout.n_channels))
    root = motion.root.copy()
    root[:, :3] /= skeleton.length_to_m
    values[:, layout.root_columns] = root
    declared = layout.posture_columns >= 0
    values[:, layout.posture_columns[declared]] = motion.posture_deg[:, declared]
    if motion.extra_deg is not None:
        values[:, layout.extra_columns] = motion.extra_deg
    return values


def write_amc(path: str | os.PathLike, motion: Motion, precision: int = 10) -> None:
    """Write a motion as an AMC file (degrees, frames numbered from 1), atomically.

    Values are printed with ``precision`` significant digits, so reading the file back
    gives the same numbers to that precision. Channels outside the 21 joints are written
    from ``motion.extra_deg`` (zeros if it is ``None``).
    """
    layout = ChannelLayout(motion.skeleton)
    values = motion_channels(motion)
    number = f"%.{precision}g"
    frame_format = "%d\n" + "".join(
        f"{name} " + " ".join([number] * count) + "\n" for name, _, count in layout.bones
    )
    header = (f"#!OML:ASF {os.path.basename(motion.skeleton.source)}\n"
              "# written by upm-controller\n:FULLY-SPECIFIED\n:DEGREES\n")
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as handle:
        handle.write(header)
        for t in range(values.shape[0]):
            handle.write(frame_format % (t + 1, *values[t]))
