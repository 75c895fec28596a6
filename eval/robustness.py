"""How often does the free-root character stay up? The balance controller's robustness.

A free-root run is one path of a chaotic system: whether the character falls can turn on
differences far under mocap's precision, so one run per clip says little. Here every
*row* (a clip, or clips joined by a transition method) is run on its exact reference
(offset seed 0) and on references whose joint channels are each moved by their own
constant drawn from N(0, ``offset_deg``) (:func:`upm.motion.perturb.offset_joint_angles`, seeds
1 to K), each by the balance controller (:func:`controller.balance.follow`: root free, no
external force) from start to end. The figures per run are those of ``upm simulate
--modes free`` (:class:`controller.balance.report.BalanceTracking`); per row, how many runs
fall and when, the others' errors, and the search's retries (the controller's work, the
same on any machine). The wall time per simulated second is recorded per run, but the
runs share the machine (``workers`` at once, each on one process): ``upm simulate`` and
``upm bench`` measure the cost alone.

The rows can be performed in the offline effort too (``efforts``: the sampling search of
:func:`controller.offline.perform`, each run on ``offline.threads`` threads), on the exact
reference and ``offline_seeds`` offset ones, with the same figures by name; ``max_s``
keeps each row's first seconds in both efforts (the offline effort costs tens of wall s
per simulated s).

A unit of work is one (row, seed, effort) (:class:`Unit`), run in a worker of
:mod:`eval.executor` (a local pool or Ray) on one process of the controller (the same run
as on two: the controller's rollouts give the same frames either way). Finished units are
appended to a checkpoint in the output directory, so a stopped run resumes where it was.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from controller.config import DEFAULT, ControllerConfig
from upm.core.errors import UsageError

CHECKPOINT_NAME = "robustness-partial.jsonl"
CHECKPOINT_FORMAT = "upm-controller/robustness-checkpoint"
CHECKPOINT_VERSION = 2
#: The default standard deviation of the per-channel offsets, degrees.
OFFSET_DEG = 0.1
#: The default number of offset seeds (besides the exact reference).
OFFSET_SEEDS = 5
#: Who performs the rows: the real-time balance controller, the offline effort's search.
EFFORTS = ("realtime", "offline")


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
    upm.core.errors.UsageError
        Naming the row, for an empty piece, an unknown method, or a malformed clip.
    """
    from upm.motion.catalog import parse_clip_ref
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
    upm.core.errors.UsageError
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
    controller_config : controller.config.ControllerConfig
        The balance controller's tuning constants (its search's budget among them): they
        travel with every unit to its worker, and a checkpoint made with another
        configuration is not reused.
    cut : str
        Where a sequence's pieces but the last end: ``"whole"`` (their last frame) or
        ``"matched"`` (:func:`upm.transitions.cuts.matched_pieces`).
    strength : float
        Every joint's torque limit times this (:func:`humanoid_xml.models.load_model`).
    max_s : float or None
        Each row's first ``max_s`` seconds only (None: whole).
    """

    data_dir: str
    map_path: str | None
    offset_deg: float
    controller_config: ControllerConfig = DEFAULT
    cut: str = "whole"
    strength: float = 1.0
    max_s: float | None = None

    def as_dict(self) -> dict:
        import hashlib
        from pathlib import Path

        the_map = "trained (train split)"
        if self.map_path:
            digest = hashlib.sha256(Path(self.map_path).read_bytes()).hexdigest()[:16]
            the_map = f"{Path(self.map_path).name} (sha256 {digest})"
        return {"data": Path(self.data_dir).name, "map": the_map,
                "offset_deg": self.offset_deg, "cut": self.cut, "strength": self.strength,
                "max_s": self.max_s, "controller_config": self.controller_config.as_dict()}


class Unit(NamedTuple):
    """One run: a row on its exact reference (seed 0) or moved by offset seed ``seed``,
    performed in ``effort`` (:data:`EFFORTS`)."""

    row: Row
    seed: int
    effort: str = "realtime"

    @property
    def key(self) -> str:
        key = f"{self.row.text}#{self.seed}"
        return key if self.effort == "realtime" else f"{key}@{self.effort}"


def task_list(rows, seeds: int, efforts=("realtime",), offline_seeds: int = 0) -> list[Unit]:
    """Every run: each row at seed 0 and offset seeds 1 to ``seeds`` in the real-time
    effort, row by row, then (if ``"offline"`` is in ``efforts``) at seed 0 and offset
    seeds 1 to ``offline_seeds`` in the offline effort."""
    units = []
    for effort, last in (("realtime", seeds), ("offline", offline_seeds)):
        if effort in efforts:
            units += [Unit(row, seed, effort) for row in rows for seed in range(last + 1)]
    return units


#: Figures of one run (of :meth:`controller.balance.report.BalanceTracking.run_summary`).
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
    from upm.motion.catalog import Catalog, parse_clip_ref
    from upm.motion.perturb import offset_joint_angles
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
    if settings.max_s is not None:
        motion = motion.frames(0, min(motion.n_frames,
                                      int(round(settings.max_s * motion.fps)) + 1))
    if seed:
        motion = offset_joint_angles(motion, settings.offset_deg, seed)
    return model, motion


def search_by_mode(troubles, n_modes: int = len(DEFAULT.modes)) -> dict:
    """Where the search's work went, by the mode of the segment each restart changed
    (one of the configuration's ``n_modes`` modes): ``{"restarts", "rerun_s",
    "got_past"}``, one entry per mode each; ``got_past`` counts the troubles whose last
    restart (the change that got past) was in that mode. ``troubles``: a report's
    ``search_troubles``."""
    out = {"restarts": [0] * n_modes, "rerun_s": [0.0] * n_modes, "got_past": [0] * n_modes}
    for trouble in troubles:
        for m in range(n_modes):
            out["restarts"][m] += trouble["restarts_by_mode"][m]
            out["rerun_s"][m] += trouble["rerun_s_by_mode"][m]
        if trouble["outcome"] == "got past" and trouble["last_mode"] is not None:
            out["got_past"][trouble["last_mode"]] += 1
    out["rerun_s"] = [round(x, 4) for x in out["rerun_s"]]
    return out


def run_unit(settings: Settings, unit: Unit) -> dict:
    """One run (in a worker): the figures of :data:`RUN_FIELDS`, plus ``seconds`` (the
    motion's length), ``wall_s``, ``search_gave_up``: the troubles the search gave up
    on (``{"time_s", "outcome"}`` each, the outcome ``"budget spent"`` or ``"no mode
    within reach"``; :class:`controller.balance.search.SearchTrouble`), and
    ``search_by_mode``: :func:`search_by_mode` of its troubles. A run of the offline
    effort (:func:`eval.robustness_offline.offline_figures`) has the same figures where
    they exist in it."""
    from controller.analysis import free_run
    from controller.qpos import to_qpos
    from eval.runs import single_threaded_blas

    single_threaded_blas()
    model, motion = reference(settings, unit.row, unit.seed)
    config = settings.controller_config
    qpos = to_qpos(model, motion)
    if unit.effort == "offline":
        from eval.robustness_offline import offline_figures
        out = offline_figures(model, qpos, motion.fps, config, RUN_FIELDS)
    else:
        tracking = free_run(model, qpos, motion.fps, processes=1, config=config)
        summary = tracking.run_summary()
        out = {k: summary[k] for k in RUN_FIELDS}
        out["search_gave_up"] = [{"time_s": trouble["time_s"], "outcome": trouble["outcome"]}
                                 for trouble in summary["search_troubles"]
                                 if trouble["outcome"] != "got past"]
        out["search_by_mode"] = search_by_mode(summary["search_troubles"],
                                               len(config.modes))
        out["wall_s"] = round(tracking.run.wall_s, 3)
    out["seconds"] = round(motion.n_frames / motion.fps, 4)
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
    efforts : tuple of str
        The efforts the rows were performed in (:data:`EFFORTS`).
    offline_seeds : int
        Offset seeds per row of the offline effort.
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
    efforts: tuple = ("realtime",)
    offline_seeds: int = 0

    def run(self, row: Row, seed: int, effort: str = "realtime") -> dict:
        return self.runs[Unit(row, seed, effort).key]


def run_robustness(settings: Settings, rows, seeds: int, out_dir, *, executor: str = "local",
                   address: str | None = None, workers: int | None = None,
                   show_progress: bool = True, efforts=("realtime",),
                   offline_seeds: int = 0) -> RobustnessResult:
    """Run every row at seed 0 and offset seeds 1 to ``seeds`` in the real-time effort,
    and at seed 0 and offset seeds 1 to ``offline_seeds`` in the offline effort, as
    ``efforts`` says (the real-time runs first; the offline ones on ``workers`` divided
    by the configuration's ``offline.threads``).

    Raises
    ------
    eval.physics.StudyIncomplete
        If runs failed: each named with its error; the finished ones stay in the
        checkpoint and the same command completes the rest.
    """
    import time

    from eval.executor import make_executor
    from eval.runs import Checkpoint, StudyIncomplete, default_workers, run_checkpointed

    efforts = tuple(e for e in EFFORTS if e in efforts)
    if not efforts:
        raise ValueError(f"no effort to run (efforts: {', '.join(EFFORTS)})")
    units = task_list(rows, seeds, efforts, offline_seeds)
    checkpoint = Checkpoint(out_dir, settings.as_dict(), name=CHECKPOINT_NAME,
                            format_name=CHECKPOINT_FORMAT, version=CHECKPOINT_VERSION,
                            numbers=False)
    resumed = checkpoint.load()
    cores = workers or default_workers()
    start = time.perf_counter()
    failures, used = [], 1
    for effort in efforts:
        todo = [u for u in units if u.effort == effort and u.key not in checkpoint.done]
        if not todo:
            continue
        threads = settings.controller_config.offline.threads if effort == "offline" else 1
        count = max(1, min(cores // threads if workers is None else cores, len(todo)))
        used = max(used, count)
        runner = make_executor(executor, count, address)
        failures += run_checkpointed(
            runner, run_unit, [(u.key, (settings, u)) for u in todo], checkpoint,
            "free-root runs" if effort == "realtime" else "offline-effort runs",
            show_progress)
    if failures:
        first, error = failures[0]
        raise StudyIncomplete(
            f"{len(failures)} of {len(units)} free-root runs failed (first: {first}: "
            f"{error}); the {len(checkpoint.done)} finished are kept in {checkpoint.path}: "
            "run the same command again to complete the rest")
    return RobustnessResult(settings=settings, rows=list(rows), seeds=seeds,
                            runs={u.key: checkpoint.done[u.key] for u in units},
                            resumed=resumed, workers=used, executor=executor,
                            wall_s=time.perf_counter() - start, efforts=efforts,
                            offline_seeds=offline_seeds)
