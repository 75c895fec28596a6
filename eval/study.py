"""The held-out study: every transition method on every pair and window length, scored on
the humanoid, and the real windows that calibrate the scores (SPEC section 7).

:func:`run_study` trains (or takes from the cache) the UPM and the SOM on the train split,
fits the two ablations (``classnn``, ``snap``) on the same postures, draws the pairs
(:mod:`eval.pairs`), and scores every method x window of every pair and every real window
(:func:`eval.scoring.score_window`), and the in-betweening task's windows (the LaFAN1
metrics, :mod:`eval.inbetween`), in parallel through an executor (:mod:`eval.executor`:
a local process pool, or Ray). The scores go into one long-form table
(:class:`eval.records.Records`: pair, real or in-betweening window, window length,
method, metric, value; :func:`eval.collect.collect`) with the registry
:data:`eval.collect.SCORE_METRICS`. They do not depend on the
number of workers: each task is a pure function of its pair, and the table sorts its rows.
BLAS runs single-threaded in every process (the arrays are small; with several threads
the spacetime optimisation ran up to 30x slower on a loaded machine).

The study's settings are :class:`eval.study_config.StudyConfig` (re-exported here).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from eval.inbetween import INBETWEEN
from eval.pairs import (
    Pair,
    RealWindow,
    draw_pairs,
    draw_real_windows,
    exclusion_zones,
    real_exclusion_zone,
)
from eval.records import Records
from eval.runs import default_workers, single_threaded_blas
from eval.study_config import ALPHA, FULL_METHODS, STUDY_METHODS, StudyConfig
from upm.transitions import PERFORMED_METHODS

__all__ = ["ALPHA", "FULL_METHODS", "STUDY_METHODS", "StudyConfig", "StudyData",
           "StudyResult", "make_transition", "pair_by_id", "prepare", "run_study"]

@dataclass
class StudyData:
    """Everything a worker needs, built once per process (:func:`prepare`).

    Attributes
    ----------
    config : StudyConfig
    catalog : upm.motion.catalog.Catalog
    motions : dict of str to upm.Motion
        The test clips at 120 fps.
    lengths : dict of str to int
        Their frame counts.
    real : eval.realdata.RealPostures
    sources : dict of str to KeyPostureSource
        By method, for the methods that have one.
    train_subjects : frozenset of str
        Subjects with at least one clip in the train split.
    position_std : ndarray, shape (22, 3), or None
        The in-betweening task's L2P normalisation (None without the task).
    """

    config: StudyConfig
    catalog: object
    motions: dict
    lengths: dict[str, int]
    real: object
    sources: dict
    train_subjects: frozenset
    position_std: object = None
    models: dict = field(default_factory=dict)

    def model(self, clip: str):
        """The humanoid of a clip's subject (loaded once)."""
        from humanoid_xml import catalog_model_path, load_model

        subject = self.catalog.info(clip).subject
        if subject not in self.models:
            self.models[subject] = load_model(catalog_model_path(self.catalog, subject))
        return self.models[subject]

    def subject(self, clip: str) -> str:
        return self.catalog.info(clip).subject

    def segment(self, segment):
        return self.motions[segment.clip].frames(segment.start, segment.stop)


def key_sources(catalog, methods, progress: bool = False) -> dict:
    """The key-posture sources the methods need, by method, each built by its registered
    builder (:func:`upm.transitions.build_key_source`) from one shared context: the UPM
    and the SOM trained on the train split (cached: :func:`upm.maps.map_cache.trained_map`),
    the ablations fitted on every frame of it."""
    from upm.transitions import KeySourceContext, build_key_source

    context = KeySourceContext(catalog=catalog, train_maps=True, progress=progress)
    if any(m in PERFORMED_METHODS for m in methods):
        from controller.offline.performer import install

        install()  # the humanoid's performer, in this process and (forked) its workers
    built = {m: build_key_source(m, context) for m in methods}
    return {m: s for m, s in built.items() if s is not None}


def prepare(config: StudyConfig, progress: bool = False) -> StudyData:
    """Load the clips and the key-posture sources (training the maps if not cached)."""
    from eval.realdata import RealPostures, load_test_clips
    from upm.motion.catalog import Catalog

    catalog = Catalog(config.data_dir)
    motions = load_test_clips(catalog)
    data = StudyData(
        config=config, catalog=catalog, motions=motions,
        lengths={name: m.n_frames for name, m in motions.items()},
        real=RealPostures.of(motions),
        sources=key_sources(catalog, config.methods, progress),
        train_subjects=frozenset(catalog.info(n).subject for n in catalog.names("train")),
    )
    if config.inbetween_windows:
        from eval.inbetween import cached_position_std

        data.position_std = cached_position_std(catalog)
    _warm_up(data)
    return data


def _warm_up(data: StudyData) -> None:
    """One short transition by every method, so that no method's first timed call pays
    for lazily built search structures or first-use imports."""
    from eval.pairs import Segment

    first, second = list(data.lengths)[:2]
    pair = Pair(index=-1, first=Segment(first, 0, 10), second=Segment(second, 0, 10))
    for method in data.config.kinematic_methods:
        make_transition(data, pair, method, 4)


def make_transition(data: StudyData, pair: Pair, method: str, frames: int):
    """The transition of one pair by one method (``upm.transitions.transition``)."""
    from upm.transitions import transition

    source = data.sources.get(method)
    return transition(method, data.segment(pair.first), data.segment(pair.second), frames,
                      ALPHA, source)


def score_pair(data: StudyData, pair: Pair) -> dict:
    """Every method x window of one pair.

    Returns
    -------
    dict
        ``index``; ``scores``: list of (L, method, ``{metric: value}``); ``ms``: ``{L:
        {method: milliseconds of the transition itself}}``; ``end_self_collision``:
        whether A and B (clip 2's first posture on clip 1's body) are in self-collision.
    """
    from eval.metrics import METRICS
    from eval.scoring import end_self_collision, score_window

    scores: list = []
    ms: dict = {}
    ends = None
    for frames in data.config.windows:
        zones = exclusion_zones(pair, frames, data.lengths)
        ms[frames] = {}
        for method in data.config.methods:
            if not data.config.scores(method, pair.index):
                scores.append((frames, method, {m: math.nan for m in METRICS}))
                ms[frames][method] = math.nan
                continue
            t = make_transition(data, pair, method, frames)
            model = data.model(pair.first.clip)
            scores.append((frames, method,
                           score_window(model, t.motion, t.window, data.real, zones)))
            ms[frames][method] = 1000.0 * t.seconds
            if ends is None:
                ends = end_self_collision(model, t.motion, t.window)
    return {"index": pair.index, "scores": scores, "ms": ms, "end_self_collision": ends}


def score_real(data: StudyData, window: RealWindow) -> dict:
    """One real window of a test clip, scored exactly as a transition's window."""
    from eval.scoring import score_window

    motion = data.motions[window.clip]
    zones = real_exclusion_zone(window, data.lengths)
    return {"index": window.index, "frames": window.frames,
            "scores": score_window(data.model(window.clip), motion,
                                   slice(window.start, window.stop), data.real, zones)}


# --- worker processes ---------------------------------------------------------------------

_DATA: StudyData | None = None


def _init_worker(config: StudyConfig) -> None:
    global _DATA
    single_threaded_blas()
    if _DATA is None or _DATA.config != config:
        _DATA = prepare(config)


def _task(kind: str, item):
    if kind == INBETWEEN:
        from eval.inbetween import score_window

        return kind, {"index": item.index, "scores": score_window(
            _DATA, item, _DATA.position_std, _DATA.config.kinematic_methods, ALPHA)}
    return kind, (score_pair(_DATA, item) if kind == "pair" else score_real(_DATA, item))


def _task_key(kind: str, item) -> str:
    """``pair/ID``, ``real/L/ID`` or ``inbetween/ID``: what a failed task is reported as."""
    if kind in ("pair", INBETWEEN):
        return f"{kind}/{item.index}"
    return f"real/{item.frames}/{item.index}"


# --- the study ----------------------------------------------------------------------------


@dataclass
class StudyResult:
    """The study's scores, before statistics.

    Attributes
    ----------
    config : StudyConfig
    records : eval.records.Records
        Every score, long-form: ``pair`` rows (id, L, method, metric, value), ``real``
        rows (id, L, ``"real"``, metric, value), metrics from :data:`eval.metrics.METRICS`,
        and ``inbetween`` rows (id, length at 30 fps, method or baseline, metric, value),
        metrics from :data:`eval.inbetween.INBETWEEN_METRICS`.
    pairs : list of dict
        Per pair (sorted by id): ``id``, ``first``/``second`` segments, ``subjects``,
        ``ab_distance_deg`` (A to B, RMS over the declared DOFs), ``seen`` (both
        subjects have clips in the train split), ``end_self_collision`` ([A, B] in
        self-collision on clip 1's body), ``flat_floor`` (both clips flat-floor).
    real : dict of int to list of dict
        Per window length, the real windows: ``id``, ``clip``, ``start``, ``stop``,
        ``flat_floor``.
    clips : dict of str to dict
        Per test clip: ``subject``, ``frames`` (120 fps), ``seen``,
        ``floor_residual_median_bw``, ``flat_floor``.
    train_subjects : list of str
    timing_ms : dict
        ``{L: {method: [ms per pair, by pair id]}}`` (not deterministic: kept apart).
    inbetween : list of eval.pairs.RealWindow
        The in-betweening task's windows (their scores: ``inbetween`` rows of records).
    wall_s : float
    workers : int
    data : StudyData
        The main process's data (for the figures).
    """

    config: StudyConfig
    records: Records
    pairs: list
    real: dict
    clips: dict
    train_subjects: list
    timing_ms: dict
    wall_s: float
    workers: int
    data: StudyData
    inbetween: list = field(default_factory=list)


def run_study(config: StudyConfig, workers: int | None = None,
              show_progress: bool = True, executor: str = "local",
              address: str | None = None) -> StudyResult:
    """Run the study.

    Parameters
    ----------
    config : StudyConfig
    workers : int, optional
        Processes (default: the usable cores, at most one per task); 1 runs in this
        process.
    show_progress : bool
        Progress bars on stderr (terminals only).
    executor : str
        Where the tasks run: ``"local"`` (a process pool) or ``"ray"``
        (:mod:`eval.executor`).
    address : str, optional
        A Ray cluster's address (with ``executor="ray"``; else a local Ray instance).

    Returns
    -------
    StudyResult

    Raises
    ------
    eval.physics.StudyIncomplete
        If a task failed (each named): nothing is returned half-done.
    """
    from eval.collect import collect
    from upm.core.progress import progress
    from upm.transitions import METHODS

    unknown = [m for m in config.methods if m not in METHODS]
    if unknown:
        from upm.core.errors import UsageError

        raise UsageError(f"no transition method {unknown[0]!r} (methods: {', '.join(METHODS)})")
    global _DATA
    start = time.perf_counter()
    single_threaded_blas()
    data = prepare(config, progress=show_progress)
    _DATA = data
    pairs = draw_pairs(data.lengths, config.pairs, config.seed)
    real = {frames: draw_real_windows(data.lengths, config.pairs, frames, config.seed)
            for frames in config.windows}
    inbetween = []
    if config.inbetween_windows:
        from eval.inbetween import draw_windows

        inbetween = draw_windows(data.lengths, config.inbetween_windows, config.seed)
    tasks = [("pair", p) for p in pairs] + [("real", w) for ws in real.values() for w in ws]
    tasks += [(INBETWEEN, w) for w in inbetween]
    workers = min(workers or default_workers(), len(tasks))

    from eval.executor import make_executor
    from eval.runs import StudyIncomplete

    runner = make_executor(executor, workers, address, _init_worker, (config,))
    keyed = [(_task_key(kind, item), (kind, item)) for kind, item in tasks]
    bar = progress(total=len(tasks), desc="scoring", unit="task",
                   disable=None if show_progress else True)
    done, failures = [], []
    try:
        for outcome in runner.run(_task, keyed):
            if outcome.ok:
                done.append(outcome.value)
            else:
                failures.append(f"{outcome.key}: {outcome.error}")
            bar.update()
    finally:
        bar.close()
    if failures:
        raise StudyIncomplete(f"{len(failures)} of {len(tasks)} study tasks failed "
                              f"(first: {failures[0]}); nothing was written")

    return StudyResult(config=config, **collect(data, pairs, real, done),
                       train_subjects=sorted(data.train_subjects),
                       wall_s=time.perf_counter() - start, workers=workers, data=data,
                       inbetween=inbetween)


def pair_by_id(result: StudyResult, index: int) -> Pair:
    """The :class:`~eval.pairs.Pair` of a record id (for re-making its transitions)."""
    from eval.pairs import Segment

    record = result.pairs[index]
    return Pair(index=record["id"], first=Segment(**record["first"]),
                second=Segment(**record["second"]))

