"""A long run: the walking sequence looped, root free, by the balance controller.

A game or a simulation drives a character for hours; the soak checks that a long run stays
sound in one process: no NaN or divergence, resident memory that does not creep up, and a
wall time per simulated second that stays flat. The walking sequence of the robustness
table (``02_01 -> 02_02 -> 02_01 -> 02_02`` joined by ``upm`` windows,
:data:`eval.robustness.DEFAULT_ROWS`) is followed by :func:`controller.balance.follow`
(the real-time controller: root free, no external force, one process) again and again
until ``duration_s`` simulated seconds have passed (the last loop cut to what is left).

Each loop starts the character anew from the sequence's first frame, grounded (the
controller's own start, :func:`controller.balance.follow.prepared_reference`): the state
does not carry over from one loop to the next, so a fall in one loop does not end the
soak (it is counted, and the next loop re-grounds the character). What carries over is
the process: the model, the compiled kernels, the allocator, every cache.

Figures (:func:`summarise`): per loop its simulated and wall seconds, whether it fell or
diverged, whether every simulated frame is finite, and the resident memory after it; per
bucket of ``bucket_s`` simulated seconds (a minute by default), the wall seconds per
simulated second; the resident memory's growth from ``duration_s / 12`` (the 5th minute
of an hour) to the end.
"""

from __future__ import annotations

import gc
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from controller.config import DEFAULT, ControllerConfig

#: Largest resident-memory growth from the twelfth of the run to its end (issue 64: under
#: 5 %).
MEMORY_GROWTH_TARGET = 0.05
#: Largest ratio of the last bucket's cost per simulated second to the first's (in raw
#: ``mj_step`` units: the wall seconds' ratio moves with the machine's load).
WALL_DRIFT_TARGET = 1.10


@dataclass(frozen=True)
class SoakSettings:
    """What a soak runs.

    Attributes
    ----------
    data_dir : str
        The CMU clips.
    duration_s : float
        Simulated seconds in all (an hour by default).
    bucket_s : float
        Simulated seconds per bucket of the wall-time figure.
    loop_s : float or None
        Loop only the sequence's first ``loop_s`` seconds (None: the whole sequence; a
        shorter loop for quick runs).
    method : str
        The transition method joining the sequence's clips.
    map_path : str or None
        The posture map for ``upm`` (None: trained on the train split, cached).
    config : controller.config.ControllerConfig
    """

    data_dir: str
    duration_s: float = 3600.0
    bucket_s: float = 60.0
    loop_s: float | None = None
    method: str = "upm"
    map_path: str | None = None
    config: ControllerConfig = DEFAULT


def resident_bytes() -> int:
    """The process's resident memory now, bytes (``/proc/self/statm``; where there is no
    ``/proc``, the peak from ``getrusage``)."""
    try:
        with open("/proc/self/statm") as handle:
            return int(handle.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        import resource

        return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


def walking_reference(settings: SoakSettings):
    """The walking sequence on its subject's humanoid: ``(model, qpos (T, nq), fps)``."""
    from controller.qpos import to_qpos
    from eval.robustness import _WALK_SEQUENCE, Row, Settings, reference

    model, motion = reference(Settings(data_dir=str(settings.data_dir),
                                       map_path=settings.map_path, offset_deg=0.0,
                                       controller_config=settings.config),
                              Row(_WALK_SEQUENCE, settings.method), 0)
    qpos = to_qpos(model, motion)
    if settings.loop_s is not None:
        qpos = qpos[:max(2, int(round(settings.loop_s * motion.fps)) + 1)]
    return model, qpos, float(motion.fps)


def run_soak(settings: SoakSettings,
             on_loop: Callable[[dict], None] | None = None) -> dict:
    """Loop the walking sequence for ``settings.duration_s`` simulated seconds.

    Parameters
    ----------
    settings : SoakSettings
    on_loop : callable, optional
        Called with each loop's figures (a dict, see :func:`summarise`) as it ends: a
        progress bar, or a log that keeps what a stopped soak reached.

    Returns
    -------
    dict
        :func:`summarise` of the loops, with ``reference_s`` (the loop's length) and
        ``reference_build_s`` (wall seconds to build the sequence).
    """
    from controller.balance.follow import follow

    start = time.perf_counter()
    model, qpos, fps = walking_reference(settings)
    build_s = time.perf_counter() - start
    loops: list[dict] = []
    simulated_s = 0.0
    while simulated_s < settings.duration_s - 1e-9:
        left = int(math.ceil((settings.duration_s - simulated_s) * fps - 1e-6)) + 1
        ref = qpos[:max(2, min(len(qpos), left))]
        clock = time.perf_counter()
        run = follow(model, ref, fps, config=settings.config, processes=1)
        wall_s = time.perf_counter() - clock
        reached = int(round(run.sim_s * fps)) + 1
        gc.collect()
        loop = {"loop": len(loops), "sim_s": round(run.sim_s, 6), "wall_s": round(wall_s, 4),
                "raw_step_units": round(run.wall_s / run.raw_step_s, 1)
                if run.raw_step_s > 0 else None,
                "fell": bool(run.fell), "fall_time_s": run.fall_time_s,
                "diverged": run.diverged_frame is not None,
                "finite": bool(np.all(np.isfinite(run.qpos[:reached]))),
                "sim_end_s": round(simulated_s + run.sim_s, 6),
                "rss_mb": round(resident_bytes() / 2**20, 2)}
        del run
        loops.append(loop)
        if on_loop is not None:
            on_loop(loop)
        if loop["sim_s"] <= 0:  # a loop that simulated nothing would never end the soak
            break
        simulated_s += loop["sim_s"]
    out = summarise(loops, settings.duration_s, settings.bucket_s)
    out.update(reference_s=round((len(qpos) - 1) / fps, 4), reference_build_s=round(build_s, 3),
               method=settings.method, loop_s=settings.loop_s)
    return out


def summarise(loops: list[dict], duration_s: float, bucket_s: float) -> dict:
    """The soak's figures from its loops.

    Parameters
    ----------
    loops : list of dict
        Per loop, in order: ``sim_s``, ``wall_s`` (seconds), ``fell``, ``diverged``,
        ``finite`` (bool), ``sim_end_s`` (simulated seconds since the soak began at the
        loop's end), ``rss_mb`` (resident memory after the loop, MiB).
    duration_s : float
        The soak's intended length, simulated seconds.
    bucket_s : float
        Simulated seconds per bucket.

    Returns
    -------
    dict
        ``simulated_s``, ``wall_s``, ``loops``, ``loops_fell``, ``loops_diverged``,
        ``loops_not_finite``, ``sound`` (no divergence, every frame finite);
        ``wall_s_per_sim_s_by_bucket``: per bucket of ``bucket_s`` (a loop counts in the
        bucket where it ends; the first loop, which loads the compiled kernels, is left
        out), wall seconds over simulated seconds; ``wall_drift``: the last bucket's over
        the first's; ``rss_mb_at_twelfth``: resident memory after the first loop ending at
        or beyond ``duration_s / 12``; ``rss_mb_end``; ``rss_growth``: their relative
        difference; ``targets`` (``rss_growth`` <= 5 %, ``raw_drift`` <= 1.10).
    """
    n_buckets = max(1, int(math.ceil(duration_s / bucket_s - 1e-9)))
    wall = [0.0] * n_buckets
    raw = [0.0] * n_buckets
    sim = [0.0] * n_buckets
    for loop in loops[1:]:
        b = min(n_buckets - 1, max(0, int(math.ceil(loop["sim_end_s"] / bucket_s - 1e-9)) - 1))
        wall[b] += loop["wall_s"]
        raw[b] += loop.get("raw_step_units") or math.nan
        sim[b] += loop["sim_s"]
    by_bucket = _per_sim_s(wall, sim, 4)
    raw_by_bucket = _per_sim_s(raw, sim, 1)
    drift, raw_drift = _drift(by_bucket), _drift(raw_by_bucket)
    twelfth = next((loop for loop in loops if loop["sim_end_s"] >= duration_s / 12 - 1e-9),
                   None)
    rss_start = twelfth["rss_mb"] if twelfth is not None else None
    rss_end = loops[-1]["rss_mb"] if loops else None
    growth = (rss_end - rss_start) / rss_start if rss_start else None
    out = {
        "duration_s": duration_s,
        "bucket_s": bucket_s,
        "simulated_s": round(sum(loop["sim_s"] for loop in loops), 4),
        "wall_s": round(sum(loop["wall_s"] for loop in loops), 3),
        "loops": len(loops),
        "loops_fell": sum(bool(loop["fell"]) for loop in loops),
        "loops_diverged": sum(bool(loop["diverged"]) for loop in loops),
        "loops_not_finite": sum(not loop["finite"] for loop in loops),
        "wall_s_per_sim_s_by_bucket": by_bucket,
        "wall_drift": None if drift is None else round(drift, 4),
        "raw_steps_per_sim_s_by_bucket": raw_by_bucket,
        "raw_drift": None if raw_drift is None else round(raw_drift, 4),
        "rss_mb_at_twelfth": rss_start,
        "rss_mb_end": rss_end,
        "rss_growth": None if growth is None else round(growth, 5),
    }
    out["sound"] = out["loops_diverged"] == 0 and out["loops_not_finite"] == 0
    targets = {}
    if growth is not None:
        targets["rss_growth"] = {"value": out["rss_growth"], "target": MEMORY_GROWTH_TARGET,
                                 "met": bool(growth <= MEMORY_GROWTH_TARGET)}
    if raw_drift is not None:
        targets["raw_drift"] = {"value": out["raw_drift"], "target": WALL_DRIFT_TARGET,
                                "met": bool(raw_drift <= WALL_DRIFT_TARGET), "unit": "ratio",
                                "reference": "the first bucket, in raw mj_step units"}
    out["targets"] = targets
    return out


def _per_sim_s(amounts, sim, digits: int) -> list:
    return [round(a / s, digits) if s > 0 and math.isfinite(a) else None
            for a, s in zip(amounts, sim, strict=True)]


def _drift(by_bucket) -> float | None:
    filled = [x for x in by_bucket if x is not None]
    return filled[-1] / filled[0] if len(filled) >= 2 else None
