"""The study's scoring: milliseconds to score one 20-frame transition window on the
humanoid (eval.scoring.score_window), and its parts, next to the reference measured in
the same run: making the UPM transition itself (upm.transitions.transition).

The study scores 8 methods x every window length x every pair, plus the real windows:
this figure times those counts is its scoring cost (the spacetime optimisation aside).
"""

from __future__ import annotations

import numpy as np

from eval.bench import BenchContext, timeit_best

NAME = "study"
WINDOW = 20


def run(context: BenchContext) -> dict:
    from eval.pairs import draw_pairs
    from eval.realdata import RealPostures, load_test_clips
    from humanoid_xml import catalog_model_path, load_model
    from upm.maps.map_cache import trained_map
    from upm.motion.catalog import Catalog

    catalog = Catalog(context.data_dir)
    motions = load_test_clips(catalog)
    lengths = {n: m.n_frames for n, m in motions.items()}
    real = RealPostures.of(motions)
    upm = trained_map(catalog, "upm")
    pairs = draw_pairs(lengths, 1 if context.quick else 5, seed=0)
    repeat = 1 if context.quick else 3

    figures: dict[str, list[float]] = {}
    for pair in pairs:
        model = load_model(catalog_model_path(catalog, pair.first.clip))
        for key, value in _time_pair(pair, motions, lengths, real, upm, model,
                                     repeat).items():
            figures.setdefault(key, []).append(value)
    ms = {k: float(np.median(v)) for k, v in figures.items()}
    reference = ms["transition_upm"]
    return {
        "window_frames": WINDOW,
        "pairs": len(pairs),
        "reference_upm_transition_ms": reference,
        "score_window_ms": ms["score_window"],
        "score_over_transition": ms["score_window"] / reference,
        "parts_ms": {k: v for k, v in ms.items() if k not in ("transition_upm", "score_window")},
        "bank_postures": int(real.postures_deg.shape[0]),
    }


def _time_pair(pair, motions, lengths, real, upm, model, repeat: int) -> dict[str, float]:
    """Milliseconds of each part of scoring one pair's UPM window, and of making it."""
    from controller.checks.dynamics import root_residual
    from controller.checks.validity import check_motion
    from controller.qpos import to_qpos
    from controller.tracking.servo import track
    from eval.metrics import window_jerk_rms
    from eval.pairs import exclusion_zones
    from eval.scoring import RESIDUAL_CONTEXT, feet_over_frames, score_window
    from upm.transitions import transition

    before = motions[pair.first.clip].frames(pair.first.start, pair.first.stop)
    after = motions[pair.second.clip].frames(pair.second.start, pair.second.stop)
    zones = exclusion_zones(pair, WINDOW, lengths)
    t = transition("upm", before, after, WINDOW, 0.5, upm)
    w0, w1 = t.window.start, t.window.stop
    ends = t.motion.frames(w0 - 1, w1 + 1)
    context_motion = t.motion.frames(w0 - RESIDUAL_CONTEXT, w1 + RESIDUAL_CONTEXT)
    qpos = to_qpos(model, context_motion)
    score_window(model, t.motion, t.window, real, zones)  # first-use imports out of the way
    timed = {
        "transition_upm": lambda: transition("upm", before, after, WINDOW, 0.5, upm),
        "score_window": lambda: score_window(model, t.motion, t.window, real, zones),
        "kinematic": lambda: check_motion(model, ends, (slice(1, WINDOW + 1),)),
        "nearest_real": lambda: real.nearest_rms_deg(t.window_posture_deg, zones),
        "jerk": lambda: window_jerk_rms(t.motion.posture_deg, t.window, t.motion.fps,
                                        real.dofs),
        "residual": lambda: root_residual(model, qpos, t.motion.fps),
        "feet": lambda: feet_over_frames(model, qpos),
        "tracking": lambda: track(model, context_motion, mode="driven"),
    }
    return {key: 1000.0 * timeit_best(fn, repeat=repeat) for key, fn in timed.items()}
