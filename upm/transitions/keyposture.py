"""The key-posture methods (paper section 3.2): ``upm``, ``som``, ``classnn``, ``snap``.

All four build the window the same way and differ only in where the key posture comes
from (a :class:`~upm.transitions.base.KeyPostureSource`):

1. the key posture K = ``source.key_posture(A, B, alpha)`` (paper section 3.1);
2. K is placed on the turn of the circle nearest the alpha-point of A->B (so that a DOF
   crossing +-180 does not go the long way round);
3. a cubic B-spline passes through the last ``SPLINE_CONTEXT`` frames of clip 1 (up to
   A), K at the window's middle ``t = (L + 1) / 2``, and the first ``SPLINE_CONTEXT``
   frames of clip 2 (from B), all unwrapped along time; the window is the spline at
   ``t = 1 .. L``.

Continuity: C1 at both edges (the spline is C2 and passes through the clip frames on
both sides of each join). At alpha = 0.5 and odd L the middle window frame is K exactly;
for even L the middle falls between two frames and the spline passes through K there.
"""

from __future__ import annotations

import math

import numpy as np

from upm.core.errors import UsageError
from upm.transitions import kernels
from upm.transitions.base import TransitionMethod, WindowProblem, WindowResult
from upm.transitions.spline import window_weights


def key_posture_unwrapped(problem: WindowProblem) -> tuple[np.ndarray, np.ndarray]:
    """The key posture, wrapped and on the turn nearest the alpha-point of A->B.

    Returns
    -------
    key_wrapped, key_continuous : ndarray, shape (63,)
    """
    key_wrapped, key, _ = _key(problem)
    return key_wrapped, key


def _key(problem: WindowProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`key_posture_unwrapped` and the squared differences (63,) of the continuous
    key from the alpha-point."""
    source = problem.key_source
    a, b = problem.a_deg, problem.b_deg
    key = np.asarray(source.key_posture(*kernels.wrap_pair(a, b), problem.alpha), dtype=float)
    if key.shape != a.shape:
        finite = False
    else:
        key_wrapped, near, squares, finite = kernels.key_on_turn(key, a, b, problem.alpha)
    if not finite:
        raise UsageError(f"the key-posture source {type(source).__name__} returned "
                         f"{key.shape} values (expected 63 finite degrees)")
    return key_wrapped, near, squares


def solve(problem: WindowProblem) -> WindowResult:
    key_wrapped, key, squares = _key(problem)
    values = np.concatenate([problem.before_deg, key[None], problem.after_deg])
    # keyframe_spline through clip 1's frames, the key at the middle, clip 2's frames
    weights = window_weights(problem.before_deg.shape[0], problem.after_deg.shape[0],
                             problem.frames)
    return WindowResult(weights @ values, key_posture_deg=key_wrapped, diagnostics={
        "key_distance_to_alpha_point_deg": math.sqrt(np.sum(squares)),
    })


def _method(kind: str, summary: str, build, key_help: str, role: str,
            needs_map: bool) -> TransitionMethod:
    return TransitionMethod(name=kind, solve=solve, continuity="C1", key_kind=kind,
                            summary=summary, key_source=build, key_help=key_help,
                            role=role, needs_map=needs_map)


def _classnn(context):
    from upm.transitions.sources import ClassNearest

    return ClassNearest(context.training_postures())


def _snap(context):
    from upm.transitions.sources import NearestPosture

    return NearestPosture(context.training_postures())


UPM = _method("upm", "the paper's method: UPM key posture at the middle, cubic B-spline "
                     "through clip frames and key (needs a trained map)",
              lambda context: context.posture_map("upm"),
              "a trained Uniform Posture Map (upm train --kind upm)", "paper", True)
SOM = _method("som", "as upm, with the key posture from a classic fixed-grid SOM (the paper's "
                     "foil; needs a trained SOM)",
              lambda context: context.posture_map("som"), "a trained SOM (upm train --kind som)",
              "baseline", True)
CLASSNN = _method("classnn", "as upm, with each class's key sub-posture the nearest training "
                             "sub-posture (ablation: no map learned)", _classnn,
                  "upm.transitions.ClassNearest.fit(training postures)", "ablation", False)
SNAP = _method("snap", "as upm, with the key posture the whole-body nearest training posture "
                       "(ablation)", _snap,
               "upm.transitions.NearestPosture.fit(training postures)", "ablation", False)
