"""Everything ``upm eval`` writes, from a :class:`~eval.study.StudyResult`.

Deterministic (byte-identical for the same seed, whatever the number of workers):

- ``scores.csv``: every score, long-form (kind, id, window, method, metric, value: every
  pair x window x method, every real window and, of kind ``inbetween``, every window x
  length x method of the in-betweening task's LaFAN1 metrics; :class:`eval.records.Records`);
- ``results.json``: the protocol, the software versions, every metric's definition and
  unit, every test clip, every pair and real window (what they are; their scores are in
  scores.csv), and all the statistics as long-form rows (:meth:`eval.summaries.Summaries.as_json`);
  ``inbetween``: the in-betweening task's protocol, windows and figures
  (:func:`eval.inbetween_report.inbetween_document`);
- ``summary.csv`` (means and intervals), ``paired.csv`` (UPM - X), ``summary.md`` (the
  Markdown tables).

Every CSV comes from the one writer :func:`eval.records.csv_text`.

Not deterministic (timings vary by nature): ``timing.json`` and ``table4.md`` (the paper's
Table 4 on this machine). Figures (PNG): ``fig13_window_dof.png``,
``fig14_sequence_dof.png``, ``metrics.png``, ``filmstrip.png``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from controller.report import software_versions
from eval.metrics import METRICS
from eval.pairs import REAL_CONTEXT, SEGMENT_FRAMES, STUDY_FPS
from eval.realdata import FLAT_FLOOR_MAX_BW
from eval.records import COLUMNS, csv_text
from eval.scoring import RESIDUAL_CONTEXT
from eval.study import StudyResult, make_transition, pair_by_id
from upm.core.fileio import atomic_open, atomic_write_text

if TYPE_CHECKING:
    from eval.summaries import Summaries

RESULTS_FORMAT = "upm-controller/eval-results"
#: 2: scores in scores.csv (long-form), statistics as lists of rows, windows as ints.
RESULTS_VERSION = 2
#: The long-form table of every score.
SCORES_NAME = "scores.csv"
#: The window length the figures show when the study has it (the paper's).
FIGURE_WINDOW = 20


def protocol(result: StudyResult) -> dict:
    """The study's settings and rules, JSON-ready."""
    data = result.data
    maps = {kind: {"neurons": source.n_neurons()}
            for kind, source in data.sources.items() if hasattr(source, "n_neurons")}
    return {
        **result.config.as_dict(),
        "fps": STUDY_FPS,
        "segment_frames": SEGMENT_FRAMES,
        "train_subjects": result.train_subjects,
        "maps": maps,
        "rules": {
            "clips": "the test split of clips.csv, resampled to 120 fps; a clip shorter "
                     "than 200 frames gives one segment of its whole length",
            "pairs": "segment 1 (ends at A) and segment 2 (starts at B) from two different "
                     "test clips; the ordered clip pairs in seeded random rounds (each once "
                     "per round), segment starts uniform",
            "humanoid": "each pair on the model of clip 1's subject; clip 2 is put on clip "
                        "1's skeleton, its root translation scaled by the leg lengths "
                        "(upm.transitions.match_clip); every method gets the same root",
            "nearest_real_exclusion": "in each source clip, the segment, the L frames the "
                                      "window stands in for and 200 frames beyond; a real "
                                      "window excludes itself and 200 frames on each side",
            "real_windows": f"per window length, as many as pairs, clips in seeded random "
                            f"rounds, starts uniform with {REAL_CONTEXT} frames on each side",
            "seen": "both clips' subjects have a clip in the train split",
            "flat_floor": f"both clips' own frames need a median root residual force below "
                          f"{FLAT_FLOOR_MAX_BW} body weights (a flat floor like the model's)",
            "residual_context_frames": RESIDUAL_CONTEXT,
            "tracking": "root driven along the reference, servos with human torque limits, "
                        f"from {RESIDUAL_CONTEXT} frames before the window; the free-root "
                        "test (--physics) runs the balance controller through each window",
        },
    }


def results_document(result: StudyResult, statistics: Summaries,
                     inbetween: list | None = None) -> dict:
    """``results.json``: every pair and real window, where their scores are, and the
    statistics (:class:`eval.summaries.Summaries`); the in-betweening task's section
    when it ran (``inbetween``: its statistics rows)."""
    from eval.inbetween_report import inbetween_document

    document = {
        "format": RESULTS_FORMAT,
        "format_version": RESULTS_VERSION,
        "protocol": protocol(result),
        "software": software_versions(),
        "metrics": {name: spec.as_dict() for name, spec in METRICS.items()},
        "clips": result.clips,
        "pairs": result.pairs,
        "real_windows": [{"window": frames, **w} for frames, ws in result.real.items()
                         for w in ws],
        "scores": {"file": SCORES_NAME, "columns": list(COLUMNS), "rows": len(result.records)},
        "statistics": statistics.as_json(),
    }
    if result.inbetween:
        document["inbetween"] = inbetween_document(result.inbetween, inbetween)
    return document


def machine_info() -> dict:
    """The machine the timings come from, and the software (:func:`software_versions`)."""
    import os
    import platform

    from threadpoolctl import threadpool_info

    blas = sorted({int(i.get("num_threads", 0)) for i in threadpool_info()
                   if i.get("user_api") == "blas"})
    return {"platform": platform.platform(terse=True), "processor": platform.machine(),
            "cpus": os.cpu_count(), **software_versions(),
            "blas_threads": blas[0] if len(blas) == 1 else blas}


def timing_document(result: StudyResult) -> dict:
    """``timing.json``: ms per transition per method and window, spacetime / UPM, the
    machine, and every pair's figure."""
    from eval.tables import timing_summary

    summary = timing_summary(result.timing_ms)
    return {
        "note": "compute time of each transition (upm.transitions.Transition.seconds), "
                "measured while the worker processes score in parallel; varies by run",
        "machine": machine_info(),
        "workers": result.workers,
        "wall_s": round(result.wall_s, 2),
        **summary,
        "per_pair_ms": {str(k): {m: [round(x, 4) for x in v] for m, v in methods.items()}
                        for k, methods in result.timing_ms.items()},
    }


def figure_window(windows) -> int:
    """The window length the figures show: 20 frames (the paper's) when studied, else the
    first."""
    return FIGURE_WINDOW if FIGURE_WINDOW in windows else windows[0]


@dataclass(frozen=True)
class Example:
    """The pair the figures show and why.

    Attributes
    ----------
    pair_id : int
    dof : str
    frames : int
    difference_deg : float
        |UPM - linear| of that DOF at the window's middle frame.
    rule : str
    """

    pair_id: int
    dof: str
    frames: int
    difference_deg: float
    rule: str


def choose_example(result: StudyResult, frames: int) -> Example:
    """The figures' pair and DOF, by a rule (not by hand).

    For every pair, the largest |UPM - linear| over the declared DOFs at the window's
    middle frame (index L // 2); the pair is the one at the median of those (the lower
    median: a typical pair, not the most dramatic), the DOF the one where they differ
    most in it.
    """
    from upm.motion.skeleton import POSTURE_DOF_NAMES
    from upm.ops.angles import angle_diff_deg

    data = result.data
    dofs = np.flatnonzero(data.real.dofs)
    largest, which = [], []
    for record in result.pairs:
        pair = pair_by_id(result, record["id"])
        middle = frames // 2
        upm = make_transition(data, pair, "upm", frames).window_posture_deg[middle, dofs]
        lin = make_transition(data, pair, "linear", frames).window_posture_deg[middle, dofs]
        diff = np.abs(angle_diff_deg(upm, lin))
        largest.append(float(diff.max()))
        which.append(int(dofs[int(np.argmax(diff))]))
    order = np.argsort(largest, kind="stable")
    k = int(order[(len(order) - 1) // 2])
    return Example(pair_id=result.pairs[k]["id"], dof=POSTURE_DOF_NAMES[which[k]],
                   frames=frames, difference_deg=round(largest[k], 4),
                   rule="the pair at the (lower) median of the largest |UPM - linear| "
                        "over the declared DOFs at the window's middle frame; the DOF "
                        "where they differ most in it")


def write_figures(result: StudyResult, statistics: Summaries, out: Path) -> dict:
    """The figures; returns ``{name: path}`` and the example's description."""
    from eval.figures import plot_metric_chart, write_filmstrip
    from upm.transitions.dof_plot import plot_sequence_dof, plot_window_dof

    config = result.config
    frames = figure_window(config.windows)
    example = choose_example(result, frames)
    pair = pair_by_id(result, example.pair_id)
    transitions = {m: make_transition(result.data, pair, m, frames) for m in ("upm", "linear")}
    label = (f"pair {pair.index}: {pair.first.clip}@{pair.first.start}:{pair.first.stop} -> "
             f"{pair.second.clip}@{pair.second.start}:{pair.second.stop}, L = {frames}")
    paths = {
        "fig13": out / "fig13_window_dof.png",
        "fig14": out / "fig14_sequence_dof.png",
        "metrics": out / "metrics.png",
        "filmstrip": out / "filmstrip.png",
    }
    plot_window_dof(paths["fig13"], transitions, dof=example.dof,
                    title=f"{example.dof} across the window, UPM vs linear\n{label}")
    plot_sequence_dof(paths["fig14"], transitions, example.dof,
                      title=f"{example.dof} across the whole sequence, UPM vs linear\n{label}")
    plot_metric_chart(paths["metrics"], statistics, list(config.methods),
                      list(config.windows))
    write_filmstrip(paths["filmstrip"], result.data.model(pair.first.clip), transitions,
                    title=f"UPM (top) and linear (bottom): every 5th frame around the window "
                          f"(orange); {label}")
    return {"paths": {k: str(v.name) for k, v in paths.items()},
            "example": {"pair_id": example.pair_id, "dof": example.dof,
                        "window_frames": frames,
                        "middle_difference_deg": example.difference_deg,
                        "rule": example.rule}}


def write_outputs(result: StudyResult, out_dir, figures: bool = True,
                  physics=None) -> dict:
    """Write every output of the study into ``out_dir`` (created if missing), all or
    nothing: the files are made in a staging folder beside it and moved in only when every
    one of them exists, so a failure leaves ``out_dir`` as it was.

    Parameters
    ----------
    result : StudyResult
    out_dir : path-like
    figures : bool
    physics : eval.physics.PhysicsResult, optional
        The free-root test (``--physics``): adds ``physics.csv`` (long-form: kind, id,
        window, method, metric, value), its section in results.json and summary.md, and
        ``physics.png``.

    Returns
    -------
    dict
        ``files``: name -> path; ``statistics`` (:class:`eval.summaries.Summaries`);
        ``inbetween`` (the in-betweening task's statistics rows, empty if it did not
        run); ``timing``; ``figures`` (if drawn); ``physics`` (its statistics, if run).
    """
    import shutil
    import tempfile

    from eval.inbetween_report import inbetween_markdown, inbetween_statistics
    from eval.summaries import PAIRED_COLUMNS, SUMMARY_COLUMNS, summarise
    from eval.tables import summary_markdown, table4_markdown

    out = Path(out_dir)
    out.parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=f".{out.name}-incomplete-", dir=out.parent))
    try:
        config = result.config
        statistics = summarise(result.records, METRICS, result.pairs, result.real,
                               config.methods, config.windows, config.seed)
        inbetween = (inbetween_statistics(result.records, config.methods, config.seed)
                     if result.inbetween else [])
        document = results_document(result, statistics, inbetween)
        markdown = summary_markdown(document, statistics)
        if result.inbetween:
            markdown += "\n" + inbetween_markdown(inbetween, len(result.inbetween))
        names = ["results.json", SCORES_NAME, "summary.csv", "paired.csv", "summary.md",
                 "timing.json", "table4.md"]
        report = {"statistics": statistics, "inbetween": inbetween}
        if physics is not None:
            from eval.physics_report import physics_markdown, plot_physics

            document["physics"] = physics_document(physics)
            markdown += "\n" + physics_markdown(physics.statistics, config.methods,
                                                 config.windows, physics.pairs,
                                                 physics.effort)
            atomic_write_text(stage / "physics.csv", physics.records.to_csv())
            names.append("physics.csv")
            report["physics"] = physics.statistics
            if figures:
                plot_physics(stage / "physics.png", physics.statistics,
                             figure_window(config.windows), config.methods, physics.effort)
                names.append("physics.png")
        with atomic_open(stage / "results.json", "w", encoding="utf-8",
                         newline="\n") as handle:
            json.dump(document, handle, indent=1)
            handle.write("\n")
        atomic_write_text(stage / SCORES_NAME, result.records.to_csv())
        atomic_write_text(stage / "summary.csv",
                          csv_text(SUMMARY_COLUMNS, statistics.summary_rows()))
        atomic_write_text(stage / "paired.csv",
                          csv_text(PAIRED_COLUMNS, statistics.paired_rows()))
        atomic_write_text(stage / "summary.md", markdown)
        timing = timing_document(result)
        report["timing"] = timing
        atomic_write_text(stage / "timing.json", json.dumps(timing, indent=1) + "\n")
        atomic_write_text(stage / "table4.md", table4_markdown(timing))
        if figures:
            drawn = write_figures(result, statistics, stage)
            report["figures"] = drawn
            names += [*drawn["paths"].values(), "figures.json"]
            atomic_write_text(stage / "figures.json", json.dumps(drawn, indent=1) + "\n")
        out.mkdir(parents=True, exist_ok=True)
        for name in names:
            os.replace(stage / name, out / name)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    report["files"] = {name: str(out / name) for name in names}
    return report


def physics_document(physics) -> dict:
    """The free-root test in results.json: protocol, metric definitions, statistics."""
    from eval.physics import CONTEXT_S, PHYSICS_METRICS

    return {
        "protocol": {
            "pairs": physics.pairs,
            "context_s": CONTEXT_S,
            "effort": physics.effort,
            "controller": ("controller.offline.perform: free root, no external force, "
                           "position servos with each joint's strength, their targets "
                           "corrected by a sampling search over segments (the best states "
                           "kept, backtracking where all are in trouble)"
                           if physics.effort == "offline" else
                           "controller.balance.follow: free root, no external force, "
                           "whole-body inverse dynamics with floor contacts in friction "
                           "pyramids and each joint's strength"),
            "real_windows": [{"window": k, "n": len(v)}
                             for k, v in physics.real_windows.items()],
            "records": "physics.csv (kind, id, window, method, metric, value)",
            # every tuning constant of the controller (ControllerConfig.from_dict reads it)
            "controller_config": physics.controller_config.as_dict(),
        },
        "metrics": {name: {"unit": m.unit, "better": m.better,
                           "description": m.description}
                    for name, m in PHYSICS_METRICS.items()},
        "statistics": physics.statistics.as_json(),
    }
