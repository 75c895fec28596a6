"""The robustness table's figures (:mod:`eval.robustness`): per row, seed 0's run, the
offset runs' falls and when, the standing runs' error ranges, the search's work by mode,
and the report as JSON, a Markdown table and a figure."""

from __future__ import annotations

from eval.robustness import RobustnessResult, Row


def row_summary(result: RobustnessResult, row: Row) -> dict:
    """One row's figures: seed 0's run, the offset runs' falls and when, the standing
    runs' error ranges and the cost."""
    exact = result.run(row, 0)
    offsets = [result.run(row, s) for s in range(1, result.seeds + 1)]
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


def summary(result: RobustnessResult) -> dict:
    """The study as JSON: settings, per-row figures, totals and every run."""
    from controller.report import software_versions

    rows = [row_summary(result, row) for row in result.rows]
    return {
        "format": "upm-controller/robustness", "version": 2,
        "settings": {**result.settings.as_dict(), "offset_seeds": result.seeds},
        "software": software_versions(),
        "totals": {"falls": sum(r["falls"] for r in rows),
                   "runs": sum(r["runs"] for r in rows),
                   "falls_budget_spent": sum(r["falls_budget_spent"] for r in rows),
                   "exact_falls": sum(bool(r["exact"]["fell"]) for r in rows),
                   "offset_falls": sum(r["offset_falls"] for r in rows),
                   "offset_runs": sum(r["offset_runs"] for r in rows),
                   "search_by_mode": summed_by_mode(result.runs.values())},
        "rows": rows,
        "runs": result.runs,
    }


def _fmt_span(span, digits: int) -> str:
    if span is None:
        return "-"
    lo, hi = span
    return f"{lo:.{digits}f}" if round(lo, digits) == round(hi, digits) else \
        f"{lo:.{digits}f}-{hi:.{digits}f}"


def table_markdown(report: dict) -> str:
    """The per-row table (markdown)."""
    s = report["settings"]
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


def plot(report: dict, path) -> None:
    """Each row's length and its falls: seed 0 (a diamond) and the offset seeds (dots)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from upm.core.fileio import atomic_path

    rows = report["rows"]
    fig, ax = plt.subplots(figsize=(8, 0.4 * len(rows) + 1.4))
    for y, r in enumerate(rows):
        ax.plot([0, r["seconds"]], [y, y], color="0.8", lw=6, solid_capstyle="butt")
        times = r["offset_fall_times_s"]
        ax.plot(times, [y] * len(times), "o", color="tab:red", ms=5, alpha=0.7)
        if r["exact"]["fell"]:
            ax.plot([r["exact"]["fall_time_s"]], [y], "D", color="black", ms=6)
        ax.text(r["seconds"] + 0.1, y, f"{r['falls']}/{r['runs']}", va="center", fontsize=8)
    ax.plot([], [], "o", color="tab:red", ms=5, label="fall, offset reference")
    ax.plot([], [], "D", color="black", ms=6, label="fall, exact reference")
    ax.set_yticks(range(len(rows)), [r["label"] for r in rows], fontsize=8)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_xlim(0, 1.1 * max(r["seconds"] for r in rows))
    ax.set_xlabel("time of the fall in the run, s (grey: the row's length; right: falls "
                  "of runs)")
    ax.set_title(f"Falls of the free-root character: exact reference and "
                 f"{report['settings']['offset_seeds']} offset ones, "
                 f"N(0, {report['settings']['offset_deg']:g} deg)", fontsize=9)
    fig.legend(fontsize=8, loc="lower center", ncol=2, frameon=False)
    fig.tight_layout(rect=(0, 0.25 / fig.get_figheight(), 1, 1))
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
