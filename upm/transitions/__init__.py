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
========== ========== ==================================================================

The root is the same for every method (:mod:`upm.transitions.root`).
"""

from __future__ import annotations

from upm.transitions import inertialize, keyposture, linear, slerp, spacetime
from upm.transitions.base import (
    KeyPostureSource,
    Transition,
    TransitionMethod,
    WindowProblem,
    WindowResult,
)
from upm.transitions.join import get_method, make_problem, match_clip, transition
from upm.transitions.sequence import Sequence, build_sequence
from upm.transitions.sources import ClassNearest, NearestPosture, training_postures

#: Every transition method, by name.
METHODS: dict[str, TransitionMethod] = {
    m.name: m
    for m in (keyposture.UPM, keyposture.SOM, keyposture.CLASSNN, keyposture.SNAP,
              linear.METHOD, slerp.METHOD, inertialize.METHOD, spacetime.METHOD)
}

#: Names of the methods whose key posture comes from a source (a map or an ablation).
KEY_POSTURE_METHODS: tuple[str, ...] = tuple(n for n, m in METHODS.items() if m.needs_key_source)

__all__ = [
    "KEY_POSTURE_METHODS",
    "METHODS",
    "ClassNearest",
    "KeyPostureSource",
    "NearestPosture",
    "Sequence",
    "Transition",
    "TransitionMethod",
    "WindowProblem",
    "WindowResult",
    "build_sequence",
    "get_method",
    "make_problem",
    "match_clip",
    "training_postures",
    "transition",
]
