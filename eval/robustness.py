"""How often does the free-root character stay up? The balance controller's robustness.

A free-root run is one path of a chaotic system: whether the character falls can turn on
differences far under mocap's precision, so one run per clip says little. Here every
*row* (a clip, or clips joined by a transition method) is run on its exact reference
(offset seed 0) and on references whose joint channels are each moved by their own
constant drawn from N(0, ``offset_deg``) (:func:`upm.perturb.offset_joint_angles`, seeds
1 to K), each by the balance controller (:func:`controller.balance.follow`: root free, no
external force) from start to end. The figures per run are those of ``upm simulate
--modes free`` (:class:`controller.balance_report.BalanceTracking`); per row, how many runs
fall and when, the others' errors, and the search's retries (the controller's work, the
same on any machine). The wall time per simulated second is recorded per run, but the
runs share the machine (``workers`` at once, each on one process): ``upm simulate`` and
``upm bench`` measure the cost alone.

A unit of work is one (row, seed) (:class:`Unit`), run in a worker of :mod:`eval.executor`
(a local pool or Ray) on one process of the controller (the same run as on two: the
controller's rollouts give the same frames either way). Finished units are appended to a
checkpoint in the output directory, so a stopped run resumes where it was.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from upm.errors import UsageError

CHECKPOINT_NAME = "robustness-partial.jsonl"
CHECKPOINT_FORMAT = "upm-controller/robustness-checkpoint"
CHECKPOINT_VERSION = 2
#: The default standard deviation of the per-channel offsets, degrees.
OFFSET_DEG = 0.1
#: The default number of offset seeds (besides the exact reference).
OFFSET_SEEDS = 5


class Row(NamedTuple):
    """A clip or a sequence of clips, joined by ``method`` windows.

    Attributes
    ----------
    pieces : tuple of str
        ``CLIP`` or ``CLIP@A:B`` each.
    method : str
        The transition method between pieces (unused for one piece).
    """

    pieces: tuple[str, ...]
    method: str = "upm"

    @property
    def text(self) -> str:
        """The row as written on the command line (``A+B+C,method``)."""
        joined = "+".join(self.pieces)
        return joined if len(self.pieces) == 1 else f"{joined},{self.method}"

    @property
    def label(self) -> str:
        """The row as the tables name it."""
        joined = " -> ".join(self.pieces)
        return joined if len(self.pieces) == 1 else f"{joined} ({self.method})"


_WALK_SEQUENCE = ("02_01", "02_02", "02_01", "02_02")
#: The rows of issue 10's table: the flat-floor walks and runs of the data, and 8-12 s
#: sequences of them joined by the project's transitions.
DEFAULT_ROWS = (
    Row(("02_01",)), Row(("02_02",)), Row(("35_01",)), Row(("02_03",)), Row(("05_01",)),
    Row(("16_15",)), Row(("09_06",)),
    Row(_WALK_SEQUENCE, "upm"), Row(("16_15",) * 2, "upm"), Row(("16_15",) * 3, "upm"),
    Row(_WALK_SEQUENCE, "feasible"),
)


def parse_row(text: str) -> Row:
    """``"02_01"``, ``"02_01@0:240"`` or ``"02_01+02_02,upm"`` -> :class:`Row`.

    Pieces are joined by ``+``; a sequence may end in ``,METHOD`` (default ``upm``).

    Raises
    ------
    upm.errors.UsageError
        Naming the row, for an empty piece, an unknown method, or a malformed clip.
    """
    from upm.catalog import parse_clip_ref
    from upm.transitions import get_method

    body, _, method = text.strip().partition(",")
    method = method.strip() or "upm"
    pieces = tuple(p.strip() for p in body.split("+"))
    if not body or any(not p for p in pieces):
        raise UsageError(f"row {text!r}: write CLIP, CLIP@A:B or CLIP+CLIP+...[,METHOD]")
    try:
        for piece in pieces:
            parse_clip_ref(piece)
        get_method(method)
    except UsageError as exc:
        raise UsageError(f"row {text!r}: {exc}") from None
    return Row(pieces, method)


def parse_rows(texts, clip_names) -> list[Row]:
    """The rows of ``--rows``: each text by :func:`parse_row`, or ``["all"]``: every clip
    of ``clip_names`` (the catalog's, in its order) as a row of its own.

    Raises
    ------
    upm.errors.UsageError
        For a malformed row, ``all`` beside other rows, or a row given twice.
    """
    texts = [t.strip() for t in texts]
    if "all" in texts:
        if len(texts) > 1:
            raise UsageError("--rows all stands alone: every clip of the data, once each")
        return [Row((name,)) for name in clip_names]
    rows = [parse_row(text) for text in texts]
    if len(set(rows)) != len(rows):
        raise UsageError("--rows: a row is repeated")
    return rows


@dataclass(frozen=True)
class Settings:
    """What every run of a robustness study shares (the figures depend on these).

    Attributes
    ----------
    data_dir : str
        The CMU clips (``--data``).
    map_path : str or None
        The UPM for rows joined by ``upm`` or ``feasible``; None: trained on the train split
        (cached).
    offset_deg : float
        Standard deviation of each joint channel's offset, degrees.
    search_budget : float or None
        The balance controller's search budget (None: its default).
    cut : str
        Where a sequence's pieces but the last end: ``"whole"`` (their last frame) or
        ``"matched"`` (:func:`upm.transitions.cuts.matched_pieces`).
    strength : float
        Every joint's torque limit times this (:func:`humanoid_xml.models.load_model`).
    """

    data_dir: str
    map_path: str | None
    offset_deg: float
    search_budget: float | None
    cut: str = "whole"
    strength: float = 1.0

    def as_dict(self) -> dict:
        import hashlib
        from pathlib import Path

        the_map = "trained (train split)"
        if self.map_path:
            digest = hashlib.sha256(Path(self.map_path).read_bytes()).hexdigest()[:16]
            the_map = f"{Path(self.map_path).name} (sha256 {digest})"
        return {"data": Path(self.data_dir).name, "map": the_map,
                "offset_deg": self.offset_deg, "search_budget": self.search_budget,
                "cut": self.cut, "strength": self.strength}


class Unit(NamedTuple):
    """One run: a row on its exact reference (seed 0) or moved by offset seed ``seed``."""

    row: Row
    seed: int

    @property
    def key(self) -> str:
        return f"{self.row.text}#{self.seed}"


def task_list(rows, seeds: int) -> list[Unit]:
    """Every run: each row at seed 0 and offset seeds 1 to ``seeds``, row by row."""
    return [Unit(row, seed) for row in rows for seed in range(seeds + 1)]


#: Figures of one run (of :meth:`controller.balance_report.BalanceTracking.run_summary`).
RUN_FIELDS = ("fell", "fall_time_s", "ends_in_trouble", "error_deg_rms",
              "body_error_mm_mean", "root_drift_m", "heading_error_deg_peak",
              "search_retries", "wall_s_per_sim_s", "raw_steps_per_step",
              "search_mode_share", "body_error_mm_mean_default_mode",
              "body_error_mm_mean_search_modes")

_WORKER: dict = {}


def reference(settings: Settings, row: Row, seed: int):
    """The row's motion (offset by ``seed`` unless it is 0) and the humanoid of its first
    piece's subject: ``(model, motion)``. Sequences are cached per worker."""
    from humanoid_xml.models import catalog_model_path, load_model
    from upm.catalog import Catalog, parse_clip_ref
    from upm.perturb import offset_joint_angles
    from upm.transitions import build_sequence
    from upm.transitions.cuts import matched_pieces
    from upm.transitions.registry import KeySourceContext, build_key_source, get_method

    if _WORKER.get("settings") != settings:
        _WORKER.clear()
        _WORKER.update(settings=settings, catalog=Catalog(settings.data_dir), sequences={},
                       sources={}, models={})
    catalog = _WORKER["catalog"]
    if row not in _WORKER["sequences"]:
        refs = [parse_clip_ref(p) for p in row.pieces]
        pieces = [catalog.load_ref(ref) for ref in refs]
        if settings.cut == "matched" and len(pieces) > 1:
            pieces = matched_pieces(pieces)[0]
        source = None
        if len(pieces) > 1:
            if row.method not in _WORKER["sources"]:
                context = KeySourceContext(catalog=catalog, map_path=settings.map_path,
                                           train_maps=True)
                _WORKER["sources"][row.method] = build_key_source(get_method(row.method),
                                                                  context)
            source = _WORKER["sources"][row.method]
        sequence = build_sequence(pieces, row.method, key_source=source)
        path = catalog_model_path(catalog, refs[0].name)
        if path not in _WORKER["models"]:
            _WORKER["models"][path] = load_model(path, strength=settings.strength)
        _WORKER["sequences"][row] = (_WORKER["models"][path], sequence.motion)
    model, motion = _WORKER["sequences"][row]
    if seed:
        motion = offset_joint_angles(motion, settings.offset_deg, seed)
    return model, motion


def run_unit(settings: Settings, unit: Unit) -> dict:
    """One run (in a worker): the figures of :data:`RUN_FIELDS`, plus ``seconds`` (the
    motion's length), ``wall_s``, ``search_gave_up``: the troubles the search gave up
    on (``{"time_s", "outcome"}`` each, the outcome ``"budget spent"`` or ``"no mode
    within reach"``; :class:`controller.balance_search.SearchTrouble`), and
    ``search_by_mode``: :func:`search_by_mode` of its troubles."""
    from controller.analysis import free_run
    from controller.qpos import to_qpos
    from eval.study import single_threaded_blas

    single_threaded_blas()
    model, motion = reference(settings, unit.row, unit.seed)
    tracking = free_run(model, to_qpos(model, motion), motion.fps,
                        search_budget=settings.search_budget, processes=1)
    summary = tracking.run_summary()
    out = {k: summary[k] for k in RUN_FIELDS}
    out["search_gave_up"] = [{"time_s": trouble["time_s"], "outcome": trouble["outcome"]}
                             for trouble in summary["search_troubles"]
                             if trouble["outcome"] != "got past"]
    out["search_by_mode"] = search_by_mode(summary["search_troubles"])
    out["seconds"] = round(motion.n_frames / motion.fps, 4)
    out["wall_s"] = round(tracking.run.wall_s, 3)
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
            for k, v in out.items()}


@dataclass
class RobustnessResult:
    """A robustness study.

    Attributes
    ----------
    settings : Settings
    rows : list of Row
    seeds : int
        Offset seeds per row (besides seed 0).
    runs : dict of str to dict
        Every unit's figures by :attr:`Unit.key`.
    resumed : int
        Runs taken from an earlier run's checkpoint.
    workers : int
    executor : str
    wall_s : float
        Wall time of the runs made now.
    """

    settings: Settings
    rows: list
    seeds: int
    runs: dict
    resumed: int
    workers: int
    executor: str
    wall_s: float

    def run(self, row: Row, seed: int) -> dict:
        return self.runs[Unit(row, seed).key]


def run_robustness(settings: Settings, rows, seeds: int, out_dir, *, executor: str = "local",
                   address: str | None = None, workers: int | None = None,
                   show_progress: bool = True) -> RobustnessResult:
    """Run every row at seed 0 and offset seeds 1 to ``seeds``.

    Raises
    ------
    eval.physics.StudyIncomplete
        If runs failed: each named with its error; the finished ones stay in the
        checkpoint and the same command completes the rest.
    """
    import time

    from eval.executor import make_executor
    from eval.physics import Checkpoint, StudyIncomplete, run_checkpointed
    from eval.study import default_workers

    units = task_list(rows, seeds)
    checkpoint = Checkpoint(out_dir, settings.as_dict(), name=CHECKPOINT_NAME,
                            format_name=CHECKPOINT_FORMAT, version=CHECKPOINT_VERSION,
                            numbers=False)
    resumed = checkpoint.load()
    todo = [u for u in units if u.key not in checkpoint.done]
    workers = max(1, min(workers or default_workers(), max(1, len(todo))))
    runner = make_executor(executor, workers, address)
    start = time.perf_counter()
    failures = run_checkpointed(runner, run_unit, [(u.key, (settings, u)) for u in todo],
                                checkpoint, "free-root runs", show_progress)
    if failures:
        first, error = failures[0]
        raise StudyIncomplete(
            f"{len(failures)} of {len(units)} free-root runs failed (first: {first}: "
            f"{error}); the {len(checkpoint.done)} finished are kept in {checkpoint.path}: "
            "run the same command again to complete the rest")
    return RobustnessResult(settings=settings, rows=list(rows), seeds=seeds,
                            runs={u.key: checkpoint.done[u.key] for u in units},
                            resumed=resumed, workers=workers, executor=executor,
                            wall_s=time.perf_counter() - start)


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


def search_by_mode(troubles) -> dict:
    """Where the search's work went, by the mode of the segment each restart changed
    (:data:`controller.balance_control.MODES`): ``{"restarts", "rerun_s", "got_past"}``,
    one entry per mode each; ``got_past`` counts the troubles whose last restart (the
    change that got past) was in that mode. ``troubles``: a report's
    ``search_troubles``."""
    from controller.balance_control import MODES

    out = {"restarts": [0] * len(MODES), "rerun_s": [0.0] * len(MODES),
           "got_past": [0] * len(MODES)}
    for trouble in troubles:
        for m in range(len(MODES)):
            out["restarts"][m] += trouble["restarts_by_mode"][m]
            out["rerun_s"][m] += trouble["rerun_s_by_mode"][m]
        if trouble["outcome"] == "got past" and trouble["last_mode"] is not None:
            out["got_past"][trouble["last_mode"]] += 1
    out["rerun_s"] = [round(x, 4) for x in out["rerun_s"]]
    return out


def summed_by_mode(runs) -> dict | None:
    """:func:`search_by_mode` summed over runs (None when a run lacks it, resumed from a
    checkpoint of before it was recorded: a sum over some of the runs would read as all)."""
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
        lines += ["", *_by_mode_markdown(by_mode)]
    return "\n".join(lines) + "\n"


def _by_mode_markdown(by_mode: dict) -> list[str]:
    """The search's work by mode, every run together (markdown lines)."""
    from controller.balance_control import MODES

    total_s = sum(by_mode["rerun_s"]) or 1.0
    lines = ["The search's work by the mode of the segment each restart changed (every run "
             "together; a trouble got past counts under its last restart's mode):", "",
             "| mode | placement gain | swing contacts not planned | swing clearance (m) | "
             "spine held | restarts | simulated s run again | troubles got past |",
             "|---|---|---|---|---|---|---|---|"]
    for m, mode in enumerate(MODES):
        lines.append(f"| {m} | {mode.placement_gain:g} | {mode.swing_contacts_excluded} | "
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

    from upm.fileio import atomic_path

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
