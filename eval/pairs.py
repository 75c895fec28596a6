"""The held-out protocol: seeded transition pairs between 200-frame segments of the test
clips, and the real windows that calibrate every figure (SPEC section 7).

- **Clips**: the ``test`` split of ``clips.csv``, every clip resampled to
  :data:`STUDY_FPS` (120 fps; 141_04 is stored at 60) before anything else.
- **Segments**: :data:`SEGMENT_FRAMES` (200) frames at 120 fps with a seeded uniform
  start; a clip shorter than that gives one segment of its whole length (02_03: 173
  frames).
- **Pairs**: segment 1 (ending at A) and segment 2 (starting at B) come from two
  *different* test clips. The ordered clip pairs are visited in a seeded random order,
  each once before any repeats (7 test clips: 42 ordered pairs), so clips and clip pairs
  are balanced whatever N is; the segment starts are drawn independently per pair.
- **Real windows** (the calibration row): L consecutive frames of a test clip, the clips
  visited in seeded random rounds like the pairs, the start uniform among the places
  that leave :data:`REAL_CONTEXT` frames before and after the window (what the scoring
  needs for the dynamics filter and the finite differences).

Every draw comes from its own seeded stream (``numpy.random.default_rng([seed, stream,
...])``): the clip order of the rounds from one, each pair's (or real window's) start
from its own. So the first n pairs of a study of N > n pairs are the n pairs of the
smaller study (the reduced default study is part of the full one), and the pairs do not
change with the window lengths.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from upm.core.errors import UsageError

#: Frame rate of the study: every clip is resampled to it first.
STUDY_FPS = 120.0
#: Frames of each segment (the paper's protocol).
SEGMENT_FRAMES = 200
#: Real frames a calibration window needs before and after it.
REAL_CONTEXT = 40

_PAIR_STREAM = 1
_REAL_STREAM = 2


@dataclass(frozen=True)
class Segment:
    """Frames ``start:stop`` (at 120 fps) of test clip ``clip``."""

    clip: str
    start: int
    stop: int

    @property
    def frames(self) -> int:
        return self.stop - self.start

    def as_dict(self) -> dict:
        return {"clip": self.clip, "start": self.start, "stop": self.stop}


@dataclass(frozen=True)
class Pair:
    """One transition of the study: ``first`` ends at A, ``second`` starts at B.

    Attributes
    ----------
    index : int
        The pair's id (0-based, the order of the draw).
    first, second : Segment
    """

    index: int
    first: Segment
    second: Segment


@dataclass(frozen=True)
class RealWindow:
    """A real window of ``frames`` frames at ``start`` of test clip ``clip`` (120 fps)."""

    index: int
    clip: str
    start: int
    frames: int

    @property
    def stop(self) -> int:
        return self.start + self.frames


def _rounds(items: list, n: int, rng: np.random.Generator) -> list:
    """``n`` items taken from seeded random permutations of ``items``, one after the other
    (each item once per round)."""
    out: list = []
    while len(out) < n:
        out += [items[i] for i in rng.permutation(len(items))]
    return out[:n]


def draw_pairs(lengths: dict[str, int], n: int, seed: int) -> list[Pair]:
    """The study's transition pairs.

    Parameters
    ----------
    lengths : dict of str to int
        Frames (at 120 fps) of each test clip, by name (at least two clips).
    n : int
        How many pairs (>= 1).
    seed : int

    Returns
    -------
    list of Pair
        ``n`` pairs, ids ``0 .. n-1``.
    """
    names = sorted(lengths)
    if len(names) < 2:
        raise UsageError(f"the study needs at least two test clips, not {len(names)}")
    if n < 1:
        raise UsageError(f"the number of pairs must be at least 1, not {n}")
    order = np.random.default_rng([seed, _PAIR_STREAM, 0])
    ordered = [(a, b) for a in names for b in names if a != b]
    pairs = []
    for index, (name1, name2) in enumerate(_rounds(ordered, n, order)):
        rng = np.random.default_rng([seed, _PAIR_STREAM, 1, index])
        first, second = (_segment(name, lengths[name], rng) for name in (name1, name2))
        pairs.append(Pair(index=index, first=first, second=second))
    return pairs


def _segment(name: str, length: int, rng: np.random.Generator) -> Segment:
    frames = min(SEGMENT_FRAMES, length)
    start = int(rng.integers(0, length - frames + 1))
    return Segment(name, start, start + frames)


def draw_real_windows(lengths: dict[str, int], n: int, frames: int, seed: int,
                      context: int = REAL_CONTEXT) -> list[RealWindow]:
    """Real windows of ``frames`` frames for the calibration row.

    Parameters
    ----------
    lengths : dict of str to int
        Frames (at 120 fps) of each test clip.
    n : int
        How many windows.
    frames : int
        L.
    seed : int
    context : int
        Real frames required before and after each window.

    Returns
    -------
    list of RealWindow
        Clips too short for ``frames + 2 context`` frames are left out of the draw.
    """
    fits = sorted(name for name, length in lengths.items() if length >= frames + 2 * context)
    if not fits:
        raise UsageError(f"no test clip is long enough for a real {frames}-frame window "
                         f"with {context} frames around it")
    order = np.random.default_rng([seed, _REAL_STREAM, frames, 0])
    windows = []
    for index, name in enumerate(_rounds(fits, n, order)):
        rng = np.random.default_rng([seed, _REAL_STREAM, frames, 1, index])
        start = int(rng.integers(context, lengths[name] - frames - context + 1))
        windows.append(RealWindow(index=index, clip=name, start=start, frames=frames))
    return windows


def exclusion_zones(pair: Pair, frames: int, lengths: dict[str, int]) -> list[Segment]:
    """The test-clip frames the nearest-real-posture distance of a pair's window ignores.

    In each source clip: the segment, the L frames the window stands in for, and
    :data:`SEGMENT_FRAMES` frames beyond them (clip 1: after its segment; clip 2: before
    it) — the same zone a real window of that clip excludes around itself
    (:func:`real_exclusion_zone`), so transitions and the calibration are scored alike.
    """
    reach = frames + SEGMENT_FRAMES
    a, b = pair.first, pair.second
    return [Segment(a.clip, a.start, min(lengths[a.clip], a.stop + reach)),
            Segment(b.clip, max(0, b.start - reach), b.stop)]


def real_exclusion_zone(window: RealWindow, lengths: dict[str, int]) -> list[Segment]:
    """The frames a real window's nearest-real distance ignores: the window and
    :data:`SEGMENT_FRAMES` frames on each side of it (its own clip's segments)."""
    return [Segment(window.clip, max(0, window.start - SEGMENT_FRAMES),
                    min(lengths[window.clip], window.stop + SEGMENT_FRAMES))]
