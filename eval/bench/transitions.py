"""Transitions: microseconds per 20-frame transition per method, and spacetime / UPM (the
paper's Table 4: spacetime 72 s vs UPM 1-2 s, i.e. 36-72x).

Each method joins the same real clip pairs (short clips, so the figure is the window,
not copying frames) through :func:`upm.transitions.transition`. The reference measured
in the same run is one cubic B-spline fit and evaluation over the same key frames (the
work every key-posture method must do at least). Key-posture sources: the UPM and the
SOM trained on the train split (:func:`upm.map_cache.trained_map`: trained once, then
cached; training time is not part of the figure), ``classnn`` and ``snap`` fitted on the
same postures.
"""

from __future__ import annotations

import numpy as np

from eval.bench import BenchContext, timeit_best

NAME = "transitions"

#: (clip 1, frame A, clip 2, frame B): real pairs from the test split.
PAIRS = (("02_01", 200, "02_03", 20), ("05_01", 300, "05_11", 100), ("16_15", 250, "03_01", 50))
WINDOW = 20
CLIP_FRAMES = 60


def run(context: BenchContext) -> dict:
    from upm.catalog import Catalog
    from upm.map_cache import trained_map
    from upm.transitions import (
        METHODS,
        ClassNearest,
        NearestPosture,
        make_problem,
        training_postures,
        transition,
    )
    from upm.transitions.spline import keyframe_spline

    catalog = Catalog(context.data_dir)
    pairs = PAIRS[:1] if context.quick else PAIRS
    step = 8 if context.quick else 1
    postures = training_postures(catalog, "train", step=step)
    sources = {"classnn": ClassNearest(postures), "snap": NearestPosture(postures)}
    # The maps of the study: trained once on the train split, then cached.
    sources.update({kind: trained_map(catalog, kind) for kind in ("upm", "som")})

    clips = []
    for name1, a, name2, b in pairs:
        before = catalog.load(name1).frames(a + 1 - CLIP_FRAMES, a + 1)
        after = catalog.load(name2).frames(b, b + CLIP_FRAMES)
        clips.append((before, after))

    repeat = 1 if context.quick else 3
    figures: dict[str, dict] = {}
    for name, method in METHODS.items():
        source = sources.get(method.key_kind) if method.needs_key_source else None
        slow = name == "spacetime"
        per_pair = [
            timeit_best(lambda b=before, a=after, n=name, s=source:
                        transition(n, b, a, WINDOW, 0.5, s),
                        repeat=1 if slow and context.quick else repeat,
                        number=1 if slow else (3 if context.quick else 20))
            for before, after in clips
        ]
        figures[name] = {"us_per_transition": 1e6 * float(np.median(per_pair)),
                         "us_per_transition_each_pair": [1e6 * s for s in per_pair]}

    problem = make_problem(*clips[0], WINDOW, 0.5)
    times = np.concatenate([problem.before_times, [problem.key_time], problem.after_times])
    keys = np.concatenate([problem.before_deg, problem.a_deg[None], problem.after_deg])
    spline_s = timeit_best(lambda: keyframe_spline(times, keys, problem.window_times),
                           repeat=3 if context.quick else 10, number=50)
    reference_us = 1e6 * spline_s
    for entry in figures.values():
        entry["ratio_to_reference"] = entry["us_per_transition"] / reference_us

    report = {
        "window_frames": WINDOW,
        "pairs": [f"{n1}@{a}->{n2}@{b}" for n1, a, n2, b in pairs],
        "reference_cubic_spline_fit_us": reference_us,
        "methods": figures,
        "paper_table4_spacetime_over_upm": [36.0, 72.0],
    }
    report["spacetime_over_upm"] = (figures["spacetime"]["us_per_transition"]
                                    / figures["upm"]["us_per_transition"])
    return report
