"""The robustness table's figures (:mod:`eval.robustness`): per row, seed 0's run, the
offset runs' falls and when, the standing runs' error ranges, the search's work by mode,
and the report as JSON, a Markdown table and a figure."""

from __future__ import annotations

from eval.robustness import RobustnessResult, Row


def row_summary(result: RobustnessResult, row: Row, effort: str = "realtime") -> dict:
    """One row's figures in one effort: seed 0's run, the offset runs' falls and when, the
    standing runs' error ranges and the cost."""
    seeds = result.seeds if effort == "realtime" else result.offline_seeds
    exact = result.run(row, 0, effort)
    offsets = [result.run(row, s, effort) for s in range(1, seeds + 1)]
    runs = [exact, *offsets]
    up = [r for r in runs if not r["fell"]]

    def span(values):
        values = [v for v in values if v is not None]
        return [min(values), max(values)] if values else None

    return {
        "row": row.text, "label": row.label, "seconds": exact["seconds"],
        "exact": exact,
        "offset_falls": sum(bool(r["fell"]) for r in offsets),
        "offset_runs": len(offsets),
        "offset_fall_times_s": sorted(r["fall_time_s"] for r in offsets if r["fell"]),
        "falls": sum(bool(r["fell"]) for r in runs), "runs": len(runs),
        "falls_budget_spent": sum(bool(r["fell"]) and _budget_spent(r) for r in runs),
        "ends_going_down": sum(bool(r["ends_in_trouble"]) for r in up),
        "standing_error_deg_rms": span(r["error_deg_rms"] for r in up),
        "standing_body_error_mm_mean": span(r["body_error_mm_mean"] for r in up),
        # the same over the frames run in the default mode and over those the search
        # changed (missing from runs checkpointed before these figures)
        "standing_body_error_mm_mean_default_mode": span(
            r.get("body_error_mm_mean_default_mode") for r in up),
        "standing_body_error_mm_mean_search_modes": span(
            r.get("body_error_mm_mean_search_modes") for r in up),
        "search_retries": span(r["search_retries"] for r in runs),
        "search_backtracks": span(r.get("search_backtracks") for r in runs),
        "wall_s_per_sim_s": span(r["wall_s_per_sim_s"] for r in runs),
        "raw_steps_per_step": span(r["raw_steps_per_step"] for r in runs),
    }


def summed_by_mode(runs) -> dict | None:
    """:func:`eval.robustness.search_by_mode` summed over runs (None when a run lacks it,
    resumed from a checkpoint of before it was recorded: a sum over some of the runs would
    read as all)."""
    parts = [r.get("search_by_mode") for r in runs]
    if not parts or any(p is None for p in parts):
        return None
    return {key: [round(sum(column), 4) for column in zip(*(p[key] for p in parts),
                                                          strict=True)]
            for key in ("restarts", "rerun_s", "got_past")}


def _budget_spent(run: dict) -> bool:
    """Whether the search gave up on a trouble of the run with its budget spent."""
    return any(g["outcome"] == "budget spent" for g in run["search_gave_up"])


def _totals(rows: list[dict], runs) -> dict:
    return {"falls": sum(r["falls"] for r in rows),
            "runs": sum(r["runs"] for r in rows),
            "falls_budget_spent": sum(r["falls_budget_spent"] for r in rows),
            "exact_falls": sum(bool(r["exact"]["fell"]) for r in rows),
            "offset_falls": sum(r["offset_falls"] for r in rows),
            "offset_runs": sum(r["offset_runs"] for r in rows),
            "search_by_mode": summed_by_mode(runs)}


def summary(result: RobustnessResult) -> dict:
    """The study as JSON: settings, per-row figures, totals and every run. ``rows`` and
    ``totals`` are the first effort's (the real-time one if it ran), ``by_effort`` every
    effort's."""
    from controller.report import software_versions
    from eval.robustness import task_list

    by_effort = {}
    for effort in result.efforts:
        rows = [row_summary(result, row, effort) for row in result.rows]
        runs = [result.runs[u.key] for u in task_list(result.rows, result.seeds, (effort,),
                                                       result.offline_seeds)]
        by_effort[effort] = {"rows": rows, "totals": _totals(rows, runs)}
    first = by_effort[result.efforts[0]]
    return {
        "format": "upm-controller/robustness", "version": 3,
        "settings": {**result.settings.as_dict(), "offset_seeds": result.seeds,
                     "efforts": list(result.efforts),
                     "offline_offset_seeds": result.offline_seeds},
        "software": software_versions(),
        "totals": first["totals"],
        "rows": first["rows"],
        "by_effort": by_effort,
        "runs": result.runs,
    }


def _fmt_span(span, digits: int) -> str:
    if span is None:
        return "-"
    lo, hi = span
    return f"{lo:.{digits}f}" if round(lo, digits) == round(hi, digits) else \
        f"{lo:.{digits}f}-{hi:.{digits}f}"


def _exact_cell(r: dict) -> str:
    e = r["exact"]
    if e["fell"]:
        return f"falls at {e['fall_time_s']:.2f} s"
    return (f"stands, {e['error_deg_rms']:.1f} / {e['body_error_mm_mean']:.0f}"
            + (", ends going down" if e["ends_in_trouble"] else ""))


def efforts_table_markdown(report: dict) -> str:
    """The per-row table of every effort side by side (markdown): seed 0's run in each
    effort (stands, with its joint / body error in deg / mm, or falls and when), the
    offset runs' falls where there are any, and the offline search's cost."""
    s = report["settings"]
    efforts = s["efforts"]
    seeds = {"realtime": s["offset_seeds"], "offline": s.get("offline_offset_seeds", 0)}
    names = {"realtime": "real time", "offline": "offline"}
    header, rule = ["row", "s"], ["---", "---"]
    for effort in efforts:
        header.append(f"{names[effort]}, exact reference (deg / mm)")
        if seeds[effort]:
            header.append(f"{names[effort]}: falls of {seeds[effort]} offset runs")
        if effort == "offline":
            header.append("offline: wall s per simulated s")
    rule = ["---"] * len(header)
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(rule) + "|"]
    rows = {e: report["by_effort"][e]["rows"] for e in efforts}
    for i, first in enumerate(rows[efforts[0]]):
        cells = [first["label"], f"{first['seconds']:.1f}"]
        for effort in efforts:
            r = rows[effort][i]
            cells.append(_exact_cell(r))
            if seeds[effort]:
                when = ", ".join(f"{t:.2f}" for t in r["offset_fall_times_s"])
                cells.append(f"{r['offset_falls']}" + (f" ({when})" if when else ""))
            if effort == "offline":
                cells.append(_fmt_span(r["wall_s_per_sim_s"], 1))
        lines.append("| " + " | ".join(cells) + " |")
    lines.append("")
    for effort in efforts:
        t = report["by_effort"][effort]["totals"]
        n = len(rows[effort])
        lines.append(f"{names[effort].capitalize()}: {t['exact_falls']} of {n} exact "
                     f"references fall" + (f", {t['offset_falls']} of {t['offset_runs']} "
                                           "offset runs" if t["offset_runs"] else "") + ".")
    if s.get("max_s") is not None:
        lines.append(f"Each row's first {s['max_s']:g} s (`--max-s`).")
    return "\n".join(lines) + "\n"


def table_markdown(report: dict) -> str:
    """The per-row table (markdown): the real-time effort's, or every effort's side by
    side (:func:`efforts_table_markdown`) when the offline effort ran."""
    s = report["settings"]
    if s.get("efforts", ["realtime"]) != ["realtime"]:
        return efforts_table_markdown(report)
    k = s["offset_seeds"]
    lines = [
        f"| row | s | exact reference (seed 0) | falls of {k} offset runs, when (s) | "
        "the standing runs' error (deg / mm) | ends going down | search retries |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in report["rows"]:
        e = r["exact"]
        exact = (f"falls at {e['fall_time_s']:.2f} s" if e["fell"] else
                 f"stands, {e['error_deg_rms']:.1f} / {e['body_error_mm_mean']:.0f}")
        when = ", ".join(f"{t:.2f}" for t in r["offset_fall_times_s"])
        error = (f"{_fmt_span(r['standing_error_deg_rms'], 1)} / "
                 f"{_fmt_span(r['standing_body_error_mm_mean'], 0)}"
                 if r["standing_error_deg_rms"] else "-")
        lines.append(f"| {r['label']} | {r['seconds']:.1f} | {exact} | "
                     f"{r['offset_falls']}" + (f" ({when})" if when else "") + f" | {error} | "
                     f"{r['ends_going_down']} of {r['runs'] - r['falls']} | "
                     f"{_fmt_span(r['search_retries'], 0)} |")
    t = report["totals"]
    lines.append("")
    lines.append(f"Falls: {t['falls']} of {t['runs']} runs ({t['exact_falls']} of "
                 f"{len(report['rows'])} on the exact references, {t['offset_falls']} of "
                 f"{t['offset_runs']} on references moved by N(0, {s['offset_deg']:g} deg) "
                 "per joint channel)" + (", each sequence's pieces cut where the next one's "
                                         "gait phase matches (`--cut matched`)."
                                         if s.get("cut") == "matched" else ".")
                 + (f" Every joint's torque limit x {s['strength']:g} (`--strength`)."
                    if s.get("strength", 1) != 1 else ""))
    if t["falls"]:
        spent, other = t["falls_budget_spent"], t["falls"] - t["falls_budget_spent"]
        lines.append(f"Of the falls, {spent} came after the search had spent its budget (a "
                     "larger `--search-budget` may carry them)"
                     + (f", {other} with no mode left within its reach." if other else "."))
    by_mode = t.get("search_by_mode")
    if by_mode and sum(by_mode["restarts"]):
        lines += ["", *_by_mode_markdown(by_mode, s.get("controller_config"))]
    return "\n".join(lines) + "\n"


def _by_mode_markdown(by_mode: dict, controller_config: dict | None) -> list[str]:
    """The search's work by mode, every run together (markdown lines); the modes those of
    the study's ``controller_config`` (a report of before it was recorded: the default)."""
    from controller.config import DEFAULT, ControllerConfig

    config = (DEFAULT if controller_config is None
              else ControllerConfig.from_dict(controller_config, "the study's settings"))

    total_s = sum(by_mode["rerun_s"]) or 1.0
    lines = ["The search's work by the mode of the segment each restart changed (every run "
             "together; a trouble got past counts under its last restart's mode):", "",
             "| mode | placement gain | swing contacts not planned | swing clearance (m) | "
             "spine held | restarts | simulated s run again | troubles got past |",
             "|---|---|---|---|---|---|---|---|"]
    for m, mode in enumerate(config.modes):
        lines.append(f"| {m} | {config.mode_gain(mode):g} | {mode.swing_contacts_excluded} | "
                     f"{mode.swing_clearance_m:g} | {'yes' if mode.spine_held else 'no'} | "
                     f"{by_mode['restarts'][m]} | "
                     f"{by_mode['rerun_s'][m]:.1f} "
                     f"({100 * by_mode['rerun_s'][m] / total_s:.0f} %) | "
                     f"{by_mode['got_past'][m]} |")
    return lines


#: Each effort's lane in the figure: offset from the row's line, colour, exact marker.
_LANES = {"realtime": (0.0, "black", "D"), "offline": (0.22, "tab:blue", "s")}


def plot(report: dict, path) -> None:
    """Each row's length and its falls: seed 0 (a diamond) and the offset seeds (dots);
    with the offline effort, its runs on a lane of their own under the row (squares)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from upm.core.fileio import atomic_path

    efforts = report["settings"].get("efforts", ["realtime"])
    by_effort = report.get("by_effort", {"realtime": {"rows": report["rows"]}})
    rows = report["rows"]
    both = len(efforts) > 1
    fig, ax = plt.subplots(figsize=(8, (0.5 if both else 0.4) * len(rows) + 1.4))
    for effort in efforts:
        shift, colour, marker = _LANES[effort] if both else (0.0, "black", "D")
        for y, r in enumerate(by_effort[effort]["rows"]):
            y = y + shift
            ax.plot([0, r["seconds"]], [y, y], color="0.8", lw=6 if not both else 4,
                    solid_capstyle="butt")
            times = r["offset_fall_times_s"]
            ax.plot(times, [y] * len(times), "o", color="tab:red", ms=5, alpha=0.7)
            if r["exact"]["fell"]:
                ax.plot([r["exact"]["fall_time_s"]], [y], marker, color=colour, ms=6)
            ax.text(r["seconds"] + 0.1, y, f"{r['falls']}/{r['runs']}", va="center",
                    fontsize=7 if both else 8, color=colour)
    if any(by_effort[e]["rows"][i]["offset_runs"] for e in efforts for i in range(len(rows))):
        ax.plot([], [], "o", color="tab:red", ms=5, label="fall, offset reference")
    for effort in efforts:
        _, colour, marker = _LANES[effort] if both else (0.0, "black", "D")
        name = "real time" if effort == "realtime" else "offline effort"
        ax.plot([], [], marker, color=colour, ms=6, label=f"fall, exact reference ({name})"
                if both else "fall, exact reference")
    ax.set_yticks(range(len(rows)), [r["label"] for r in rows], fontsize=8)
    ax.set_ylim(len(rows) - 0.5 + (0.25 if both else 0.0), -0.5)
    ax.set_xlim(0, 1.1 * max(r["seconds"] for r in rows))
    ax.set_xlabel("time of the fall in the run, s (grey: the row's length; right: falls "
                  "of runs)")
    s = report["settings"]
    what = (f"exact reference and {s['offset_seeds']} offset ones, "
            f"N(0, {s['offset_deg']:g} deg)" if s["offset_seeds"] else "exact references")
    ax.set_title(f"Falls of the free-root character: {what}"
                 + (" (upper lane real time, lower lane the offline effort)" if both else ""),
                 fontsize=9)
    fig.legend(fontsize=8, loc="lower center", ncol=3 if both else 2, frameon=False)
    fig.tight_layout(rect=(0, 0.25 / fig.get_figheight(), 1, 1))
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
