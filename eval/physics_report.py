"""The free-root test's tables and figure (from :func:`eval.physics.physics_statistics`:
an :class:`eval.summaries.Summaries`)."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

from eval.physics import CONTEXT_S
from eval.physics_unit import PERCENT, PHYSICS_METRICS
from eval.records import REAL
from upm.transitions.registry import get_method

#: Bar colours by a method's role (:data:`upm.transitions.base.ROLES`); grey: real windows.
ROLE_COLOURS = {"real": "#7f8c8d", "paper": "#c0392b", "recommended": "#27ae60",
                "paper-comparison": "#2c3e50", "baseline": "#2c3e50", "ablation": "#95a5a6",
                "performed": "#8e44ad"}

if TYPE_CHECKING:
    from eval.summaries import Summaries

#: The columns of the Markdown and terminal tables.
TABLE_METRICS = ("fell", "ends_in_trouble", "fell_or_going_down", "joint_error_deg_rms",
                 "body_error_mm_mean", "root_drift_m", "torque_saturation_share",
                 "contact_force_peak_bw")


def _fmt(metric: str, value, signed: bool = False) -> str:
    if value is None:
        return "-"
    scale = 100.0 if metric in PERCENT else 1.0
    decimals = 0 if metric in ("body_error_mm_mean", "body_error_mm_peak") else (
        1 if metric in PERCENT or metric.endswith("_deg_rms") else 2)
    return f"{value * scale:{'+' if signed else ''}.{decimals}f}"


def cell(metric: str, iv: dict, signed: bool = False) -> str:
    """``mean [lo, hi] (n)`` in display units (percent for shares)."""
    if not iv["n"]:
        return "-"
    mean = iv.get("mean", iv.get("mean_diff"))
    return (f"{_fmt(metric, mean, signed)} [{_fmt(metric, iv['lo'], signed)}, "
            f"{_fmt(metric, iv['hi'], signed)}]")


def label(metric: str) -> str:
    return PHYSICS_METRICS[metric].label


#: The columns of the offline effort's table beside the real-time controller's: each
#: offline figure followed by the real-time controller's on the same runs.
BESIDE_METRICS = ("fell", "realtime_fell", "fell_or_going_down", "realtime_fell_or_going_down",
                  "joint_error_deg_rms", "realtime_joint_error_deg_rms")


def method_rows(statistics: Summaries, frames: int, methods, group: str = "all",
                metrics=TABLE_METRICS) -> list[list[str]]:
    """Per method (then the real windows): the cells of ``metrics``."""
    rows = []
    for name in [*methods, REAL]:
        shown = "real windows (calibration)" if name == REAL else name
        n = statistics.interval(frames, name, "fell", group)["n"]
        rows.append([f"{shown} (n={n})"] + [cell(m, statistics.interval(frames, name, m, group))
                                            for m in metrics])
    return rows


def beside_label(metric: str) -> str:
    """A column of :data:`BESIDE_METRICS`: which effort, then the figure."""
    if metric.startswith("realtime_"):
        return label(metric)
    return "offline: " + label(metric)


def _table(header, rows) -> str:
    lines = ["| " + " | ".join(header) + " |",
             "|" + "|".join(["---"] + ["---:"] * (len(header) - 1)) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


#: Who performs the motion in each effort of the free-root test, in words.
PERFORMERS = {
    "realtime": "the balance controller (controller.balance.follow: root free, no external "
                "force, each joint's strength)",
    "offline": "the offline effort (controller.offline.perform: root free, no external force, "
               "each joint's strength; a sampling search over the servos' targets, the best "
               "states kept, backtracking where all are in trouble)",
}


def physics_markdown(statistics: Summaries, methods, windows, n_pairs: int,
                     effort: str = "realtime") -> str:
    """The free-root section of summary.md (``effort``: who performed the runs)."""
    reference = statistics.reference
    parts = [
        "## Can the character perform it? The free-root test"
        + (" (offline effort)" if effort == "offline" else ""),
        "",
        f"The first {n_pairs} pairs (and as many real windows): {PERFORMERS[effort]} follows "
        f"each method's motion from {CONTEXT_S:g} s before the window to {CONTEXT_S:g} s "
        f"after it. Falls: share of runs in which the character fell (anywhere in the run); "
        f"going down: share of runs in which it did not fall but ended in trouble (the "
        f"balance search's test: pelvis or head well below the motion's, or the pelvis "
        f"tilted well beyond the motion's); "
        f"errors over the window's frames before any fall, against the method's own motion "
        f"(n: runs with such frames). Mean [95 % bootstrap interval].",
    ]
    for frames in windows:
        parts += ["", f"### Window of {frames} frames", "",
                  _table(["method"] + [label(m) for m in TABLE_METRICS],
                         method_rows(statistics, frames, methods))]
        others = statistics.compared(frames)
        if others:
            rows = []
            for other in others:
                row = [f"{reference} - {other}"]
                for metric in TABLE_METRICS:
                    c = statistics.comparison(frames, other, metric)
                    iv = {"mean_diff": c["mean_diff"], "lo": c["lo"], "hi": c["hi"],
                          "n": c["n"]}
                    row.append(f"{cell(metric, iv, signed=True)} "
                               f"({c['wins']}/{c['ties']}/{c['losses']})")
                rows.append(row)
            parts += ["", f"Paired over pairs ({reference} wins/ties/losses; lower is better "
                          f"for every column):", "",
                      _table(["comparison"] + [label(m) for m in TABLE_METRICS], rows)]
        if effort == "offline":
            parts += ["", "The real-time controller beside it, on the same runs (the offline "
                          "search starts from the real-time controller's run of each motion: "
                          "its warm start):", "",
                      _table(["method"] + [beside_label(m) for m in BESIDE_METRICS],
                             method_rows(statistics, frames, methods, metrics=BESIDE_METRICS))]
    return "\n".join(parts) + "\n"


def physics_text(statistics: Summaries, frames: int, methods,
                 effort: str = "realtime") -> str:
    """The free-root headline for the terminal (the offline effort: beside the real-time
    controller's figures on the same runs, :data:`BESIDE_METRICS`)."""
    metrics = BESIDE_METRICS if effort == "offline" else TABLE_METRICS
    header = ["method"] + [beside_label(m) if effort == "offline" else label(m)
                           for m in metrics]
    cells = method_rows(statistics, frames, methods, metrics=metrics)
    widths = [max(len(h), *(len(c[i]) for c in cells)) for i, h in enumerate(header)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) for row in cells]
    return "\n".join(lines)


def plot_physics(path: str | os.PathLike, statistics: Summaries, frames: int, methods,
                 effort: str = "realtime") -> None:
    """Falls (with the runs that end going down stacked on them), joint and body error per
    method beside the real windows (bars with 95 % intervals: of falls or going down in
    the first panel)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [*methods, REAL]

    def bars(metric):
        scale = 100.0 if metric in PERCENT else 1.0
        means, los, his = [], [], []
        for name in names:
            iv = statistics.interval(frames, name, metric)
            m = iv["mean"] if iv["mean"] is not None else float("nan")
            means.append(m * scale)
            los.append((m - (iv["lo"] if iv["lo"] is not None else m)) * scale)
            his.append(((iv["hi"] if iv["hi"] is not None else m) - m) * scale)
        return means, los, his

    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2))
    colours = [ROLE_COLOURS["real"] if n == REAL else
               ROLE_COLOURS.get(get_method(n).role, ROLE_COLOURS["baseline"]) for n in names]
    x = range(len(names))
    falls = bars("fell")[0]
    either, los, his = bars("fell_or_going_down")
    axes[0].bar(x, falls, color=colours, label="fell")
    axes[0].bar(x, [e - f for e, f in zip(either, falls, strict=True)], bottom=falls,
                color=colours, alpha=0.35, yerr=[los, his], capsize=3,
                label="ends going down")
    axes[0].set_title(label("fell_or_going_down") + " (pale: going down)")
    for ax, metric in zip(axes[1:], ("joint_error_deg_rms", "body_error_mm_mean"),
                          strict=True):
        means, los, his = bars(metric)
        ax.bar(x, means, yerr=[los, his], color=colours, capsize=3)
        ax.set_title(label(metric))
    for ax in axes:
        ax.set_xticks(x)
        ax.set_xticklabels(["real" if n == REAL else n for n in names], rotation=45,
                           ha="right")
        ax.grid(axis="y", alpha=0.3)
    performer = "the offline effort" if effort == "offline" else "the balance controller"
    fig.suptitle(f"Free-root test: {performer} performs each window "
                 f"(L = {frames}; {CONTEXT_S:g} s context each side; grey: real windows)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
