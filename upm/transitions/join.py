"""One transition: clip 1 up to A, L new frames, clip 2 from B (paper section 3.2).

The joint angles of the window come from the chosen method; the root from the shared
root blend (:mod:`upm.transitions.root`) — every method gets the same root, so that
comparisons between methods are about the postures. Angles: the methods work on angles
unwrapped along time (clip 2 shifted by whole turns so that B lies within 180 degrees of
A); the window's joint angles are then wrapped to [-180, 180), like the paper's DOF
values, so the joined motion is continuous *on the circle* (difference frames with
``upm.ops.angles.angle_diff_deg`` or unwrap first). Clip frames are kept as given, but for
marker dropouts (:mod:`upm.motion.dropouts`: a bone read as exactly zero for a few frames), which
are filled from the frames around them first: 16_15 starts with its left arm at rest for
2 frames, and B taken from them would swing the arm down through the window and 76 degrees
back up in the frame after it. The root's Euler angles, in contrast, are written
continuing from A's (numerically continuous).
"""

from __future__ import annotations

import time

import numpy as np

from upm.core.errors import UsageError
from upm.motion.dropouts import dropout_runs, fill_runs
from upm.motion.motion import Motion
from upm.motion.resample import resample
from upm.transitions import kernels
from upm.transitions.base import (
    Transition,
    TransitionMethod,
    WindowProblem,
    check_alpha,
    check_frames,
    check_motion,
)
from upm.transitions.registry import get_method
from upm.transitions.root import blend_root, leg_length_m
from upm.transitions.spline import SPLINE_CONTEXT


def check_key_source(method: TransitionMethod, key_source) -> None:
    """Whether ``key_source`` suits ``method`` (UsageError if not)."""
    if not method.needs_key_source:
        return
    if key_source is None:
        raise UsageError(f"method {method.name!r} needs a key-posture source: "
                         f"{method.key_help or 'a key-posture source'}")
    # what isinstance(key_source, KeyPostureSource) checks (a runtime protocol), without
    # its walk over the protocol's classes on every call
    if not callable(getattr(key_source, "key_posture", None)):
        raise UsageError(f"method {method.name!r}: {type(key_source).__name__} has no "
                         "key_posture(a_deg, b_deg, alpha)")
    kind = getattr(key_source, "kind", None)
    if isinstance(kind, str) and kind != method.key_kind:
        raise UsageError(f"method {method.name!r} expects a {method.key_kind!r} key source, "
                         f"not a {kind!r} one")


def match_clip(reference: Motion, motion: Motion) -> tuple[Motion, dict[str, float]]:
    """``motion`` made ready to follow ``reference``: resampled to its frame rate and, for
    another subject, put on its skeleton with the root translation scaled by the ratio
    of leg lengths (postures are joint angles and carry over as they are).

    Returns
    -------
    Motion, dict
        The matched motion and ``{"root_scale", "resampled_from_fps"}``.
    """
    info = {"root_scale": 1.0, "resampled_from_fps": 0.0}
    if motion.fps != reference.fps:
        info["resampled_from_fps"] = float(motion.fps)
        motion = resample(motion, reference.fps)
    if motion.skeleton is not reference.skeleton:
        scale = leg_length_m(reference.skeleton) / leg_length_m(motion.skeleton)
        root = motion.root.copy()
        root[:, :3] *= scale
        same_extras = motion.skeleton.extra_channels == reference.skeleton.extra_channels
        motion = motion.replace(skeleton=reference.skeleton, root=root,
                                extra_deg=motion.extra_deg if same_extras else None)
        info["root_scale"] = float(scale)
    return motion, info


def make_problem(before: Motion, after: Motion, frames: int, alpha: float,
                 key_source=None, context: int = SPLINE_CONTEXT,
                 root_window=None) -> WindowProblem:
    """The window problem: up to ``context`` frames of each clip, unwrapped along time,
    clip 2's shifted by whole turns per DOF so that B is within 180 degrees of A;
    ``root_window`` (L, 6), the window's shared root, when known."""
    k1, k2 = min(context, before.n_frames), min(context, after.n_frames)
    # unwrap_deg of both, then clip 2 shifted: one compiled call, the same operations
    before_deg, after_deg = kernels.window_context(before.posture_deg[-k1:],
                                                   after.posture_deg[:k2])
    return WindowProblem(before_deg=before_deg, after_deg=after_deg, frames=frames,
                         alpha=alpha, skeleton=before.skeleton, key_source=key_source,
                         root_window=root_window)


def _extra_window(before: Motion, after: Motion, frames: int) -> np.ndarray | None:
    if before.extra_deg is None and after.extra_deg is None:
        return None
    n_extra = len(before.skeleton.extra_channels)
    a = before.extra_deg[-1] if before.extra_deg is not None else np.zeros(n_extra)
    b = after.extra_deg[0] if after.extra_deg is not None else np.zeros(n_extra)
    return kernels.linear_extra(a, b, frames)  # wrap(a + s * wrap(b - a)), s = t / (L + 1)


def _concat_extra(parts: list[Motion | np.ndarray | None], lengths: list[int], n_extra: int):
    if all(p is None for p in parts):
        return None
    return np.concatenate([np.zeros((n, n_extra)) if p is None else p
                           for p, n in zip(parts, lengths, strict=True)])


def _without_dropouts(motion: Motion) -> tuple[Motion, int]:
    """``motion`` with its marker dropouts filled, and the number of (joint, frame) entries
    filled: :func:`upm.motion.dropouts.fill_dropouts`, to the last bit, but its per-joint
    scan runs only on the joints that can have a dropout at all -- all three angles exactly
    zero in some frames but not in every frame -- found in one compiled pass. (The scan
    of all 21 joints of both clips was three quarters of a transition's time.)"""
    posture = motion.posture_deg
    filled, out = 0, None
    for joint in kernels.dropout_candidates(posture).tolist():
        channels = slice(3 * joint, 3 * joint + 3)
        runs = dropout_runs(posture[:, channels])
        if runs:
            out = np.array(posture, dtype=float) if out is None else out
            out[:, channels] = fill_runs(out[:, channels], runs)
            filled += sum(stop - start for start, stop in runs)
    return (motion if out is None else motion.replace(posture_deg=out)), filled


def transition(method: str, before: Motion, after: Motion, frames: int = 20,
               alpha: float = 0.5, key_source=None, *, align_heading: bool = True,
               context: int = SPLINE_CONTEXT) -> Transition:
    """Join two clips with a transition window of ``frames`` new frames.

    Parameters
    ----------
    method : str
        A name of :data:`upm.transitions.METHODS` (:mod:`upm.transitions.registry`).
    before : Motion
        Clip 1; its last frame is A.
    after : Motion
        Clip 2; its first frame is B. Resampled to clip 1's frame rate if it differs;
        from another subject, it is put on clip 1's skeleton (see :func:`match_clip`).
    frames : int
        L, the window's new frames (paper: 20 at 120 fps).
    alpha : float
        Key-posture ratio in [0, 1]: 0 is A, 1 is B (paper: 0.5).
    key_source : KeyPostureSource, optional
        Required by the key-posture methods (``upm``, ``som``, ``classnn``, ``snap``,
        ``feasible``): :func:`upm.transitions.registry.build_key_source` builds it.
    align_heading : bool
        Turn clip 2 about the vertical so its heading continues clip 1's (default).
    context : int
        Frames of each clip the window's fit sees (the splines, inertialization's
        velocities); at least 2 for velocity continuity.

    Returns
    -------
    Transition

    Raises
    ------
    UsageError
        Unknown method, missing or wrong key source, bad ``frames``/``alpha``, empty clips.
    """
    spec = get_method(method)
    frames, alpha = check_frames(frames), check_alpha(alpha)
    check_motion(before, "clip 1")
    check_motion(after, "clip 2")
    check_key_source(spec, key_source)
    if isinstance(context, bool) or not isinstance(context, (int, np.integer)) or context < 1:
        raise UsageError(f"context must be a whole number of frames >= 1, not {context!r}")
    before, filled_before = _without_dropouts(before)
    after, filled_after = _without_dropouts(after)
    after, info = match_clip(before, after)
    info["dropouts_filled"] = float(filled_before + filled_after)

    start = time.perf_counter()
    # The root first: it does not depend on the window's angles, and a method may check
    # its frames against the floor with it.
    root = blend_root(before.root, after.root, frames, alpha, before.skeleton.root_axis_order,
                      align_heading=align_heading, context=context)
    problem = make_problem(before, after, frames, alpha, key_source, context, root.window)
    result = spec.solve(problem)
    # wrap_deg, and 0 where the skeleton declares no DOF
    window_posture = kernels.wrap_window(np.asarray(result.posture_deg, dtype=float),
                                         before.skeleton.declared)
    seconds = time.perf_counter() - start

    n1, n2 = before.n_frames, after.n_frames
    n_extra = len(before.skeleton.extra_channels)
    extra = _concat_extra([before.extra_deg, _extra_window(before, after, frames),
                           after.extra_deg], [n1, frames, n2], n_extra)
    motion = Motion(
        skeleton=before.skeleton,
        posture_deg=np.concatenate([before.posture_deg, window_posture, after.posture_deg]),
        root=np.concatenate([before.root, root.window, root.after]),
        fps=before.fps,
        extra_deg=extra,
        name=f"{before.name}+{after.name}" if before.name or after.name else "",
    )
    diagnostics = dict(result.diagnostics)
    diagnostics.update(info)
    out = Transition(
        motion=motion, window=slice(n1, n1 + frames), method=spec.name, frames=frames,
        alpha=alpha, key_posture_deg=result.key_posture_deg, key_time=problem.key_time,
        seconds=seconds, heading_turn_deg=root.heading_turn_deg, diagnostics=diagnostics,
    )
    return out if spec.finish is None else spec.finish(out, key_source)
