"""The report of a :class:`~controller.checks.validity.Validity`: totals and frame
records (JSON-ready). The functions take the Validity (duck-typed: this module imports
nothing of the checks, so that validity can re-export it)."""

from __future__ import annotations

import numpy as np


def summarize(validity, part: slice | None = None) -> dict:
    """Totals of a part of the motion (all of it by default), JSON-ready.

    Returns
    -------
    dict
        ``frames``; ``valid_frames`` and ``valid_pct``; ``limit_violation_frames``,
        ``limit_excess_mean_deg`` (mean over frames of each frame's largest excess, 0
        for frames inside the limits) and ``limit_excess_peak_deg``;
        ``self_collision_frames`` and ``self_depth_peak_mm``; ``floor_penetration_frames``
        and ``floor_depth_peak_mm``; for parts with window frames, the same limit figures
        for the added excess (``added_*``) and ``valid_beyond_ends_frames``; ``pairs``:
        body pair -> frames in self-collision; ``dofs``: DOF -> frames beyond its limit.
    """
    index = validity.frames_of(part)
    n = int(index.size)
    excess = validity.limit_excess_deg[index]
    per_frame = excess.max(axis=1, initial=0.0)
    pairs: dict[str, int] = {}
    frame_pairs = validity.self_pairs()
    for t in index:
        for key in frame_pairs[t]:
            pairs[key] = pairs.get(key, 0) + 1
    dof_frames = (excess > 0).sum(axis=0)
    out = {
        "frames": n,
        "valid_frames": int(validity.valid[index].sum()),
        "valid_pct": _pct(validity.valid[index].sum(), n),
        "limit_violation_frames": int((per_frame > 0).sum()),
        "limit_violation_pct": _pct((per_frame > 0).sum(), n),
        "limit_excess_mean_deg": round(float(per_frame.mean()) if n else 0.0, 4),
        "limit_excess_peak_deg": round(float(per_frame.max(initial=0.0)), 4),
        "self_collision_frames": int(validity.self_collision[index].sum()),
        "self_collision_pct": _pct(validity.self_collision[index].sum(), n),
        "self_depth_peak_mm": round(1000 * float(validity.self_depth_m[index].max(initial=0)),
                                    3),
        "self_touch_frames": int(validity.self_touch[index].sum()),
        "self_excess_peak_mm": round(
            1000 * float(validity.self_excess_m[index].max(initial=0)), 3),
        "floor_penetration_frames": int(validity.floor_penetration[index].sum()),
        "floor_penetration_pct": _pct(validity.floor_penetration[index].sum(), n),
        "floor_depth_peak_mm": round(1000 * float(validity.floor_depth_m[index].max(initial=0)),
                                     3),
        "limits": validity.limits,
        "beyond_asf_frames": int(validity.beyond_asf[index].sum()),
        "beyond_asf_pct": _pct(validity.beyond_asf[index].sum(), n),
        "asf_excess_mean_deg": round(float(
            validity.asf_excess_deg[index].max(axis=1, initial=0.0).mean()) if n else 0.0, 4),
    }
    in_window = validity.in_window[index] >= 0
    if in_window.any():
        added = validity.added_excess_deg[index][in_window].max(axis=1, initial=0.0)
        m = int(in_window.sum())
        out.update({
            "window_frames": m,
            "added_limit_violation_frames": int((added > 0).sum()),
            "added_limit_violation_pct": _pct((added > 0).sum(), m),
            "added_excess_mean_deg": round(float(added.mean()), 4),
            "added_excess_peak_deg": round(float(added.max(initial=0.0)), 4),
            "valid_beyond_ends_frames": int(validity.valid_beyond_ends[index].sum()),
        })
    out["pairs"] = dict(sorted(pairs.items(), key=lambda kv: (-kv[1], kv[0])))
    # "dofs": the range model's rules (ASF DOF names with --limits asf)
    out["dofs"] = {validity.rule_names[i]: int(dof_frames[i])
                   for i in np.argsort(-dof_frames, kind="stable") if dof_frames[i] > 0}
    return out


def frame_records(validity) -> list[dict]:
    """One JSON-ready record per frame: ``frame``, ``time_s``, ``window`` (index or None),
    ``valid``, ``limit_violation``, ``limit_excess_max_deg``, ``limit_dofs`` (rule ->
    degrees beyond), ``self_collision``, ``self_depth_mm``, ``self_pairs`` (pairs beyond
    their allowance -> mm), ``self_excess_mm``, ``beyond_asf``, ``floor_penetration``,
    ``floor_depth_mm``, ``floor_excess_mm``; in windows also ``added_excess_max_deg``,
    ``added_dofs`` and ``valid_beyond_ends``."""
    pairs = validity.self_pairs()
    window = validity.in_window
    max_excess = validity.max_excess_deg
    added = validity.added_excess_deg
    self_depth, floor_depth = validity.self_depth_m, validity.floor_depth_m
    self_excess, floor_excess = validity.self_excess_m, validity.floor_excess_m
    beyond_asf = validity.beyond_asf
    valid, beyond = validity.valid, validity.valid_beyond_ends
    limit, self_col, floor = (validity.limit_violation, validity.self_collision,
                              validity.floor_penetration)
    records = []
    for t in range(validity.n_frames):
        record = {
            "frame": t,
            "time_s": round(t / validity.fps, 6),
            "window": int(window[t]) if window[t] >= 0 else None,
            "valid": bool(valid[t]),
            "limit_violation": bool(limit[t]),
            "limit_excess_max_deg": round(float(max_excess[t]), 4),
            "limit_dofs": {k: round(v, 4) for k, v in validity.violating_dofs(t).items()}
            if limit[t] else {},
            "self_collision": bool(self_col[t]),
            "self_depth_mm": round(1000 * float(self_depth[t]), 3),
            "self_pairs": {k: round(1000 * v, 3) for k, v in pairs[t].items()},
            "self_excess_mm": round(1000 * float(self_excess[t]), 3),
            "beyond_asf": bool(beyond_asf[t]),
            "floor_penetration": bool(floor[t]),
            "floor_depth_mm": round(1000 * float(floor_depth[t]), 3),
            "floor_excess_mm": round(1000 * float(floor_excess[t]), 3),
        }
        if window[t] >= 0:
            row = added[t]
            record["added_excess_max_deg"] = round(float(row.max()), 4)
            record["added_dofs"] = {validity.rule_names[i]: round(float(row[i]), 4)
                                    for i in np.flatnonzero(row > 0)}
            record["valid_beyond_ends"] = bool(beyond[t])
        records.append(record)
    return records


def _pct(count, total) -> float:
    return round(100.0 * float(count) / total, 2) if total else 0.0
