"""``linear``: per-DOF linear interpolation from A to B, the short way round (the
paper's comparison, its Fig. 13b).

Window frame ``t`` (1 .. L) is ``A + t / (L + 1) * wrap(B - A)``. Continuity: C0 only —
positions join at both edges, but the velocity jumps from the clip's own to the constant
``wrap(B - A) / (L + 1)``.
"""

from __future__ import annotations

from upm.transitions.base import TransitionMethod, WindowProblem, WindowResult


def solve(problem: WindowProblem) -> WindowResult:
    return WindowResult(problem.linear())


METHOD = TransitionMethod(
    name="linear", solve=solve, continuity="C0", key_kind=None,
    summary="per-DOF linear blend from A to B, the short way round (the paper's comparison)",
    role="paper-comparison",
)
