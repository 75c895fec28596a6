"""Where to end a clip so that the next can follow it: gait-phase-matched cuts.

A sequence of whole clips joins each clip's last frame to the next one's first, wherever
in its stride each happens to be: 02_01 ends with its left foot early in its swing and
02_02 begins with it late in its swing, so within the 0.17 s window the feet cross most
of a stride near the floor, which a body standing on a foot cannot do. Motion graphs
(Kovar et al. 2002) and motion matching cut where the poses match instead. Here each
clip but the last ends at the frame, within its last :data:`MATCH_SEARCH_S` and its
second half, whose feet
are nearest the next clip's first frame's: both ankles' positions relative to the pelvis,
in the pelvis's heading frame, and their velocities (so that a foot passing forward is
not matched with one passing back).
"""

from __future__ import annotations

from itertools import pairwise
from typing import NamedTuple

import numpy as np

from upm.motion.kinematics import global_transforms
from upm.motion.motion import Motion

#: The end of each clip is chosen within its last this many seconds (a stride and a bit
#: of a walk: every phase is within reach).
MATCH_SEARCH_S = 1.2
#: Ankle velocities count as their displacement over this many seconds.
VELOCITY_WEIGHT_S = 0.1
#: The bones whose distal ends are the ankles (ASF names).
ANKLE_BONES = ("ltibia", "rtibia")


class Cut(NamedTuple):
    """Where a clip ends to be followed by the next.

    Attributes
    ----------
    stop : int
        The clip's frames are ``0 .. stop - 1``.
    distance_m : float
        The feet's feature distance (:func:`gait_features`) between the clip's frame
        ``stop - 1`` and the next clip's first frame.
    whole_distance_m : float
        The same for the clip's last frame (the whole clip).
    """

    stop: int
    distance_m: float
    whole_distance_m: float


def gait_features(motion: Motion) -> np.ndarray:
    """Both ankles relative to the pelvis, in its heading frame, and their velocities.

    Parameters
    ----------
    motion : Motion
        At least 2 frames.

    Returns
    -------
    ndarray, shape (T, 12)
        Metres: the left and right ankle's position (3 each), then their velocities times
        :data:`VELOCITY_WEIGHT_S` (central differences, one-sided at the ends).
    """
    from upm.transitions.root import heading_deg

    if motion.n_frames < 2:
        raise ValueError("gait features need at least 2 frames")
    skeleton = motion.skeleton
    rotations, positions = global_transforms(skeleton, motion.posture_deg, motion.root)
    ankles = positions[:, [skeleton.bone_index(b) for b in ANKLE_BONES]]  # (T, 2, 3)
    relative = ankles - positions[:, :1]
    # turn about the vertical (ASF y) by minus the pelvis's heading
    theta = np.radians(heading_deg(rotations[:, 0]))
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    x, y, z = relative[..., 0], relative[..., 1], relative[..., 2]
    local = np.stack([c * x - s * z, y, s * x + c * z], axis=-1)
    velocity = np.gradient(local, 1.0 / motion.fps, axis=0) * VELOCITY_WEIGHT_S
    return np.concatenate([local.reshape(-1, 6), velocity.reshape(-1, 6)], axis=1)


def matched_cut(before: Motion, after: Motion, search_s: float = MATCH_SEARCH_S) -> Cut:
    """The frame to end ``before`` at so that ``after`` (from its first frame) follows it
    at the nearest gait phase.

    Parameters
    ----------
    before, after : Motion
        At least 2 frames each; ``before``'s frame rate sets the search's length.
    search_s : float
        How far back from its end ``before`` may be cut (> 0); it keeps at least half of
        its frames, and at least 2.

    Returns
    -------
    Cut
        The earliest frame on a tie.
    """
    if not search_s > 0:
        raise ValueError(f"the cut's search must be longer than 0 s, not {search_s!r}")
    features = gait_features(before)
    target = gait_features(after.frames(0, min(after.n_frames, 3)))[0]
    n = before.n_frames
    # the last frame's candidates: within search_s of the end, in the second half
    first = max(1, n - int(round(search_s * before.fps)), (n + 1) // 2 - 1)
    distance = np.linalg.norm(features[first:] - target, axis=1)
    best = int(np.argmin(distance))
    return Cut(stop=first + best + 1, distance_m=float(distance[best]),
               whole_distance_m=float(distance[-1]))


def matched_pieces(pieces: list[Motion],
                   search_s: float = MATCH_SEARCH_S) -> tuple[list[Motion], list[Cut]]:
    """Each piece but the last ended where the next one's first frame matches it.

    Returns
    -------
    pieces : list of Motion
        The cut pieces (the last one whole).
    cuts : list of Cut
        One per join (``len(pieces) - 1``).
    """
    pieces = list(pieces)
    cuts = [matched_cut(a, b, search_s) for a, b in pairwise(pieces)]
    out = [p.frames(0, cut.stop) for p, cut in zip(pieces[:-1], cuts, strict=True)]
    return out + pieces[-1:], cuts
