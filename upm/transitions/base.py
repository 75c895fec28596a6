"""The shared interface of the transition methods: the window problem, its answer, the
method record and the result of a transition.

Time axis of a transition (in frames): clip 1's last frame A at ``t = 0``, the L window
frames at ``t = 1 .. L``, clip 2's first frame B at ``t = L + 1``; the key posture (for
the methods that have one) at the middle, ``t = (L + 1) / 2``. Frames of clip 1 before A
sit at negative times, frames of clip 2 after B at ``t > L + 1``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from upm.core.errors import UsageError
from upm.motion.motion import Motion
from upm.motion.skeleton import Skeleton


@runtime_checkable
class KeyPostureSource(Protocol):
    """Anything that proposes the key posture of a transition (paper section 3.1): the
    Uniform Posture Map, the classic SOM, or the nearest-training-posture ablations."""

    def key_posture(self, a_deg, b_deg, alpha=0.5) -> np.ndarray:
        """(63,) or (N, 63) degrees for A, B of the same shape and ratio ``alpha``."""
        ...


@dataclass(frozen=True, eq=False)
class WindowProblem:
    """What a method sees: the postures around the window, continuous along time.

    Attributes
    ----------
    before_deg : ndarray, shape (K1, 63)
        The last K1 frames of clip 1 (``K1 >= 1``), ending at A, at ``t = 1-K1 .. 0``;
        unwrapped along time.
    after_deg : ndarray, shape (K2, 63)
        The first K2 frames of clip 2 (``K2 >= 1``), starting at B, at
        ``t = L+1 .. L+K2``; unwrapped along time and shifted by whole turns per DOF so
        that B lies within 180 degrees of A (the short way round).
    frames : int
        L, the number of window frames.
    alpha : float
        Key-posture ratio in [0, 1] (0 is A, 1 is B).
    skeleton : Skeleton
        The skeleton of the joined motion (clip 1's).
    key_source : KeyPostureSource or None
    root_window : ndarray, shape (L, 6), or None
        The root every method's window gets (the shared root blend,
        :func:`upm.transitions.root.blend_root`): tx, ty, tz metres, rx, ry, rz degrees
        in the skeleton's root axis order; None when the caller did not compute it. A
        method that checks its frames against the floor needs it.
    """

    before_deg: np.ndarray
    after_deg: np.ndarray
    frames: int
    alpha: float
    skeleton: Skeleton
    key_source: KeyPostureSource | None = None
    root_window: np.ndarray | None = None

    @property
    def a_deg(self) -> np.ndarray:
        """A, clip 1's last posture, (63,)."""
        return self.before_deg[-1]

    @property
    def b_deg(self) -> np.ndarray:
        """B, clip 2's first posture (within 180 degrees of A per DOF), (63,)."""
        return self.after_deg[0]

    @property
    def end_time(self) -> int:
        """The time of B, ``L + 1``."""
        return self.frames + 1

    @property
    def key_time(self) -> float:
        """The time of the key posture, ``(L + 1) / 2``."""
        return 0.5 * (self.frames + 1)

    @property
    def window_times(self) -> np.ndarray:
        """``1 .. L``, shape (L,)."""
        return np.arange(1, self.frames + 1, dtype=float)

    @property
    def before_times(self) -> np.ndarray:
        """``1-K1 .. 0``, shape (K1,)."""
        return np.arange(1 - self.before_deg.shape[0], 1, dtype=float)

    @property
    def after_times(self) -> np.ndarray:
        """``L+1 .. L+K2``, shape (K2,)."""
        return self.end_time + np.arange(self.after_deg.shape[0], dtype=float)

    @property
    def velocity_a(self) -> np.ndarray:
        """Clip 1's velocity at A, degrees per frame (backward difference; 0 with one
        frame), (63,)."""
        if self.before_deg.shape[0] < 2:
            return np.zeros(self.before_deg.shape[1])
        return self.before_deg[-1] - self.before_deg[-2]

    @property
    def velocity_b(self) -> np.ndarray:
        """Clip 2's velocity at B, degrees per frame (forward difference), (63,)."""
        if self.after_deg.shape[0] < 2:
            return np.zeros(self.after_deg.shape[1])
        return self.after_deg[1] - self.after_deg[0]

    def linear(self) -> np.ndarray:
        """The per-DOF linear blend from A to B over the window, (L, 63)."""
        s = self.window_times / self.end_time
        return self.a_deg + s[:, None] * (self.b_deg - self.a_deg)


@dataclass(frozen=True, eq=False)
class WindowResult:
    """A method's answer.

    Attributes
    ----------
    posture_deg : ndarray, shape (L, 63)
        The window's postures, continuous with the problem's (unwrapped) context.
    key_posture_deg : ndarray, shape (63,), or None
        The key posture, wrapped to [-180, 180), for the methods that have one.
    diagnostics : mapping of str to float
        Method-specific figures (e.g. an optimiser's iterations and objective).
    """

    posture_deg: np.ndarray
    key_posture_deg: np.ndarray | None = None
    diagnostics: Mapping[str, float] = field(default_factory=dict)


#: The roles a method can play in the study (see :class:`TransitionMethod`), in table order.
ROLES = ("recommended", "paper", "paper-comparison", "baseline", "ablation", "performed")


@dataclass(frozen=True)
class TransitionMethod:
    """A named transition method.

    Attributes
    ----------
    name : str
        Registry key (``"upm"``, ``"linear"``, ...).
    solve : callable
        ``solve(problem: WindowProblem) -> WindowResult``.
    continuity : str
        What the method promises at both window edges: ``"C0"`` (positions join) or
        ``"C1"`` (positions and velocities join).
    key_kind : str or None
        For key-posture methods, the kind of source they expect (``"upm"``, ``"som"``,
        ``"classnn"``, ``"snap"``); None if the method needs none.
    summary : str
        One line for ``--help`` and reports.
    key_source : callable or str or None
        How the method's key source is built, for key-posture methods:
        ``build(context: upm.transitions.registry.KeySourceContext) -> KeyPostureSource``,
        (its imports inside the builder, so that a method costs nothing until it is used).
    key_help : str
        What the key source is, for the error raised when it is missing.
    role : str
        What the method is in the study (one of :data:`ROLES`): ``"paper"`` (the paper's
        method), ``"paper-comparison"`` (what the paper compares it with), ``"recommended"``
        (the method the project recommends), ``"baseline"`` (another standard method),
        ``"ablation"`` (a part of a method taken away) or ``"performed"`` (the window as the
        humanoid performed another method's). Tables, figures and the studio
        read it.
    needs_map : bool
        Whether the key source is a trained posture map (``--map``; the study trains
        it), rather than nothing or something fitted on the data at once.
    finish : callable or None
        For a method whose window is made from the assembled transition:
        ``finish(transition: Transition, key_source) -> Transition``, called on the
        transition ``solve``'s window made (``performed``: what the humanoid did while
        following it). None for the others.
    """

    name: str
    solve: Callable[[WindowProblem], WindowResult]
    continuity: str
    key_kind: str | None
    summary: str
    key_source: Callable | None = None
    key_help: str = ""
    role: str = "baseline"
    needs_map: bool = False
    finish: Callable | None = None

    def __post_init__(self):
        if self.role not in ROLES:
            raise UsageError(f"method {self.name!r}: role {self.role!r} is not one of "
                             f"{', '.join(ROLES)}")

    @property
    def needs_key_source(self) -> bool:
        return self.key_kind is not None


@dataclass(frozen=True, eq=False)
class Transition:
    """The result of one transition.

    Attributes
    ----------
    motion : Motion
        Clip 1, the L window frames, then clip 2 turned about the vertical and moved to
        continue where the window ends; clip 1's skeleton and frame rate.
    window : slice
        Where the window's frames lie in ``motion``.
    method : str
    frames : int
        L.
    alpha : float
    key_posture_deg : ndarray, shape (63,), or None
        The key posture (wrapped), for the key-posture methods.
    key_time : float
        Frames after A at which the key posture sits, ``(L + 1) / 2``.
    seconds : float
        Compute time of the transition (window postures, root blend and re-anchoring of
        clip 2), without resampling and without assembling ``motion``.
    heading_turn_deg : float
        The turn about the vertical applied to clip 2 (0 if heading alignment is off).
    diagnostics : mapping of str to float
        The method's own figures plus ``root_scale`` (clip 2's root translation scale
        when it comes from another subject), ``resampled_from_fps`` (0 if not) and
        ``dropouts_filled`` (the (joint, frame) marker dropouts of both clips filled
        before the window was made, :func:`upm.motion.dropouts.fill_dropouts`).
    """

    motion: Motion
    window: slice
    method: str
    frames: int
    alpha: float
    key_posture_deg: np.ndarray | None
    key_time: float
    seconds: float
    heading_turn_deg: float
    diagnostics: Mapping[str, float]

    @property
    def window_posture_deg(self) -> np.ndarray:
        """The window's postures, (L, 63) degrees in [-180, 180)."""
        return self.motion.posture_deg[self.window]

    @property
    def window_root(self) -> np.ndarray:
        """The window's root, (L, 6): tx, ty, tz metres, rx, ry, rz degrees."""
        return self.motion.root[self.window]

    @property
    def a_index(self) -> int:
        """Index of A (clip 1's last frame) in ``motion``."""
        return self.window.start - 1

    @property
    def b_index(self) -> int:
        """Index of B (clip 2's first frame) in ``motion``."""
        return self.window.stop


def check_frames(frames) -> int:
    """The window length as an int >= 1 (UsageError otherwise)."""
    if isinstance(frames, bool) or not float(frames).is_integer() or frames < 1:
        raise UsageError(f"window length must be a whole number of frames >= 1, not {frames!r}")
    return int(frames)


def check_alpha(alpha) -> float:
    """Alpha as a float in [0, 1] (UsageError for NaN or outside)."""
    try:
        value = float(alpha)
    except (TypeError, ValueError):
        raise UsageError(f"alpha must be a number in [0, 1], not {alpha!r}") from None
    if math.isnan(value) or not 0.0 <= value <= 1.0:
        raise UsageError(f"alpha must be in [0, 1] (0 is A, 1 is B), not {alpha!r}")
    return value


def check_motion(motion: Motion, role: str) -> None:
    if not isinstance(motion, Motion):
        raise UsageError(f"{role} must be a Motion, not {type(motion).__name__}")
    if motion.n_frames < 1:
        raise UsageError(f"{role} motion {motion.name!r} has no frames")
