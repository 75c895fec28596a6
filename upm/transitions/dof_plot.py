"""The paper's Fig. 13 and 14: one DOF across a transition, several methods against the
real frames around it (matplotlib, Agg backend, PNG written atomically).

Here, below every consumer, so that ``upm transition --plot``, the studio and the study's
figures (:mod:`eval.figures`) draw it with one piece of code; matplotlib is imported
only when a figure is drawn.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import numpy as np

from upm.motion.skeleton import JOINTS, POSTURE_DOF_NAMES
from upm.ops.angles import angle_diff_deg, unwrap_deg

#: The DOFs the paper's Fig. 13 is about: the right shoulder (CMU's clavicle and humerus).
SHOULDER_DOFS = tuple(n for n in POSTURE_DOF_NAMES if n.split(".")[0] in ("rclavicle", "rhumerus"))

_COLOURS = {"upm": "#c0392b", "linear": "#2c3e50", "som": "#8e44ad", "classnn": "#d35400",
            "snap": "#16a085", "slerp": "#2980b9", "inertialize": "#27ae60",
            "spacetime": "#7f8c8d"}


def _segment(transition, context: int) -> tuple[np.ndarray, np.ndarray]:
    """Frames from ``context`` before A to ``context`` after B: times (A at 0), postures
    unwrapped along time."""
    motion = transition.motion
    a = transition.a_index
    first = max(0, a - context)
    stop = min(motion.n_frames, transition.b_index + 1 + context)
    times = np.arange(first, stop) - a
    return times, unwrap_deg(motion.posture_deg[first:stop])


def choose_dof(transitions: Mapping[str, object]) -> str:
    """The right-shoulder DOF where the first two transitions differ most in the window
    (with one transition: where it moves most)."""
    items = list(transitions.values())
    indices = [POSTURE_DOF_NAMES.index(n) for n in SHOULDER_DOFS]
    first = items[0].window_posture_deg[:, indices]
    if len(items) > 1:
        second = items[1].window_posture_deg[:, indices]
        spread = np.abs(angle_diff_deg(first, second)).max(axis=0)
    else:
        spread = np.ptp(unwrap_deg(first), axis=0)
    return SHOULDER_DOFS[int(np.argmax(spread))]


def plot_window_dof(path: str | os.PathLike, transitions: Mapping[str, object],
                    dof: str | None = None, context: int = 30, title: str | None = None) -> str:
    """Plot one DOF across the transition window for several methods (paper Fig. 13).

    Parameters
    ----------
    path : path-like
        The PNG to write (atomically).
    transitions : mapping of label to Transition
        Transitions of the same clip pair and window length (e.g. ``{"upm": ...,
        "linear": ...}``); the real frames around the window are drawn from the first.
    dof : str, optional
        A posture DOF name such as ``"rhumerus.rz"`` (default: :func:`choose_dof`).
    context : int
        Real frames shown on each side of the window.
    title : str, optional

    Returns
    -------
    str
        The DOF plotted.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from upm.core.errors import UsageError
    from upm.core.fileio import atomic_open

    if not transitions:
        raise UsageError("nothing to plot: no transitions given")
    if dof is None:
        dof = choose_dof(transitions)
    if dof not in POSTURE_DOF_NAMES:
        raise UsageError(f"no DOF {dof!r} (DOFs are JOINT.rx/ry/rz, joints: {', '.join(JOINTS)})")
    column = POSTURE_DOF_NAMES.index(dof)
    reference = next(iter(transitions.values()))
    n_frames = reference.frames

    figure = Figure(figsize=(7.0, 3.6), dpi=120)
    FigureCanvasAgg(figure)
    axes = figure.add_subplot(1, 1, 1)
    axes.axvspan(0.5, n_frames + 0.5, color="#f1c40f", alpha=0.15, lw=0,
                 label=f"window ({n_frames} frames)")
    times, values = _segment(reference, context)
    offset = values[times == 0, column][0]
    real = (times <= 0) | (times >= n_frames + 1)
    curve = values[:, column]
    shown = np.where(real, curve, np.nan)
    axes.plot(times, shown, color="black", lw=2.2, label="real frames (clip 1, clip 2)")
    for label, transition in transitions.items():
        t, v = _segment(transition, context)
        y = v[:, column]
        # Same turn of the circle as the reference at A, so curves overlay.
        y = y + 360.0 * np.round((offset - y[t == 0][0]) / 360.0)
        inside = (t >= 0) & (t <= n_frames + 1)
        axes.plot(t[inside], y[inside], color=_COLOURS.get(label), lw=1.6, marker=".",
                  ms=4, label=label)
        key = transition.key_posture_deg
        if key is not None:
            key_value = y[t == 0][0] + np.mod(key[column] - y[t == 0][0] + 180.0, 360.0) - 180.0
            axes.plot([transition.key_time], [key_value], marker="D", ms=7, ls="none",
                      color=_COLOURS.get(label), markeredgecolor="black",
                      label=f"{label} key posture")
    axes.set_xlabel("frame (0 = last frame of clip 1)")
    axes.set_ylabel(f"{dof} (degrees)")
    axes.set_title(title or f"{dof} across the transition", fontsize=10)
    axes.grid(alpha=0.3)
    axes.legend(fontsize=7, loc="best")
    figure.tight_layout()
    with atomic_open(path, "wb") as handle:
        figure.savefig(handle, format="png")
    return dof


def plot_sequence_dof(path: str | os.PathLike, transitions: Mapping[str, object], dof: str,
                      title: str | None = None) -> str:
    """One DOF across the whole joined sequence (clip 1, the window, clip 2): the paper's
    Fig. 14. The same drawing as :func:`plot_window_dof` with every frame as context."""
    reference = next(iter(transitions.values()))
    context = max(reference.a_index, reference.motion.n_frames - 1 - reference.b_index)
    return plot_window_dof(path, transitions, dof=dof, context=context,
                           title=title or f"{dof} across the whole sequence")
