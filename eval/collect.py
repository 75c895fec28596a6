"""The study's task outcomes gathered into its tables: the long-form scores, the pair
records, the timings, the real windows and the test clips (:func:`collect`)."""

from __future__ import annotations

import math

from eval.inbetween import INBETWEEN, INBETWEEN_METRICS
from eval.metrics import METRICS, pose_distance_rms_deg
from eval.records import REAL, Records

#: Every figure scores.csv may hold: the study's metrics and the in-betweening task's.
SCORE_METRICS = (*METRICS, *INBETWEEN_METRICS)


def clip_records(data) -> dict:
    """Per test clip: ``subject``, ``frames`` (120 fps), ``seen``,
    ``floor_residual_median_bw``, ``flat_floor``."""
    from eval.realdata import FLAT_FLOOR_MAX_BW, floor_residuals

    floor = floor_residuals(data.catalog, data.motions)
    return {name: {"subject": data.subject(name), "frames": data.lengths[name],
                   "seen": data.subject(name) in data.train_subjects,
                   "floor_residual_median_bw": floor[name],
                   "flat_floor": floor[name] < FLAT_FLOOR_MAX_BW}
            for name in data.motions}


def pair_record(data, pair, outcome: dict, clips: dict) -> dict:
    """What a pair is (see :class:`eval.study.StudyResult`, ``pairs``)."""
    a = data.motions[pair.first.clip].posture_deg[pair.first.stop - 1]
    b = data.motions[pair.second.clip].posture_deg[pair.second.start]
    dofs = data.real.dofs
    subjects = [data.subject(pair.first.clip), data.subject(pair.second.clip)]
    return {
        "id": pair.index,
        "first": pair.first.as_dict(),
        "second": pair.second.as_dict(),
        "subjects": subjects,
        "ab_distance_deg": round(float(pose_distance_rms_deg(a[dofs], b[dofs])), 6),
        "seen": all(s in data.train_subjects for s in subjects),
        "end_self_collision": outcome["end_self_collision"],
        "flat_floor": clips[pair.first.clip]["flat_floor"] and clips[pair.second.clip][
            "flat_floor"],
    }


def collect(data, pairs: list, real: dict, done: list) -> dict:
    """The tables of a study from its finished tasks.

    Parameters
    ----------
    data : eval.study.StudyData
    pairs : list of eval.pairs.Pair
    real : dict of int to list of eval.pairs.RealWindow
    done : list of (kind, outcome)
        Every task's result (``pair``, ``real`` or ``inbetween``), in any order.

    Returns
    -------
    dict
        ``records``, ``pairs``, ``real``, ``clips`` and ``timing_ms`` of
        :class:`eval.study.StudyResult`.
    """
    config = data.config
    clips = clip_records(data)
    records = Records(SCORE_METRICS)
    for kind, outcome in done:
        if kind in ("pair", INBETWEEN):
            for frames, method, values in outcome["scores"]:
                records.add(kind, outcome["index"], frames, method, values)
        else:
            records.add(REAL, outcome["index"], outcome["frames"], REAL, outcome["scores"])
    by_pair = {r["index"]: r for kind, r in done if kind == "pair"}
    # a method not scored on a pair (performed past performed_pairs) has no time there
    timing = {frames: {m: [ms for p in pairs
                           if math.isfinite(ms := by_pair[p.index]["ms"][frames][m])]
                       for m in config.methods} for frames in config.windows}
    real_records = {frames: [{"id": w.index, "clip": w.clip, "start": w.start, "stop": w.stop,
                              "flat_floor": clips[w.clip]["flat_floor"]} for w in ws]
                    for frames, ws in real.items()}
    return {"records": records, "clips": clips, "timing_ms": timing, "real": real_records,
            "pairs": [pair_record(data, p, by_pair[p.index], clips) for p in pairs]}
