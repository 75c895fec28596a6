"""Reading BVH files into a skeleton and a channel table.

Any hierarchy depth (bounded by :data:`MAX_DEPTH`), any channel order and count per joint,
``End Site`` blocks, CRLF/LF line endings mixed in one file, tabs or spaces (also after
``Frames:``). Every problem is a :class:`~upm.core.errors.DataFileError` naming the file and
line.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from upm.core.errors import DataFileError

#: Bounds on what a BVH may hold.
MAX_BVH_BYTES = 2 * 1024 ** 3
MAX_JOINTS = 1000
MAX_DEPTH = 256
MAX_ABS_VALUE = 1e7
CHANNEL_NAMES = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation",
                 "Zrotation")


@dataclass(frozen=True)
class BvhSkeleton:
    """A BVH hierarchy.

    Attributes
    ----------
    names : tuple of str, length J
        Joint names in file order (``ROOT`` first; parents before children).
    parents : ndarray of int, shape (J,)
        Parent index, -1 for the root.
    offsets : ndarray, shape (J, 3)
        ``OFFSET`` of each joint in its parent's frame (file units).
    channels : tuple of tuple of str, length J
        Each joint's channels in file order (names of :data:`CHANNEL_NAMES`).
    end_sites : ndarray, shape (J, 3)
        The ``End Site`` offset of each joint that has one (NaN otherwise).
    """

    names: tuple[str, ...]
    parents: np.ndarray
    offsets: np.ndarray
    channels: tuple[tuple[str, ...], ...]
    end_sites: np.ndarray

    @property
    def n_joints(self) -> int:
        return len(self.names)

    @property
    def channel_start(self) -> np.ndarray:
        """Column of each joint's first channel in the motion table, (J,)."""
        counts = [len(c) for c in self.channels]
        return np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(int)

    @property
    def n_channels(self) -> int:
        return sum(len(c) for c in self.channels)


@dataclass(frozen=True)
class BvhMotion:
    """A BVH file's content.

    Attributes
    ----------
    skeleton : BvhSkeleton
    values : ndarray, shape (T, C)
        The ``MOTION`` table (file units and degrees).
    frame_time_s : float
    source : str
    """

    skeleton: BvhSkeleton
    values: np.ndarray
    frame_time_s: float
    source: str = ""

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time_s

    @property
    def n_frames(self) -> int:
        return self.values.shape[0]


def read_bvh(path: str | os.PathLike) -> BvhMotion:
    """Read a BVH file.

    Raises
    ------
    DataFileError
        Missing, unreadable, too large, malformed or out-of-range content (file and line).
    """
    from upm.core.textfile import read_text_lines

    try:
        size = os.path.getsize(path)
    except OSError:
        size = 0
    if size > MAX_BVH_BYTES:
        raise DataFileError(path, f"BVH file of {size} bytes is over the limit of "
                                  f"{MAX_BVH_BYTES} bytes")
    lines = read_text_lines(path, "BVH")
    parser = _Parser(path, lines)
    skeleton = parser.hierarchy()
    values, frame_time = parser.motion(skeleton.n_channels)
    return BvhMotion(skeleton, values, frame_time, str(path))


class _Parser:
    def __init__(self, path, lines):
        self.path = path
        self.lines = lines
        self.i = 0

    def _error(self, message, line=None):
        return DataFileError(self.path, message, line if line is not None else self.i)

    def _next(self) -> list[str]:
        """The next non-blank line's tokens (``self.i`` is its 1-based number)."""
        while self.i < len(self.lines):
            self.i += 1
            tokens = self.lines[self.i - 1].split()
            if tokens:
                return tokens
        raise self._error("the file ends inside the hierarchy", len(self.lines))

    def _numbers(self, tokens, count, what):
        if len(tokens) != count:
            raise self._error(f"{what} needs {count} numbers, found {len(tokens)}")
        try:
            values = [float(t) for t in tokens]
        except ValueError:
            raise self._error(f"{what}: not a number in {' '.join(tokens)!r}") from None
        if not all(math.isfinite(v) and abs(v) <= MAX_ABS_VALUE for v in values):
            raise self._error(f"{what}: values must be finite and within ±{MAX_ABS_VALUE:g}")
        return values

    def hierarchy(self) -> BvhSkeleton:
        tokens = self._next()
        if tokens != ["HIERARCHY"]:
            raise self._error("a BVH file starts with HIERARCHY")
        tokens = self._next()
        if tokens[0] != "ROOT" or len(tokens) != 2:
            raise self._error("expected 'ROOT name' after HIERARCHY")
        names, parents, offsets, channels, ends = [], [], [], [], []
        self._joint(tokens[1], -1, 0, names, parents, offsets, channels, ends)
        return BvhSkeleton(tuple(names), np.array(parents, dtype=int),
                           np.array(offsets, dtype=float).reshape(-1, 3), tuple(channels),
                           np.array(ends, dtype=float).reshape(-1, 3))

    def _joint(self, name, parent, depth, names, parents, offsets, channels, ends):
        if depth > MAX_DEPTH:
            raise self._error(f"the hierarchy is deeper than {MAX_DEPTH} levels")
        if len(names) >= MAX_JOINTS:
            raise self._error(f"more than {MAX_JOINTS} joints")
        if name in names:
            raise self._error(f"joint {name!r} is defined twice")
        index = len(names)
        names.append(name)
        parents.append(parent)
        offsets.append([0.0, 0.0, 0.0])
        channels.append(())
        ends.append([math.nan] * 3)
        if self._next() != ["{"]:
            raise self._error(f"expected '{{' after joint {name!r}")
        seen_offset = False
        while True:
            tokens = self._next()
            key = tokens[0]
            if key == "OFFSET":
                offsets[index] = self._numbers(tokens[1:], 3, "OFFSET")
                seen_offset = True
            elif key == "CHANNELS":
                try:
                    count = int(tokens[1]) if len(tokens) > 1 else -1
                except ValueError:
                    count = -1
                names_given = tokens[2:]
                if count < 0 or count > 6 or len(names_given) != count:
                    raise self._error("CHANNELS needs a count (0-6) and that many names")
                bad = [c for c in names_given if c not in CHANNEL_NAMES]
                if bad:
                    raise self._error(f"unknown channel {bad[0]!r} (channels: "
                                      f"{', '.join(CHANNEL_NAMES)})")
                if len(set(names_given)) != count:
                    raise self._error("a channel is repeated")
                channels[index] = tuple(names_given)
            elif key == "JOINT":
                if len(tokens) != 2:
                    raise self._error("expected 'JOINT name'")
                self._joint(tokens[1], index, depth + 1, names, parents, offsets, channels,
                            ends)
            elif key == "End":
                if tokens[1:] != ["Site"] or self._next() != ["{"]:
                    raise self._error("expected 'End Site {'")
                off = self._next()
                if off[0] != "OFFSET":
                    raise self._error("an End Site needs an OFFSET")
                ends[index] = self._numbers(off[1:], 3, "End Site OFFSET")
                if self._next() != ["}"]:
                    raise self._error("expected '}' closing the End Site")
            elif key == "}":
                if not seen_offset:
                    raise self._error(f"joint {name!r} has no OFFSET")
                return
            else:
                raise self._error(f"unexpected {key!r} in joint {name!r}")

    def motion(self, n_channels: int) -> tuple[np.ndarray, float]:
        tokens = self._next()
        if tokens != ["MOTION"]:
            raise self._error("expected MOTION after the hierarchy")
        tokens = self._next()
        if tokens[0] != "Frames:" or len(tokens) != 2 or not tokens[1].isascii() or \
                not tokens[1].isdigit() or len(tokens[1]) > 9:
            raise self._error("expected 'Frames: N'")
        n_frames = int(tokens[1])
        tokens = self._next()
        if tokens[:2] != ["Frame", "Time:"] or len(tokens) != 3:
            raise self._error("expected 'Frame Time: SECONDS'")
        frame_time = self._numbers(tokens[2:], 1, "Frame Time")[0]
        if not 1e-5 <= frame_time <= 10.0:
            raise self._error(f"Frame Time {frame_time:g} s is out of range (1e-5 to 10 s)")
        start = self.i
        rows = [line for line in self.lines[start:] if line.strip()]
        if len(rows) != n_frames:
            raise self._error(f"'Frames: {n_frames}' but {len(rows)} frame lines follow",
                              start - 1)
        if n_frames == 0:
            raise self._error("no frames", start - 1)
        numbered = [(k, line) for k, line in enumerate(self.lines[start:], start + 1)
                    if line.strip()]
        for k, line in numbered:
            if len(line.split()) != n_channels:
                raise self._error(f"a frame needs {n_channels} values, found "
                                  f"{len(line.split())}", k)
        try:
            table = np.array(" ".join(r for _, r in numbered).split(),
                             dtype=float).reshape(n_frames, n_channels)
        except ValueError:
            for k, line in numbered:
                self.i = k
                self._numbers(line.split(), n_channels, "frame")
            raise self._error("malformed frame lines", start) from None
        bad = ~np.isfinite(table) | (np.abs(table) > MAX_ABS_VALUE)
        if bad.any():
            row = int(np.argwhere(bad.any(axis=1))[0, 0])
            line = numbered[row][0]
            raise self._error(f"frame values must be finite and within ±{MAX_ABS_VALUE:g}",
                              line)
        return table, frame_time
