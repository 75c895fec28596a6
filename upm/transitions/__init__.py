"""Motion transitions (paper section 3.2) and the methods it is compared with, behind one
interface.

>>> from upm.transitions import transition, METHODS
>>> t = transition("linear", clip1, clip2, frames=20)       # doctest: +SKIP
>>> t.motion, t.window, t.window_posture_deg                 # doctest: +SKIP

Every method is a :class:`TransitionMethod` in :data:`METHODS`, selected by name:

========== ========== ==================================================================
name       continuity how the window's joint angles are made
========== ========== ==================================================================
upm        C1         key posture from the Uniform Posture Map at the window's middle,
                      cubic B-spline through clip frames and key (the paper)
som        C1         the same with a classic SOM's key posture (the paper's foil)
classnn    C1         the same with each class's nearest training sub-posture (ablation)
snap       C1         the same with the whole-body nearest training posture (ablation)
linear     C0         per-DOF linear blend, short way round (the paper's comparison)
slerp      C0         per-joint slerp, projected back to the declared Euler DOFs
inertialize C1        Bollo's quintic offset decay
spacetime  C1         minimum inertial effort by L-BFGS-B (Rose et al. 1996 stand-in)
feasible   C1         UPM key among the neurons the humanoid can take, then the window as a
                      small QP: near the UPM curve, minimum jerk, every frame in range
========== ========== ==================================================================

The root is the same for every method (:mod:`upm.transitions.root`). The registry, and
how each method's key source is built, is :mod:`upm.transitions.registry`.
"""

from __future__ import annotations

from upm.transitions.base import (
    KeyPostureSource,
    Transition,
    TransitionMethod,
    WindowProblem,
    WindowResult,
)
from upm.transitions.join import make_problem, match_clip, transition
from upm.transitions.registry import (
    METHODS,
    KeySourceContext,
    build_key_source,
    get_method,
    register,
)
from upm.transitions.sequence import Sequence, build_sequence
from upm.transitions.sources import ClassNearest, NearestPosture, training_postures

#: Names of the methods whose window is made from the postures alone (every method but
#: those whose window the humanoid performs, :attr:`TransitionMethod.finish`).
KINEMATIC_METHODS: tuple[str, ...] = tuple(n for n, m in METHODS.items() if m.finish is None)
#: Names of the methods whose window the humanoid performs (``performed``): they need the
#: humanoid's performer (:mod:`upm.transitions.performed`) and cost about a minute a window.
PERFORMED_METHODS: tuple[str, ...] = tuple(n for n, m in METHODS.items()
                                           if m.finish is not None)
#: Names of the methods whose key posture comes from a source (a map or an ablation).
KEY_POSTURE_METHODS: tuple[str, ...] = tuple(n for n in KINEMATIC_METHODS
                                             if METHODS[n].needs_key_source)

__all__ = [
    "KEY_POSTURE_METHODS",
    "KINEMATIC_METHODS",
    "METHODS",
    "PERFORMED_METHODS",
    "ClassNearest",
    "KeyPostureSource",
    "KeySourceContext",
    "NearestPosture",
    "Sequence",
    "Transition",
    "TransitionMethod",
    "WindowProblem",
    "WindowResult",
    "build_key_source",
    "build_sequence",
    "get_method",
    "make_problem",
    "match_clip",
    "register",
    "training_postures",
    "transition",
]
