"""Figures of the study (matplotlib, Agg backend, PNG written atomically).

- :func:`plot_window_dof`: one DOF across a transition window, several methods side by
  side with the real frames around it — the paper's Fig. 13 (UPM vs linear); with the
  whole sequence as context, its Fig. 14 (:func:`plot_sequence_dof`).
- :func:`plot_metric_chart`: every headline metric across the methods, with the 95 %
  intervals and the real windows' value (the calibration) as a band.
- :func:`write_filmstrip`: the simulated humanoid through the same transition by several
  methods, one row each (the paper's Fig. 11/12), rendered offscreen by MuJoCo.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from upm.angles import angle_diff_deg, unwrap_deg
from upm.skeleton import JOINTS, POSTURE_DOF_NAMES

if TYPE_CHECKING:
    from eval.summaries import Summaries

#: The DOFs the paper's Fig. 13 is about: the right shoulder (CMU's clavicle and humerus).
SHOULDER_DOFS = tuple(n for n in POSTURE_DOF_NAMES if n.split(".")[0] in ("rclavicle", "rhumerus"))

#: Metrics drawn on a log scale in :func:`plot_metric_chart` (slerp's jerk runs an order of
#: magnitude above the rest where its Euler projection flips).
LOG_SCALE = frozenset({"jerk_rms_deg_s3"})

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

    from upm.errors import UsageError
    from upm.fileio import atomic_open

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


def plot_metric_chart(path: str | os.PathLike, statistics: Summaries, methods, windows,
                      metrics=None, title: str | None = None) -> None:
    """Every metric across the methods: the mean over pairs with its 95 % interval, one
    marker per window length, and the real windows' mean and interval as a dashed line
    and a band of the window's colour.

    Parameters
    ----------
    path : path-like
        The PNG to write (atomically).
    statistics : eval.summaries.Summaries
        The study's (:func:`eval.summaries.summarise`).
    methods : sequence of str
    windows : sequence of int
    metrics : sequence of str, optional
        Default: :data:`eval.metrics.HEADLINE`.
    title : str, optional
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.ticker import ScalarFormatter

    from eval.metrics import HEADLINE, METRICS
    from eval.tables import DISPLAY
    from upm.fileio import atomic_open

    metrics = list(metrics or HEADLINE)
    columns = 4
    rows = -(-len(metrics) // columns)
    figure = Figure(figsize=(4.2 * columns, 3.4 * rows), dpi=110)
    FigureCanvasAgg(figure)
    axes = figure.subplots(rows, columns, squeeze=False).ravel()
    window_colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b"]
    x = np.arange(len(methods))
    width = 0.7 / max(len(windows), 1)
    for ax, metric in zip(axes, metrics, strict=False):
        scale, _, label = DISPLAY[metric]
        for k, frames in enumerate(windows):
            colour = window_colours[k % len(window_colours)]
            ivs = [statistics.interval(frames, m, metric) for m in methods]
            mean = np.array([iv["mean"] for iv in ivs], dtype=float) * scale
            lo = np.array([iv["lo"] for iv in ivs], dtype=float) * scale
            hi = np.array([iv["hi"] for iv in ivs], dtype=float) * scale
            offset = (k - (len(windows) - 1) / 2) * width
            ax.errorbar(x + offset, mean, yerr=[mean - lo, hi - mean], fmt="o", ms=4,
                        capsize=2, color=colour, label=f"L = {frames}")
            real = statistics.interval(frames, "real", metric)
            if real["n"]:
                ax.axhline(real["mean"] * scale, color=colour, ls="--", lw=1)
                ax.axhspan(real["lo"] * scale, real["hi"] * scale, color=colour, alpha=0.08,
                           lw=0)
        if metric in LOG_SCALE:
            ax.set_yscale("log")
            ax.yaxis.set_major_formatter(ScalarFormatter())
        ax.set_xticks(x)
        ax.set_xticklabels(methods, rotation=45, ha="right", fontsize=8)
        better = "higher" if METRICS[metric].better == "higher" else "lower"
        ax.set_title(f"{label} ({better} is better)", fontsize=9)
        ax.grid(alpha=0.3, axis="y")
        for tick, name in zip(ax.get_xticklabels(), methods, strict=True):
            if name == "upm":
                tick.set_fontweight("bold")
    for ax in axes[len(metrics):]:
        ax.axis("off")
    handles, labels = axes[0].get_legend_handles_labels()
    handles.append(Line2D([], [], color="grey", ls="--"))
    labels.append("real windows (calibration), band = 95 % interval")
    figure.legend(handles, labels, loc="lower right", fontsize=8, frameon=False)
    figure.suptitle(title or "Transition methods on held-out pairs: mean and 95 % interval",
                    fontsize=11)
    figure.tight_layout(rect=(0, 0.03, 1, 0.96))
    with atomic_open(path, "wb") as handle:
        figure.savefig(handle, format="png")


def write_filmstrip(path: str | os.PathLike, model, transitions: Mapping[str, object],
                    step: int = 5, margin: int = 2, title: str | None = None):
    """The humanoid through the same transition by several methods, one row each: every
    ``step``-th frame from ``margin`` steps before the window to ``margin`` steps after it
    (the paper's Fig. 11/12), rendered offscreen (:mod:`controller.render`).

    Parameters
    ----------
    path : path-like
    model : mujoco.MjModel
        The humanoid of the transitions' skeleton.
    transitions : mapping of label to Transition
        Of the same pair and window length.
    """
    from controller.qpos import to_qpos
    from controller.render import filmstrip, filmstrip_frames

    items = list(transitions.items())
    reference = items[0][1]
    n = reference.motion.n_frames
    frames = filmstrip_frames([reference.window], n, step=step, margin=margin, limit=32)
    rows = [(label, to_qpos(model, t.motion)) for label, t in items]
    return filmstrip(model, rows, frames, path, fps=reference.motion.fps,
                     windows=[reference.window], title=title)
