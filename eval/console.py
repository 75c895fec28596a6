"""What ``upm eval`` prints at the end: the headline table (every method run, the means
of the headline metrics, the time per transition) with a legend, in at most
:data:`WIDTH` columns; the intervals, the other metrics and every score are in the files
it names.
"""

from __future__ import annotations

import textwrap
from typing import TYPE_CHECKING

from eval.metrics import HEADLINE, METRICS
from eval.records import REAL
from eval.tables import DISPLAY

if TYPE_CHECKING:
    from eval.summaries import Summaries

#: The terminal's width the tables fit.
WIDTH = 100
#: Short column headers of the headline metrics, and what each means (with its unit).
CONSOLE: dict[str, tuple[str, str]] = {
    "valid_pct": ("valid%", "valid frames, %"),
    "added_limit_mean_deg": ("+limit", "joint-limit excess added beyond the end postures', "
                                       "deg"),
    "self_collision_pct": ("selfcol%", "self-collision frames, %"),
    "nearest_real_mean_deg": ("nearest", "distance to the nearest real posture, deg RMS"),
    "residual_force_mean_bw": ("resid", "root residual force, body weights"),
    "jerk_rms_deg_s3": ("jerk", "joint jerk, 10^3 deg/s^3"),
    "foot_skate_mps": ("skate", "foot skating, m/s"),
    "tracking_error_deg": ("track", "servo tracking error, deg RMS"),
}
#: What the ``ms`` column is.
MS_LEGEND = ("ms: median milliseconds to compute one transition (window postures, root "
             "blend, clip 2 re-anchored; not the scoring), on this machine in this run, "
             "measured while the workers score in parallel (table4.md, timing.json)")


def _mean(metric: str, interval: dict) -> str:
    """A mean in the metric's display units (:data:`eval.tables.DISPLAY`), "-" if none."""
    if not interval["n"] or interval["mean"] is None:
        return "-"
    scale, decimals, _ = DISPLAY[metric]
    text = f"{interval['mean'] * scale:.{decimals}f}"
    return f"{0.0:.{decimals}f}" if float(text) == 0.0 else text


def _header(metric: str) -> tuple[str, str]:
    spec = METRICS[metric]
    return CONSOLE.get(metric, (spec.label, f"{spec.label}, {spec.unit}"))


def headline_rows(statistics: Summaries, timing: dict, frames: int, methods) -> list[dict]:
    """Every method run (in order) and the real windows, each with the headline metrics'
    ``{mean, lo, hi, n}`` and the median ms per transition."""
    out = []
    for name in (*methods, REAL):
        entry = {"method": name if name != REAL else "real windows"}
        for metric in HEADLINE:
            entry[metric] = statistics.interval(frames, name, metric)
        ms = timing["ms"][str(frames)].get(name) if name != REAL else None
        entry["ms_median"] = ms["median"] if ms else None
        out.append(entry)
    return out


def columns(header: list[str], rows: list[list[str]], gap: str = "  ") -> list[str]:
    """Plain-text columns: the first left-aligned, the others right-aligned."""
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]

    def line(cells):
        return gap.join(c.ljust(w) if i == 0 else c.rjust(w)
                        for i, (c, w) in enumerate(zip(cells, widths, strict=True)))

    return [line(header)] + [line(r) for r in rows]


def legend(parts: list[str], width: int = WIDTH) -> list[str]:
    """``parts`` joined by "; " and wrapped to ``width`` columns."""
    return textwrap.wrap("; ".join(parts), width=width, subsequent_indent="  ")


def headline_text(statistics: Summaries, timing: dict, frames: int, methods) -> str:
    """The headline for the terminal: every method run and the real windows x the means of
    the headline metrics and ms, then the legend; no line over :data:`WIDTH` columns."""
    rows = headline_rows(statistics, timing, frames, methods)
    header = ["method"] + [_header(m)[0] for m in HEADLINE] + ["ms"]
    cells = [[r["method"]] + [_mean(m, r[m]) for m in HEADLINE]
             + ["-" if r["ms_median"] is None else f"{r['ms_median']:.2f}"] for r in rows]
    lines = columns(header, cells)
    lines += legend([f"{_header(m)[0]}: {_header(m)[1]}" for m in HEADLINE] + [MS_LEGEND])
    return "\n".join(lines)
