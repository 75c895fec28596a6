"""The in-betweening task's figures (:mod:`eval.inbetween`) as statistics, Markdown, a
terminal table and a section of ``results.json``.

Per protocol length and method (the study's methods, then the baselines): L2Q and L2P as
means over windows with their 95 % percentile bootstrap intervals
(:func:`eval.statistics.bootstrap_mean`), NPSS as the protocol pools it (one
power-weighted average over windows and features, :func:`eval.lafan.pooled_npss`) with
the bootstrap interval of that ratio, and the mean target miss.
"""

from __future__ import annotations

import numpy as np

from eval.inbetween import INBETWEEN, INBETWEEN_METRICS, STEP
from eval.lafan import BASELINES, LAFAN_FPS, LAFAN_LENGTHS, PAST_FRAMES, pooled_npss
from eval.statistics import CONFIDENCE, RESAMPLES, bootstrap_mean, resample_indices, round6

#: What the tables show, in order: (figure, header, decimals).
COLUMNS = (("l2q", "L2Q", 2), ("l2p", "L2P", 2), ("npss", "NPSS", 4))
#: The published LaFAN1 figures of the protocol's baselines (the official repository's
#: evaluate_test.py and README, 2232 test windows of subject 5): for the kind of value.
PUBLISHED = {
    "zerovel": {"l2q": (0.56, 1.10, 1.51), "l2p": (1.52, 3.69, 6.60),
                "npss": (0.0053, 0.0522, 0.2318)},
    "interp": {"l2q": (0.22, 0.62, 0.98), "l2p": (0.37, 1.25, 2.32),
               "npss": (0.0023, 0.0391, 0.2013)},
}


def pooled_interval(values, powers, seed: int) -> dict:
    """The pooled NPSS and the percentile bootstrap interval of that ratio over windows."""
    v, w = np.asarray(values, dtype=float), np.asarray(powers, dtype=float)
    if v.size == 0:
        return {"mean": None, "lo": None, "hi": None, "n": 0}
    index = resample_indices(v.size, seed, RESAMPLES)
    ratios = (v[index] * w[index]).sum(axis=1) / w[index].sum(axis=1)
    tail = 100.0 * (1.0 - CONFIDENCE) / 2.0
    lo, hi = np.percentile(ratios, [tail, 100.0 - tail])
    return {"mean": round6(pooled_npss(v, w)), "lo": round6(lo), "hi": round6(hi),
            "n": int(v.size)}


def inbetween_statistics(records, methods, seed: int) -> list[dict]:
    """Long-form rows: ``length``, ``method``, ``metric`` (l2q, l2p, npss, target_miss_m),
    ``mean``, ``lo``, ``hi``, ``n``; the methods run, then the baselines."""
    rows = []
    for length in LAFAN_LENGTHS:
        for method in (*methods, *BASELINES):
            ids = records.ids(INBETWEEN, length, method)
            if not ids:
                continue
            for metric in ("l2q", "l2p", "target_miss_m"):
                values = records.values(INBETWEEN, length, method, metric, ids)
                rows.append({"length": length, "method": method, "metric": metric,
                             **bootstrap_mean(values, seed).as_dict()})
            npss = pooled_interval(records.values(INBETWEEN, length, method, "npss", ids),
                                   records.values(INBETWEEN, length, method, "npss_power",
                                                  ids), seed)
            rows.append({"length": length, "method": method, "metric": "npss", **npss})
    return rows


def _lookup(rows: list[dict]) -> dict:
    return {(r["length"], r["method"], r["metric"]): r for r in rows}


def _methods(rows: list[dict]) -> list[str]:
    return list(dict.fromkeys(r["method"] for r in rows))


def _value(row: dict | None, decimals: int) -> str:
    return "-" if row is None or row["mean"] is None else f"{row['mean']:.{decimals}f}"


def inbetween_text(rows: list[dict]) -> str:
    """The figures as a terminal table (at most 100 columns): one line per method, the
    means of L2Q, L2P and NPSS at each length."""
    table = _lookup(rows)
    header = ["method"] + [f"{label}@{n}" for _, label, _ in COLUMNS for n in LAFAN_LENGTHS]
    cells = [[m] + [_value(table.get((n, m, metric)), decimals)
                    for metric, _, decimals in COLUMNS for n in LAFAN_LENGTHS]
             for m in _methods(rows)]
    widths = [max(len(h), *(len(c[i]) for c in cells)) for i, h in enumerate(header)]
    lines = [" ".join(h.rjust(w) if i else h.ljust(w)
                      for i, (h, w) in enumerate(zip(header, widths, strict=True)))]
    lines += [" ".join(c.rjust(w) if i else c.ljust(w)
                       for i, (c, w) in enumerate(zip(row, widths, strict=True)))
              for row in cells]
    return "\n".join(lines)


def _cell(row: dict | None, decimals: int) -> str:
    if row is None or row["mean"] is None:
        return "-"
    return (f"{row['mean']:.{decimals}f} [{row['lo']:.{decimals}f}, "
            f"{row['hi']:.{decimals}f}]")


def inbetween_markdown(rows: list[dict], windows: int) -> str:
    """The section of ``summary.md``: one table per figure, methods x lengths."""
    table = _lookup(rows)
    methods = _methods(rows)
    parts = [
        "## In-betweening: the LaFAN1 metrics (Harvey et al. 2020)",
        "",
        f"{windows} held-out windows of the test clips; each method fills the protocol's "
        f"transitions of {', '.join(map(str, LAFAN_LENGTHS))} frames at 30 fps from the "
        f"{PAST_FRAMES} frames before and the target after, and is scored against the "
        "recorded frames. zerovel and interp are the protocol's baselines (the last "
        "context frame held; LERP root and SLERP joints to the target). L2Q, L2P: mean "
        "[95 % bootstrap interval] over windows; NPSS pooled as the protocol does. The data "
        "are CMU clips, not LaFAN1's: the figures are comparable in kind, not in value. "
        "Definitions: results.json (`inbetween`); docs/results/lafan-metrics.md.",
    ]
    for metric, label, decimals in (*COLUMNS, ("target_miss_m", "target miss m", 3)):
        header = ["method"] + [f"{label}, {n} frames" for n in LAFAN_LENGTHS]
        body = [[m] + [_cell(table.get((n, m, metric)), decimals) for n in LAFAN_LENGTHS]
                for m in methods]
        parts += ["", f"### {label}", "", _markdown_table(header, body)]
    published = [[f"{m} (LaFAN1, published)"]
                 + [f"{PUBLISHED[m][metric][i]:.{decimals}f}"
                    for metric, _, decimals in COLUMNS for i in range(len(LAFAN_LENGTHS))]
                 for m in PUBLISHED]
    ours = [[m] + [_value(table.get((n, m, metric)), decimals)
                   for metric, _, decimals in COLUMNS for n in LAFAN_LENGTHS]
            for m in PUBLISHED if any(r["method"] == m for r in rows)]
    header = ["baseline"] + [f"{label}@{n}" for _, label, _ in COLUMNS for n in LAFAN_LENGTHS]
    parts += ["", "### The baselines here and on LaFAN1", "",
              _markdown_table(header, ours + published)]
    return "\n".join(parts) + "\n"


def _markdown_table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |",
             "| " + " | ".join(["---"] + ["---:"] * (len(header) - 1)) + " |"]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def inbetween_document(windows, rows: list[dict]) -> dict:
    """The ``inbetween`` section of ``results.json``: the protocol, the definitions, the
    windows and the statistics."""
    return {
        "protocol": {
            "source": "Harvey et al. 2020, Robust Motion In-betweening (LaFAN1 benchmark: "
                      "github.com/ubisoft/ubisoft-laforge-animation-dataset)",
            "lengths_frames_30fps": list(LAFAN_LENGTHS),
            "fps": LAFAN_FPS,
            "past_frames": PAST_FRAMES,
            "frames": f"the test clips at 120 fps read every {STEP}th frame through the "
                      "last context frame: the methods run at 30 fps on recorded frames",
            "target": "the frame (length + 1) / 30 s after the last context frame; clip 2 "
                      "is not turned (align_heading=False) but moved to where the shared "
                      "root velocity blend ends (target_miss_m)",
            "normalisation": "L2P: per joint and coordinate, the standard deviation of "
                             "the global positions over 50-frame windows every 20 frames "
                             "(30 fps) of the train split, each centred and turned",
            "frame_of_reference": "every window turned about the vertical so the root "
                                  "faces heading 0 at the last context frame",
            "joints": "the root and the distal ends (positions) and rotations of the 21 "
                      "posture joints' bones: 22",
            "baselines": {"zerovel": "the last context frame held",
                          "interp": "root position LERP, every joint's rotation (the "
                                    "root's included) SLERP, last context frame to target"},
            "data": "CMU clips, not LaFAN1: comparable in kind, not in value",
            "rows": "scores.csv rows of kind 'inbetween': window = the length (30 fps "
                    "frames), method, metric",
        },
        "metrics": {name: spec.as_dict() for name, spec in INBETWEEN_METRICS.items()},
        "windows": [{"id": w.index, "clip": w.clip, "last_context_frame": w.start - 1,
                     "target_frames": {str(n): w.start - 1 + STEP * (n + 1)
                                       for n in LAFAN_LENGTHS}} for w in windows],
        "statistics": rows,
        "published_lafan1_baselines": PUBLISHED,
    }

