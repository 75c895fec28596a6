"""Figures of the study (matplotlib, Agg backend, PNG written atomically).

- the paper's Fig. 13 and 14 (one DOF across the window, UPM vs linear) are drawn by
  :mod:`upm.transitions.dof_plot`, which the studio and ``upm transition --plot`` share;
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

if TYPE_CHECKING:
    from eval.summaries import Summaries

#: Metrics drawn on a log scale in :func:`plot_metric_chart` (slerp's jerk runs an order of
#: magnitude above the rest where its Euler projection flips).
LOG_SCALE = frozenset({"jerk_rms_deg_s3"})


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
    from upm.core.fileio import atomic_open
    from upm.transitions.registry import METHODS

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
            if name in METHODS and METHODS[name].role in ("paper", "recommended"):
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
