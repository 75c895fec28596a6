"""Can the character perform the transition? The study's free-root test (``--physics``).

For every pair x method x window (and every real window of the calibration row), the
balance controller (:func:`controller.balance.follow`: root free, no external force, the
humanoid's own joint strength) follows the motion from :data:`CONTEXT_S` before the window
to :data:`CONTEXT_S` after it — the same context for every method: clip 1's own frames
before, clip 2's after — and the figures of :data:`PHYSICS_METRICS` are recorded: whether
the character fell (anywhere in the run) and when relative to the window's first frame,
whether it was going down at the run's end without having fallen (in trouble by the
balance search's test), and, over the window's frames before any fall, how far it was from
the method's own motion (joint angles, body positions), how far it drifted, how often it
asked for more torque than the joint has and the peak floor force.

A unit of work is one (pair or real window, method, window length): :func:`task_list`
names them, :func:`run_unit` runs one in a worker (:mod:`eval.executor`: a local pool or
Ray). Finished units are appended to a checkpoint file in the output directory as they
come (:class:`Checkpoint`), so a run that fails or is stopped keeps them and the same
command completes only what is missing. The figures are deterministic (the controller has
no randomness), whatever the executor and the number of workers. The controller's tuning
constants are one :class:`controller.config.ControllerConfig` (``upm eval --physics
--config FILE.toml``): it goes to every worker with the study's data, into the
checkpoint's settings (a checkpoint made with another configuration is not reused) and
into results.json.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from controller.config import DEFAULT, ControllerConfig
from eval.physics_unit import DEFAULT_EFFORT, EFFORTS, PHYSICS_METRICS, simulate_unit
from eval.records import REAL, Records
from eval.runs import Checkpoint, StudyIncomplete, run_checkpointed

if TYPE_CHECKING:
    from eval.summaries import Summaries

#: Seconds of the motion simulated before and after the window.
CONTEXT_S = 0.5
CHECKPOINT_NAME = "physics-partial.jsonl"
CHECKPOINT_FORMAT = "upm-controller/physics-checkpoint"
CHECKPOINT_VERSION = 3


@dataclass(frozen=True)
class Unit:
    """One unit of work: a pair (or real window) by one method at one window length."""

    kind: str
    index: int
    window: int
    method: str

    @property
    def key(self) -> str:
        return f"{self.kind}/{self.index}/{self.window}/{self.method}"

    def describe(self) -> str:
        what = f"pair {self.index}" if self.kind == "pair" else f"real window {self.index}"
        return f"{what}, {self.method}, L = {self.window}"


def task_list(pairs, real_windows: dict, methods, windows, scores=None) -> list[Unit]:
    """Every unit of the free-root test, in a fixed order.

    Parameters
    ----------
    pairs : list of eval.pairs.Pair
    real_windows : dict of int to list of eval.pairs.RealWindow
    methods : sequence of str
    windows : sequence of int
    scores : callable, optional
        ``scores(method, pair_index)``: whether a method is run on a pair
        (:meth:`eval.study.StudyConfig.scores`: ``performed`` on its first pairs only);
        default: every one.
    """
    units = [Unit("pair", p.index, frames, m) for frames in windows for p in pairs
             for m in methods if scores is None or scores(m, p.index)]
    units += [Unit("real", w.index, frames, REAL) for frames in windows
              for w in real_windows[frames]]
    return units


def context_frames(fps: float) -> int:
    """Frames of :data:`CONTEXT_S` at ``fps``."""
    return int(round(CONTEXT_S * fps))


def unit_motion(data, unit: Unit, pairs: dict, real_windows: dict):
    """The motion a unit simulates and where its window lies in it.

    Returns
    -------
    model : mujoco.MjModel
    motion : upm.Motion
        From :data:`CONTEXT_S` before the window to :data:`CONTEXT_S` after it (less where
        the clip is shorter).
    start, stop : int
        The window's frames in ``motion``.
    """
    from eval.study import make_transition

    if unit.kind == "pair":
        pair = pairs[unit.index]
        t = make_transition(data, pair, unit.method, unit.window)
        motion, window, clip = t.motion, t.window, pair.first.clip
    else:
        w = next(w for w in real_windows[unit.window] if w.index == unit.index)
        motion, window, clip = data.motions[w.clip], slice(w.start, w.stop), w.clip
    c = context_frames(motion.fps)
    lo, hi = max(0, window.start - c), min(motion.n_frames, window.stop + c)
    return data.model(clip), motion.frames(lo, hi), window.start - lo, window.stop - lo


# --- in the workers -------------------------------------------------------------------------

_WORKER: dict = {}


def init_worker(config, pairs: dict, real_windows: dict,
                controller_config: ControllerConfig = DEFAULT,
                effort: str = DEFAULT_EFFORT) -> None:
    """Load the study's data once per worker process (idempotent), and keep the
    controller's configuration and effort for its units."""
    from eval.runs import single_threaded_blas
    from eval.study import prepare

    if _WORKER.get("config") != config:
        single_threaded_blas()
        _WORKER.update(config=config, data=prepare(config), pairs=pairs,
                       real_windows=real_windows)
    _WORKER["controller_config"] = controller_config
    _WORKER["effort"] = effort


def run_unit(unit: Unit) -> dict[str, float]:
    """One unit in a worker (after :func:`init_worker`)."""
    model, motion, start, stop = unit_motion(_WORKER["data"], unit, _WORKER["pairs"],
                                             _WORKER["real_windows"])
    return simulate_unit(model, motion, start, stop, _WORKER["controller_config"],
                         _WORKER.get("effort", DEFAULT_EFFORT))


def records_of(units: list[Unit], done: dict[str, dict[str, float]],
               skipped: list[Unit] = ()) -> Records:
    """The long-form table of finished units, and NaN rows for the ``skipped`` ones (a
    method not run on a pair: the summaries leave them out)."""
    records = Records(PHYSICS_METRICS)
    for unit in units:
        records.add(unit.kind, unit.index, unit.window, unit.method, done[unit.key])
    for unit in skipped:
        records.add(unit.kind, unit.index, unit.window, unit.method,
                    {name: math.nan for name in PHYSICS_METRICS})
    return records


# --- statistics -----------------------------------------------------------------------------


def physics_statistics(records: Records, pair_records: list[dict], real_windows: dict,
                       clips: dict, methods, windows, seed: int):
    """Intervals per method (and the real windows) and paired UPM - X
    (:func:`eval.summaries.summarise` with :data:`PHYSICS_METRICS`).

    Means and intervals are over the units where a figure exists (errors: the window
    frames before a fall; a unit that fell before its window has none): ``n`` says how
    many. Paired differences use the pairs where both methods have the figure.

    Parameters
    ----------
    records : eval.records.Records
    pair_records : list of dict
        The study's pairs tested (:attr:`eval.study.StudyResult.pairs`).
    real_windows : dict of int to list of eval.pairs.RealWindow
    clips : dict
        The study's clips (``flat_floor`` of each).

    Returns
    -------
    eval.summaries.Summaries
    """
    from eval.summaries import summarise

    real = {frames: [{"id": w.index, "clip": w.clip,
                      "flat_floor": bool(clips[w.clip]["flat_floor"])} for w in ws]
            for frames, ws in real_windows.items()}
    return summarise(records, PHYSICS_METRICS, pair_records, real, methods, windows, seed)


# --- the run --------------------------------------------------------------------------------


@dataclass
class PhysicsResult:
    """The free-root test of a study.

    Attributes
    ----------
    records : eval.records.Records
        Long-form: every unit's :data:`PHYSICS_METRICS`.
    statistics : eval.summaries.Summaries
        :func:`physics_statistics`.
    pairs : int
        Pairs tested (the study's first ones).
    real_windows : dict of int to list of eval.pairs.RealWindow
    checkpoint : Checkpoint
    resumed : int
        Units taken from an earlier run's checkpoint.
    executor : str
    workers : int
    wall_s : float
        Wall time of the units run now.
    controller_config : controller.config.ControllerConfig
        The balance controller's configuration.
    effort : str
        The free-root body's effort (:data:`EFFORTS`).
    """

    records: Records
    statistics: Summaries
    pairs: int
    real_windows: dict
    checkpoint: Checkpoint
    resumed: int
    executor: str
    workers: int
    wall_s: float
    controller_config: ControllerConfig = DEFAULT
    effort: str = DEFAULT_EFFORT


def run_physics(result, n_pairs: int, out_dir, executor: str = "local",
                address: str | None = None, workers: int | None = None,
                show_progress: bool = True,
                controller_config: ControllerConfig = DEFAULT,
                effort: str = DEFAULT_EFFORT) -> PhysicsResult:
    """Run the free-root test on the first ``n_pairs`` pairs of a study.

    Parameters
    ----------
    result : eval.study.StudyResult
        The kinematic study (its pairs, data and settings).
    n_pairs : int
        At most the study's pairs.
    out_dir : path-like
        Where the checkpoint lives (the study's output directory).
    executor : str
        ``"local"`` or ``"ray"`` (:mod:`eval.executor`).
    address : str, optional
        A Ray cluster (with ``executor="ray"``).
    workers : int, optional
        Processes (local) or CPUs of a local Ray instance; default: the usable cores.
    controller_config : controller.config.ControllerConfig
        The balance controller's tuning constants (the offline effort: its ``offline``
        section).
    effort : str
        ``"realtime"``: the balance controller; ``"offline"``: the offline effort's
        sampling search (each run on ``controller_config.offline.threads`` threads: the
        default workers are the usable cores divided by them).

    Raises
    ------
    StudyIncomplete
        If units failed: each named with its error; the finished ones stay in the
        checkpoint and the same command completes the rest.
    """
    import time

    if effort not in EFFORTS:
        raise ValueError(f"unknown effort {effort!r} (efforts: {', '.join(EFFORTS)})")
    from eval.executor import make_executor
    from eval.pairs import draw_real_windows
    from eval.runs import default_workers
    from eval.study import pair_by_id

    config = result.config
    data = result.data
    pairs = {i: pair_by_id(result, i) for i in range(n_pairs)}
    context = context_frames(120.0)
    real_windows = {frames: draw_real_windows(data.lengths, n_pairs, frames, config.seed,
                                              context=context)
                    for frames in config.windows}
    units = task_list(list(pairs.values()), real_windows, config.methods, config.windows,
                      config.scores)
    every = task_list(list(pairs.values()), real_windows, config.methods, config.windows)
    kept = {u.key for u in units}
    skipped = [u for u in every if u.key not in kept]
    settings = {"data": Path(config.data_dir).name, "seed": config.seed, "context_s": CONTEXT_S,
                "alpha": config.as_dict()["alpha"],
                "controller_config": controller_config.as_dict(), "effort": effort}
    checkpoint = Checkpoint(out_dir, settings, name=CHECKPOINT_NAME,
                            format_name=CHECKPOINT_FORMAT, version=CHECKPOINT_VERSION)
    resumed = checkpoint.load()
    todo = [u for u in units if u.key not in checkpoint.done]
    threads = controller_config.offline.threads if effort == "offline" else 1
    workers = max(1, min(workers or default_workers() // threads, max(1, len(todo))))
    # This process already holds the data: forked workers inherit it.
    _WORKER.update(config=config, data=data, pairs=pairs, real_windows=real_windows)
    runner = make_executor(executor, workers, address, init_worker,
                           (config, pairs, real_windows, controller_config, effort))
    start = time.perf_counter()
    by_key = {u.key: u for u in todo}
    failures = [(by_key[key], error) for key, error in run_checkpointed(
        runner, run_unit, [(u.key, (u,)) for u in todo], checkpoint, "free-root test",
        show_progress)]
    wall = time.perf_counter() - start
    if failures:
        first, error = failures[0]
        raise StudyIncomplete(
            f"{len(failures)} of {len(units)} free-root runs failed (first: "
            f"{first.describe()}: {error}); the {len(checkpoint.done)} finished are kept in "
            f"{checkpoint.path}: run the same command again to complete the rest")
    records = records_of(units, checkpoint.done, skipped)
    statistics = physics_statistics(records, result.pairs[:n_pairs], real_windows,
                                    result.clips, config.methods, config.windows, config.seed)
    return PhysicsResult(records=records, statistics=statistics, pairs=n_pairs,
                         real_windows=real_windows, checkpoint=checkpoint, resumed=resumed,
                         executor=executor, workers=workers, wall_s=wall,
                         controller_config=controller_config, effort=effort)
