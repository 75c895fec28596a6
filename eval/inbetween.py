"""The study's in-betweening task: the LaFAN1 protocol's L2P, L2Q and NPSS
(:mod:`eval.lafan`; Harvey et al. 2020) on held-out windows of the test clips, for every
method of the study and the protocol's two baselines (zero velocity; interpolation: LERP
root, SLERP joints).

- **Windows**: drawn like the study's real windows (:func:`eval.pairs.draw_real_windows`:
  as many as pairs, the test clips in seeded rounds, starts uniform with
  :data:`eval.pairs.REAL_CONTEXT` frames on each side), long enough for the longest
  transition; every transition length starts at the same frame, as the protocol's
  lengths share its test windows. A clip too short for them (02_03) is left out.
- **Time**: the clips are at 120 fps (141_04 resampled from 60), the protocol at 30. The
  task reads every 4th frame of a window (120 = 4 x 30: recorded frames, no
  interpolation; for 141_04, recorded at 60 fps, they are its recorded frames when C is
  even and frames of its 120-fps spline when C is odd) and runs the
  protocol as it is: :data:`eval.lafan.PAST_FRAMES` (10) frames of past context ending at
  the last context frame C, a transition of n frames at 30 fps, the target at C + n + 1
  and :data:`FUTURE_FRAMES` frames from it. The methods run at 30 fps on those frames
  (their windows are defined in frames; at 120 fps a 1 s transition is 123 frames, where
  spacetime took 3 to 30 s per transition) and the metrics compare their n frames with the
  recorded ones. In 120-fps frames a window spans :func:`gap_frames` frames between C
  and the target.
- **What each method sees**: the 10 past frames and the 10 from the target on (the
  protocol's models see the past and the target frame only; the study's methods also
  read the target's velocity, from the 3 frames their splines use). Clip 2 is the same
  clip, so it is not turned (``align_heading=False``: the target's heading is known) but,
  as in every transition of the project, it is moved to where the shared root velocity
  blend ends: the study's methods do not aim at the target's recorded horizontal
  position, and their L2P includes that miss (``target_miss_m``, the same for all of
  them).
- **Normalisation** (L2P): per joint and coordinate, the standard deviation of the global
  positions over the protocol's training windows (50 frames every 20 at 30 fps, centred
  and turned, :func:`eval.lafan.stats_windows`) of the train split, resampled to 30 fps
  (:func:`upm.motion.resample.resample`; cached, :func:`cached_position_std`).

The data are not LaFAN1's (CMU clips, another skeleton, other subjects and motions,
other joints), so the figures are comparable with the literature's in kind, not in
value.
"""

from __future__ import annotations

import numpy as np

from eval.lafan import (
    INTERPOLATION,
    LAFAN_FPS,
    LAFAN_LENGTHS,
    PAST_FRAMES,
    ZERO_VELOCITY,
    facing_rotation,
    interpolation,
    position_std,
    stats_windows,
    window_metrics,
    zero_velocity,
)
from eval.metrics import Metric
from eval.pairs import REAL_CONTEXT, STUDY_FPS, draw_real_windows

#: The row kind of the in-betweening scores in ``scores.csv``.
INBETWEEN = "inbetween"
#: 120-fps frames per 30-fps frame.
STEP = int(round(STUDY_FPS / LAFAN_FPS))
#: Frames from the target on that the methods get (the protocol's future context; its
#: benchmark reads the first, the target, only).
FUTURE_FRAMES = 10

_METRICS = (
    Metric("l2q", "L2Q", "quaternion L2", "lower",
           "per frame, the L2 norm of the difference of the 22 global joint quaternions "
           "(one 88-vector; the prediction's signs put in the truth's hemisphere), "
           "averaged over the transition's frames at 30 fps (Harvey et al. 2020)"),
    Metric("l2p", "L2P", "normalised", "lower",
           "per frame, the L2 norm of the difference of the 22 global joint positions "
           "(one 66-vector), each coordinate divided by its standard deviation over the "
           "protocol's training windows of the train split; averaged over the frames"),
    Metric("npss", "NPSS", "", "lower",
           "normalised power spectrum similarity of the global quaternions (Gopalakrishnan "
           "et al. 2019, as the LaFAN1 benchmark computes it): the power-weighted earth "
           "mover's distance between the truth's and the prediction's normalised power "
           "spectra; the protocol's figure over windows weights each by npss_power"),
    Metric("npss_power", "NPSS weight", "DFT power", "n/a",
           "the truth's total power over the features (squared real DFT coefficients): "
           "the window's weight in the protocol's pooled NPSS"),
    Metric("target_miss_m", "target miss", "m", "lower",
           "how far, horizontally, the method puts the target frame (the clip after the "
           "gap) from where it was recorded: the study's methods move it to where the "
           "shared root velocity blend ends; 0 for the baselines, which keep it"),
)
#: The in-betweening figures, by name.
INBETWEEN_METRICS: dict[str, Metric] = {m.name: m for m in _METRICS}


def gap_frames(length: int) -> int:
    """New 120-fps frames for a protocol transition of ``length`` frames at 30 fps: the
    target is (length + 1) / 30 s after the last context frame."""
    return STEP * (int(length) + 1) - 1


def draw_windows(lengths: dict[str, int], n: int, seed: int):
    """The task's windows (:class:`eval.pairs.RealWindow`, ``start`` the first frame of
    the gap, ``frames`` the longest gap), the study's real-window draw."""
    return draw_real_windows(lengths, n, gap_frames(max(LAFAN_LENGTHS)), seed,
                             context=max(REAL_CONTEXT, STEP * max(PAST_FRAMES, FUTURE_FRAMES)))


def train_position_std(catalog, split: str = "train") -> np.ndarray:
    """The L2P normalisation: per joint and coordinate, the standard deviation of the
    global positions over the protocol's training windows of the split's clips at 30 fps,
    (22, 3) metres."""
    from upm.motion.resample import resample

    windows = []
    for name in catalog.names(split):
        clip = resample(catalog.load(name), LAFAN_FPS)
        windows.append(stats_windows(clip.skeleton, clip.posture_deg, clip.root))
    return position_std(windows)


#: Modules whose code decides the normalisation: a change to any of them recomputes it.
_STATS_MODULES = ("eval.lafan", "upm.motion.kinematics", "upm.motion.resample",
                  "upm.motion.amc", "upm.motion.asf", "upm.ops.rotations")


def cached_position_std(catalog, split: str = "train") -> np.ndarray:
    """:func:`train_position_std`, kept in the cache (``upm.core.cache``) under a digest
    of the split's files and the code that computes it (reading and resampling the train
    split takes half a minute)."""
    import importlib
    from pathlib import Path

    from upm.core.cache import cache_dir, digest
    from upm.core.fileio import atomic_path

    items: list[bytes | str] = [split]
    items += [Path(importlib.import_module(m).__file__).read_bytes() for m in _STATS_MODULES]
    for name in catalog.names(split):
        info = catalog.info(name)
        items += [name, str(info.fps), info.amc_path.read_bytes(), info.asf_path.read_bytes()]
    path = cache_dir("lafan") / f"position-std-{digest(*items)}.npy"
    if path.exists():
        return np.load(path)
    std = train_position_std(catalog, split)
    with atomic_path(path) as tmp:
        np.save(tmp, std)
    return std


def _at_30_fps(clip, frames: np.ndarray):
    """The clip's frames ``frames`` (120-fps indices, 4 apart) as a 30-fps motion."""
    return clip.replace(posture_deg=clip.posture_deg[frames], root=clip.root[frames],
                        extra_deg=None if clip.extra_deg is None else clip.extra_deg[frames],
                        fps=LAFAN_FPS)


def score_window(data, window, std_m, methods, alpha: float) -> list:
    """Every method and baseline on one window at every protocol length.

    Parameters
    ----------
    data : eval.study.StudyData
    window : eval.pairs.RealWindow
        From :func:`draw_windows`: ``start - 1`` is the last context frame C.
    std_m : ndarray, shape (22, 3)
        :func:`train_position_std`.
    methods : sequence of str
        The study's methods (the baselines are added).
    alpha : float
        The key-posture ratio.

    Returns
    -------
    list of (length, method, {metric: value})
        Values rounded to 6 decimals (``npss_power`` to 6 significant digits).
    """
    from upm.transitions import transition

    clip = data.motions[window.clip]
    skeleton = clip.skeleton
    c = window.start - 1
    facing = facing_rotation(skeleton, clip.root[c])
    before = _at_30_fps(clip, c - STEP * np.arange(PAST_FRAMES - 1, -1, -1))
    last = (before.posture_deg[-1], before.root[-1])
    out = []
    for length in LAFAN_LENGTHS:
        truth = _at_30_fps(clip, c + STEP * np.arange(1, length + 1))
        after = _at_30_fps(clip, c + STEP * (length + 1 + np.arange(FUTURE_FRAMES)))
        target = (after.posture_deg[0], after.root[0])
        found = {}
        for method in methods:
            t = transition(method, before, after, length, alpha, data.sources.get(method),
                           align_heading=False)
            found[method] = ((t.motion.posture_deg[t.window], t.motion.root[t.window]),
                             t.motion.root[t.window.stop])
        found[ZERO_VELOCITY] = (zero_velocity(*last, length), target[1])
        found[INTERPOLATION] = (interpolation(skeleton, last, target, length), target[1])
        for method, (predicted, target_root) in found.items():
            values = window_metrics(skeleton, facing, std_m,
                                    (truth.posture_deg, truth.root), predicted)
            miss = target_root[[0, 2]] - target[1][[0, 2]]
            values["target_miss_m"] = float(np.hypot(*miss))
            out.append((length, method, _rounded(values)))
    return out


def _rounded(values: dict) -> dict:
    return {k: (float(f"{v:.6g}") if k == "npss_power" else round(float(v), 6))
            for k, v in values.items()}
