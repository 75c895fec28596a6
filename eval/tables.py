"""Tables of the study: ``summary.md`` (the Markdown tables) and ``table4.md`` (the
paper's Table 4: milliseconds per transition and the spacetime / UPM ratio); the
terminal's are in :mod:`eval.console`. The CSVs are the long-form tables themselves
(:mod:`eval.summaries`, :func:`eval.records.csv_text`).

Every table but Table 4 reads the study's :class:`eval.summaries.Summaries` (one lookup
per cell, a misspelt metric refused by name), so it is byte-identical for the same seed;
Table 4 comes from the run's timings and varies from run to run.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from eval.metrics import HEADLINE, METRICS
from eval.records import REAL
from eval.statistics import GROUPS
from upm.transitions.registry import methods_with_role

if TYPE_CHECKING:
    from eval.summaries import Summaries

#: How each metric is shown in Markdown: (scale, decimals, header).
DISPLAY: dict[str, tuple[float, int, str]] = {
    "valid_pct": (1.0, 1, "valid frames %"),
    "raw_valid_pct": (1.0, 1, "valid frames (raw limits) %"),
    "valid_added_pct": (1.0, 1, "valid frames (added only) %"),
    "added_limit_mean_deg": (1.0, 2, "added limit deg"),
    "added_limit_max_deg": (1.0, 2, "added limit max deg"),
    "self_collision_pct": (1.0, 1, "self-collision frames %"),
    "self_collision_added_pct": (1.0, 1, "self-collision added %"),
    "self_depth_max_mm": (1.0, 1, "self-contact max mm"),
    "floor_penetration_pct": (1.0, 1, "floor penetration %"),
    "beyond_asf_pct": (1.0, 1, "beyond the ASF limits %"),
    "nearest_real_mean_deg": (1.0, 2, "nearest real deg"),
    "nearest_real_max_deg": (1.0, 2, "nearest real max deg"),
    "jerk_rms_deg_s3": (1e-3, 0, "jerk 10^3 deg/s^3"),
    "foot_skate_mps": (1.0, 3, "foot skate m/s"),
    "residual_force_mean_bw": (1.0, 3, "residual force bw"),
    "residual_force_peak_bw": (1.0, 3, "residual peak bw"),
    "tracking_error_deg": (1.0, 2, "tracking error deg"),
}
#: Plain names of the groups.
GROUP_NAMES = {
    "all": "all pairs", "ab_near": "A-B near (1st tercile)", "ab_middle": "A-B middle",
    "ab_far": "A-B far (3rd tercile)", "seen": "subjects seen in training",
    "unseen": "a subject not seen", "flat_floor": "flat floor", "uneven_floor": "not flat",
}


def best_baseline(statistics: Summaries, frames: int, methods) -> str | None:
    """The baseline with the highest mean valid-frame share at window ``frames`` (ties:
    the lower mean nearest-real distance), among the methods of role ``"baseline"`` that
    were run (the ablations are not baselines: they are UPM without its map)."""
    candidates = [m for m in methods_with_role("baseline") if m in methods]
    if not candidates:
        return None
    return min(candidates, key=lambda m: (
        -statistics.interval(frames, m, "valid_pct")["mean"],
        statistics.interval(frames, m, "nearest_real_mean_deg")["mean"]))


def _num(metric: str, value, signed: bool = False) -> str:
    if value is None:
        return "-"
    scale, decimals, _ = DISPLAY[metric]
    text = f"{value * scale:{'+' if signed else ''}.{decimals}f}"
    return f"{0.0:.{decimals}f}" if float(text) == 0.0 else text


def cell(metric: str, interval: dict, signed: bool = False) -> str:
    """``mean [lo, hi]`` in the metric's display units."""
    if interval["n"] == 0:
        return "-"
    return (f"{_num(metric, interval['mean'], signed)} "
            f"[{_num(metric, interval['lo'], signed)}, {_num(metric, interval['hi'], signed)}]")


def _table(header: list[str], rows: list[list[str]], align: list[str] | None = None) -> str:
    align = align or ["l"] + ["r"] * (len(header) - 1)
    rule = ["---:" if a == "r" else "---" for a in align]
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(rule) + " |"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def method_table(statistics: Summaries, frames: int, methods, metrics, group: str = "all",
                 real_label: str = "real windows (calibration)") -> str:
    """Methods (and the real windows) x metrics: ``mean [95 % interval]``."""
    header = ["method"] + [DISPLAY[m][2] for m in metrics]
    rows = [[label] + [cell(m, statistics.interval(frames, name, m, group)) for m in metrics]
            for name, label in [*((n, n) for n in methods), (REAL, real_label)]]
    return _table(header, rows)


def _difference(c: dict) -> dict:
    return {"mean": c["mean_diff"], "lo": c["lo"], "hi": c["hi"], "n": c["n"]}


def paired_table(statistics: Summaries, frames: int, other: str, group: str = "all") -> str:
    """UPM - X per metric: mean difference [interval], wins / ties / losses."""
    rows = []
    for metric in METRICS:
        c = statistics.comparison(frames, other, metric, group)
        better = "higher" if METRICS[metric].better == "higher" else "lower"
        rows.append([DISPLAY[metric][2], better,
                     cell(metric, _difference(c), signed=True),
                     f"{c['wins']} / {c['ties']} / {c['losses']}", verdict(c, metric)])
    return _table(["metric", "better", f"UPM - {other}", "UPM wins / ties / loses", "verdict"],
                  rows, ["l", "l", "r", "r", "l"])


def verdict(comparison: dict, metric: str) -> str:
    """``UPM better`` / ``UPM worse`` when the interval of the mean difference excludes 0
    on that side, ``no difference shown`` otherwise."""
    lo, hi = comparison["lo"], comparison["hi"]
    if comparison["n"] == 0 or lo is None:
        return "-"
    sign = 1.0 if METRICS[metric].better == "higher" else -1.0
    if lo == hi == 0:
        return "identical"
    if sign * lo > 0 and sign * hi > 0:
        return "UPM better"
    if sign * lo < 0 and sign * hi < 0:
        return "UPM worse"
    return "no difference shown"


def _with_counts(metric: str, c: dict) -> str:
    return f"{cell(metric, _difference(c), signed=True)} ({c['wins']}/{c['ties']}/{c['losses']})"


def group_table(statistics: Summaries, frames: int, other: str, metrics) -> str:
    """UPM - X on some metrics in every group: ``diff [interval] (W/T/L)``."""
    counts = statistics.groups["pairs"]
    rows = []
    for group in GROUPS:
        row = [f"{GROUP_NAMES[group]} (n={counts[group]})"]
        for metric in metrics:
            c = statistics.comparison(frames, other, metric, group)
            row.append("-" if c["n"] == 0 else _with_counts(metric, c))
        rows.append(row)
    return _table(["pairs"] + [DISPLAY[m][2] for m in metrics], rows)


def versus_table(statistics: Summaries, frames: int, others, metrics) -> str:
    """UPM - X for several X on some metrics: ``diff [interval] (W/T/L)``."""
    rows = [[f"UPM - {other}"] + [_with_counts(m, statistics.comparison(frames, other, m))
                                  for m in metrics] for other in others]
    return _table(["comparison"] + [DISPLAY[m][2] for m in metrics], rows)


def calibration_table(statistics: Summaries, frames: int, clips: dict) -> str:
    """Real windows per test clip: the mean of each headline metric."""
    rows = []
    for clip in statistics.clips(frames):
        info = clips.get(clip, {})
        rows.append([clip, str(statistics.clip_windows[(frames, clip)]),
                     "yes" if info.get("flat_floor") else "no",
                     "yes" if info.get("seen") else "no"]
                    + [_num(m, statistics.clip_mean(frames, clip, m)) for m in HEADLINE])
    return _table(["clip", "windows", "flat floor", "subject seen"]
                  + [DISPLAY[m][2] for m in HEADLINE], rows)


def summary_markdown(result_meta: dict, statistics: Summaries) -> str:
    """The study's tables as Markdown.

    Parameters
    ----------
    result_meta : dict
        ``protocol`` (from results.json) and ``clips``.
    statistics : eval.summaries.Summaries
        The study's (:func:`eval.summaries.summarise`).
    """
    protocol = result_meta["protocol"]
    clips = result_meta["clips"]
    methods = protocol["methods"]
    others = [m for m in methods if m != "upm"]
    secondary = [m for m in METRICS if m not in HEADLINE]
    parts = [
        "# UPM transition study: held-out results",
        "",
        f"{protocol['pairs']} transition pairs between {protocol['segment_frames']}-frame "
        f"segments of two different test clips ({', '.join(clips)}), at "
        f"{protocol['fps']:g} fps, windows of {', '.join(map(str, protocol['windows']))} "
        f"frames, seed {protocol['seed']}; maps trained on the train split. Every cell is "
        f"the mean over pairs with its 95 % percentile bootstrap interval "
        f"({statistics.settings['resamples']} resamples). The calibration row scores "
        f"real windows of the test clips exactly as a transition's window. Units and "
        f"definitions: results.json (`metrics`).",
    ]
    ends = statistics.groups["end_self_collision"]
    parts += [
        "",
        "Reading these tables:",
        "",
        "- Every method gets the same root (the velocity blend of upm.transitions.root): the "
        "differences in residual force and foot skating between methods come from the joint "
        "angles alone; their level is set mostly by that shared root and by the data (see "
        "the calibration rows).",
        "- Valid frames (the calibrated verdict, `upm calibrate`): an excess beyond the human "
        "range of motion counts only where it is beyond what the two end postures already "
        "have; a self-contact counts where it is deeper than its body pair's soft-tissue "
        "allowance, a geom under the floor where it is deeper than its class allows. The "
        "frames beyond the ASF's declared limits are reported apart, not judged. Clip 2's "
        "first posture B on "
        f"clip 1's body is itself in self-collision in {ends['B']} of {protocol['pairs']} "
        f"pairs (A in {ends['A']}): 'valid (added only)' also counts only self-collisions "
        "between body pairs in contact at neither end.",
        "- Linear and slerp stay between A and B on every DOF, so they add an excess of a "
        "per-DOF range only where the short way round crosses a DOF's excluded arc, and of a "
        "coupled rule (the hips' and shoulders') where the blend of two admissible postures "
        "is not; a window that moves through a key posture, as real motion does, can add "
        "more.",
        "- Jerk: third differences at 120 fps amplify the capture noise, so real windows "
        "score above any smooth window; the metric ranks methods against each other (a C0 "
        "join shows as a velocity jump).",
        "- Residual force: read it on the flat-floor pairs; on the other clips the real data "
        "alone needs about one body weight (the model's floor is flat).",
        "- Foot skating uses the height threshold only: a swing foot skimming the floor "
        "below 5 cm counts too, so real walks score well above zero; compare methods with "
        "each other and with the calibration row.",
        "- Tracking error: the humanoid's servos (human torque limits) follow the motion with "
        "the root driven along it. With the root free, the humanoid performs "
        "the window in the free-root test (`upm eval --physics`, its own section).",
    ]
    for frames in protocol["windows"]:
        best = best_baseline(statistics, frames, methods)
        parts += [
            "",
            f"## Window of {frames} frames ({frames / protocol['fps'] * 1000:.0f} ms)",
            "",
            "### Every method, headline metrics",
            "",
            method_table(statistics, frames, methods, HEADLINE),
            "",
            "### Every method, the other metrics",
            "",
            method_table(statistics, frames, methods, secondary),
            "",
            "### Residual force on flat-floor pairs only",
            "",
            f"Pairs whose two clips are flat-floor (n = "
            f"{statistics.groups['pairs']['flat_floor']}); real windows of flat-floor clips.",
            "",
            method_table(statistics, frames, methods,
                         ["residual_force_mean_bw", "residual_force_peak_bw"],
                         group="flat_floor"),
        ]
        if "upm" in methods and "linear" in methods:
            parts += [
                "",
                "### UPM - linear, paired over pairs",
                "",
                "A tie is an equal value (e.g. both windows fully valid). Verdict: the 95 % "
                "interval of the mean difference excludes 0.",
                "",
                paired_table(statistics, frames, "linear"),
                "",
                "### UPM - linear by group (difference [interval] (UPM wins/ties/losses))",
                "",
                f"A-B distance terciles cut at {statistics.groups['ab_tercile_edges_deg']} "
                "deg RMS.",
                "",
                group_table(statistics, frames, "linear", HEADLINE),
            ]
        if "upm" in methods and others:
            parts += [
                "",
                "### UPM - every other method (all pairs)",
                "",
                versus_table(statistics, frames, others, HEADLINE),
            ]
        if "upm" not in methods:
            parts += ["", "No paired tables: they compare every method with upm, which this "
                          "run did not include."]
        elif "linear" not in methods:
            parts += ["", "No UPM - linear tables: this run did not include linear."]
        if best is not None:
            baselines = ", ".join(methods_with_role("baseline"))
            parts += ["", f"Best other baseline at this window (highest valid share among "
                          f"{baselines}): **{best}**."]
        parts += [
            "",
            "### Calibration: real windows per test clip (means)",
            "",
            calibration_table(statistics, frames, clips),
        ]
    return "\n".join(parts) + "\n"


def timing_summary(timing_ms: dict) -> dict:
    """Per window and method: median, mean and 90th percentile of the milliseconds per
    transition, and spacetime / UPM (ratio of medians)."""
    out = {"ms": {}, "spacetime_over_upm": {}}
    for frames, methods in timing_ms.items():
        key = str(frames)
        out["ms"][key] = {m: {"median": round(float(np.median(v)), 4),
                              "mean": round(float(np.mean(v)), 4),
                              "p90": round(float(np.percentile(v, 90)), 4), "n": len(v)}
                          for m, v in methods.items()}
        if "spacetime" in methods and "upm" in methods:
            out["spacetime_over_upm"][key] = round(
                float(np.median(methods["spacetime"]) / np.median(methods["upm"])), 2)
    return out


def table4_markdown(timing: dict) -> str:
    """The paper's Table 4 on this machine: ms per transition per method and window."""
    windows = list(timing["ms"])
    methods = list(next(iter(timing["ms"].values())))
    header = ["method"] + [f"ms, L = {w} (median [p90])" for w in windows]
    rows = [[m] + [f"{timing['ms'][w][m]['median']:.2f} [{timing['ms'][w][m]['p90']:.2f}]"
                   for w in windows] for m in methods]
    if timing["spacetime_over_upm"]:
        rows.append(["**spacetime / UPM**"] + [f"**{timing['spacetime_over_upm'][w]:.1f}x**"
                                               for w in windows])
    machine = timing["machine"]
    return "\n".join([
        "# Table 4: time per transition",
        "",
        "Milliseconds to compute one transition (window postures, root blend, re-anchoring "
        "clip 2; not the scoring), median over the pairs of this run with the 90th "
        "percentile. The paper's Table 4: spacetime 72 s vs UPM 1-2 s (36-72x).",
        "",
        _table(header, rows),
        "",
        f"Machine: {machine['platform']}, {machine['cpus']} CPUs ({machine['processor']}), "
        f"Python {machine['python']}, numpy {machine['numpy']}, scipy {machine['scipy']}, "
        f"MuJoCo {machine['mujoco']}; "
        f"BLAS threads per process: {machine['blas_threads']}; {timing['workers']} worker "
        f"processes scoring in parallel (the timings include that load). Study wall time "
        f"{timing['wall_s']:.0f} s (loading or training the maps, and the scoring; not the "
        f"figures).",
        "",
    ])
