"""Sequences: several clips joined into one continuous motion, a transition between each
consecutive pair.

Pieces at different frame rates are resampled to one rate first (the first piece's, or
the one given). Pieces of different subjects are allowed: postures are joint angles, so
they carry over, but the joined motion has the first piece's skeleton — its bone lengths
— so each later piece's root translation is scaled by the ratio of leg lengths (its feet
stay near the floor, its steps match the legs; the arms' reach and the like are the first
subject's).
"""

from __future__ import annotations

from dataclasses import dataclass

from upm.core.errors import UsageError
from upm.motion.motion import Motion
from upm.motion.resample import resample
from upm.transitions.join import get_method, transition
from upm.transitions.spline import SPLINE_CONTEXT


@dataclass(frozen=True, eq=False)
class Sequence:
    """A joined sequence of clips.

    Attributes
    ----------
    motion : Motion
        One continuous motion (the first piece's skeleton, at ``fps``).
    windows : tuple of slice
        Where each transition window lies in ``motion`` (len = pieces - 1).
    pieces : tuple of slice
        Where each piece's own frames lie in ``motion``.
    seconds : tuple of float
        Compute time of each transition.
    method : str
    frames : int
    diagnostics : tuple of dict
        Each transition's diagnostics (:attr:`upm.transitions.Transition.diagnostics`).
    """

    motion: Motion
    windows: tuple[slice, ...]
    pieces: tuple[slice, ...]
    seconds: tuple[float, ...]
    method: str
    frames: int
    diagnostics: tuple[dict, ...] = ()


def build_sequence(pieces: list[Motion], method: str = "upm", frames: int = 20,
                   alpha: float = 0.5, key_source=None, *, fps: float | None = None,
                   align_heading: bool = True, context: int = SPLINE_CONTEXT) -> Sequence:
    """Join clips one after the other with transitions.

    Parameters
    ----------
    pieces : list of Motion
        At least one.
    method, frames, alpha, key_source, align_heading, context
        As in :func:`upm.transitions.transition`.
    fps : float, optional
        Frame rate of the result (default: the first piece's).

    Returns
    -------
    Sequence
    """
    get_method(method)
    pieces = list(pieces)
    if not pieces:
        raise UsageError("a sequence needs at least one clip")
    rate = float(fps) if fps is not None else pieces[0].fps
    pieces = [p if p.fps == rate else resample(p, rate) for p in pieces]
    joined = pieces[0]
    windows, spans, seconds, diagnostics = [], [slice(0, joined.n_frames)], [], []
    for piece in pieces[1:]:
        step = transition(method, joined, piece, frames, alpha, key_source,
                          align_heading=align_heading, context=context)
        windows.append(step.window)
        spans.append(slice(step.window.stop, step.motion.n_frames))
        seconds.append(step.seconds)
        diagnostics.append(dict(step.diagnostics))
        joined = step.motion
    names = "+".join(p.name for p in pieces if p.name)
    return Sequence(motion=joined.replace(name=names), windows=tuple(windows),
                    pieces=tuple(spans), seconds=tuple(seconds), method=method,
                    frames=int(frames), diagnostics=tuple(diagnostics))
