"""Validity reports: plain JSON (per frame, per transition window, totals) and a CSV
summary table, written atomically.

The JSON document (``schema`` = :data:`SCHEMA`, ``schema_version`` =
:data:`SCHEMA_VERSION`)::

    {
      "schema": "upm-controller/validity", "schema_version": 2,
      "kind": "check" | "simulate",
      "motion": {name, frames, fps, seconds, skeleton, model, mass_kg, stature_m, ...},
      "settings": {thresholds and methods, with units in their names},
      "software": {"python", "upm-controller", "mujoco", "numpy", "scipy", ...: versions},
      "totals": {"kinematic": {...}, "dynamics": {...}, "tracking": {mode: {...}}},
      "windows": [{"index", "start", "stop", "frames", ...meta,
                   "kinematic": {...}, "dynamics": {...}, "tracking": {mode: {...}}}],
      "pieces": [{"index", "name", "start", "stop", "kinematic": {...}, ...}],
      "frames": [{"frame", "time_s", "window", "valid", ..., "residual_force_bw", ...,
                  "free_error_deg", "driven_error_deg", ...}]
    }

Version 2: the free-root tracking is by default the balance controller
(``controller.balance.follow``; ``settings.tracking.free_controller``), and its part figures
(totals, windows, pieces, and each window's own ``free_window`` run) add to ``fell``,
``fall_time_s`` and ``error_deg_rms``: ``body_error_mm_mean``/``_peak``, ``root_drift_m``,
``heading_error_deg_peak`` (added within version 2; readers of older version-2 reports
find it missing), ``com_height_error_m``, ``contact_force_peak_bw``/``_mean_bw``,
``torque_peak_nm``/``_mean_nm``, ``torque_saturation_share``, ``trouble_time_s`` and
``ends_in_trouble`` (the time the character went on in trouble, by the search's test in the run's
``trouble_rule``, and whether the part's last frame before any fall is in trouble: going
down without having fallen yet; per frame ``free_trouble``), ``wall_s_per_sim_s`` and
``raw_steps_per_step`` (the controller's cost in raw ``mj_step`` equivalents). The whole
run's figures (``totals.tracking.free``) also list ``search_troubles`` (added within
version 2): every trouble the search worked on, ``{"frame", "time_s", "cause", "retries",
"rerun_s", "outcome", "restarts_by_mode", "rerun_s_by_mode", "last_mode"}``
(:class:`controller.balance.search.SearchTrouble`; the last three added within version 2:
the retries and the seconds run again by the mode of the segment each restart changed,
one entry per mode of the configuration's ``modes``, and the mode of the last
restart, the change that got past the trouble when it did); and every part's,
``torque_by_actuator`` (added within version 2; JSON only): per actuator ``{"peak_nm",
"mean_nm", "range_nm", "saturation_share", "saturated_concentric_share"}``: the torque's
largest and mean magnitude, the actuator's range ``[least, largest]`` (its strength either
way), the share of the part's frames before any fall at which it was at either end, and,
of those frames, the share at which the joint turned the way its torque pushed (positive
work: the muscles across it shortening, where a real muscle holds less than the isometric
peak the strength is; ``null`` when the joint was never at its strength; the last key
added within version 2, missing from older reports).

Every part's figures of a free-root balance run also take its errors apart by where the
search worked (added within version 2, missing from older reports): ``search_mode_share``
(the share of the part's frames before any fall run in a mode the search changed, not the
default: ``controller.balance.search.frame_modes``), and ``error_deg_rms`` and
``body_error_mm_mean`` over the frames run in the default mode (``..._default_mode``) and
over those the search changed (``..._search_modes``; ``null`` where there are none).

``settings.strength`` (added within version 2; readers of older reports take 1): every
joint's torque limit was the strength tables' times this (``upm simulate --strength``).

``settings.controller_config`` (added within version 2, missing from older reports): every
tuning constant of the controller, the servo tracking and the residual check the report
was made with (:meth:`controller.config.ControllerConfig.as_dict`; ``upm simulate
--config``); ``ControllerConfig.from_dict`` of it gives the same configuration, and the
same motion with it the same run.

``software`` names the versions the figures were computed with: a free-root run is
deterministic on one installation, but its search takes discrete decisions, so another
MuJoCo or numpy release can change them (and a long sequence's figures with them).

Frame numbers are 0-based frames of the (joined) motion; a window is the half-open
frame range ``start:stop``; a frame's ``window`` is the index of the window it lies in
(``null`` outside windows). Non-finite numbers are written as ``null``.

The CSV has one row per part — ``all``, each window, each piece — and one column per
scalar figure (the same names as the JSON; tracking figures prefixed by their mode,
``free_`` or ``driven_``).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from pathlib import Path

import numpy as np

from controller.checks.validity import Validity, frame_records, summarize

SCHEMA = "upm-controller/validity"
#: Bumped whenever a field changes meaning or is removed.
SCHEMA_VERSION = 2


def build_report(kind: str, validity: Validity, *, motion: dict | None = None,
                 settings: dict | None = None, residual=None, tracking=None,
                 window_meta=None, window_tracking=None, pieces=None) -> dict:
    """Assemble a report.

    Parameters
    ----------
    kind : str
        ``"check"`` or ``"simulate"``.
    validity : Validity
        The kinematic checks (its ``windows`` are the report's windows).
    motion, settings : dict, optional
        Descriptions copied into the report.
    residual : controller.checks.dynamics.RootResidual, optional
    tracking : dict of str to controller.tracking.Tracking, optional
        Whole-motion simulations by mode (``"free"``, ``"driven"``).
    window_meta : list of dict, optional
        Extra fields per window (method, compute seconds, ...).
    window_tracking : list of dict, optional
        Per window, JSON-ready results of simulations of that window alone (e.g. the free
        root started shortly before it).
    pieces : list of (str, slice), optional
        The motion's pieces (clips of a sequence) by name.

    Returns
    -------
    dict
        JSON-ready (see the module docstring).
    """
    tracking = dict(tracking or {})
    frames = frame_records(validity)
    if residual is not None:
        force, torque = residual.force_bw, residual.torque_bwh
        needed = residual.needed_force_bw
        for t, record in enumerate(frames):
            record["residual_force_bw"] = _num(force[t])
            record["residual_torque_bwh"] = _num(torque[t])
            record["needed_force_bw"] = _num(needed[t])
            record["support_points"] = int(residual.support_points[t])
    for mode, run in tracking.items():
        error = run.error_deg
        fallen = run.fallen
        trouble = getattr(run, "trouble", None)  # the balance controller's
        for t, record in enumerate(frames):
            record[f"{mode}_error_deg"] = _num(error[t])
            record[f"{mode}_limit_rows"] = int(run.limit_rows[t])
            record[f"{mode}_self_contacts"] = int(run.self_contacts[t])
            record[f"{mode}_fallen"] = bool(fallen[t])
            if trouble is not None:
                record[f"{mode}_trouble"] = bool(trouble[t])

    def part_figures(part: slice | None) -> dict:
        out = {"kinematic": summarize(validity, part)}
        if residual is not None:
            out["dynamics"] = residual.summary(part)
        if tracking:
            out["tracking"] = {mode: run.summary(part) for mode, run in tracking.items()}
        return out

    windows = []
    for k, window in enumerate(validity.windows):
        start, stop, _ = window.indices(validity.n_frames)
        entry = {"index": k, "start": start, "stop": stop, "frames": stop - start}
        if window_meta is not None:
            entry.update(window_meta[k])
        entry.update(part_figures(window))
        if window_tracking is not None:
            entry.setdefault("tracking", {}).update(window_tracking[k])
        windows.append(entry)
    piece_entries = []
    for k, (name, part) in enumerate(pieces or ()):
        start, stop, _ = part.indices(validity.n_frames)
        piece_entries.append({"index": k, "name": name, "start": start, "stop": stop,
                              **part_figures(part)})
    totals = part_figures(None)
    if tracking:
        totals["tracking"] = {mode: run.run_summary() for mode, run in tracking.items()}
    report = {
        "schema": SCHEMA,
        "schema_version": SCHEMA_VERSION,
        "kind": kind,
        "motion": dict(motion or {"name": validity.name, "frames": validity.n_frames,
                                  "fps": validity.fps}),
        "settings": dict(settings or {}),
        "software": software_versions(),
        "totals": totals,
        "windows": windows,
        "pieces": piece_entries,
        "frames": frames,
    }
    return _clean(report)


#: The distributions whose versions a report records (those the figures depend on).
SOFTWARE = ("upm-controller", "mujoco", "numpy", "scipy", "quadprog", "numba")


def software_versions() -> dict:
    """The Python version and those of :data:`SOFTWARE` (``None`` where not installed)."""
    import platform
    from importlib import metadata

    out = {"python": platform.python_version()}
    for name in SOFTWARE:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def summary_rows(report: dict) -> list[dict]:
    """The CSV table of a report: one row per part (``all``, ``window K``, ``piece K``),
    the scalar figures as columns."""
    rows = [{"part": "all", "start": 0, "stop": report["motion"].get("frames"),
             **_flat(report["totals"])}]
    for w in report["windows"]:
        rows.append({"part": f"window {w['index']}", "start": w["start"], "stop": w["stop"],
                     **{k: v for k, v in w.items() if _scalar(v)
                        and k not in ("index", "start", "stop")},
                     **_flat({k: w[k] for k in ("kinematic", "dynamics", "tracking")
                              if k in w})})
    for p in report["pieces"]:
        rows.append({"part": f"piece {p['index']}", "start": p["start"], "stop": p["stop"],
                     "name": p["name"],
                     **_flat({k: p[k] for k in ("kinematic", "dynamics", "tracking")
                              if k in p})})
    return rows


def csv_text(rows: list[dict]) -> str:
    """Rows as CSV text (columns in first-seen order; missing cells empty)."""
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: "" if v is None else v for k, v in row.items()})
    return buffer.getvalue()


def write_report(report: dict, json_path: str | os.PathLike,
                 csv_path: str | os.PathLike | None = None) -> tuple[Path, Path]:
    """Write the JSON report and its CSV summary atomically.

    Parameters
    ----------
    report : dict
    json_path : path-like
    csv_path : path-like, optional
        Default: ``json_path`` with the suffix ``.csv``.

    Returns
    -------
    (Path, Path)
        The JSON and CSV paths written.
    """
    from upm.core.fileio import atomic_write_text

    json_path = Path(json_path)
    csv_path = Path(csv_path) if csv_path is not None else json_path.with_suffix(".csv")
    if csv_path == json_path:
        csv_path = json_path.with_name(json_path.name + ".csv")
    atomic_write_text(json_path, json.dumps(report, indent=1, allow_nan=False) + "\n")
    atomic_write_text(csv_path, csv_text(summary_rows(report)))
    return json_path, csv_path


#: Per-name breakdowns kept in the JSON only (their keys vary from row to row).
_JSON_ONLY = frozenset({"pairs", "dofs", "limit_joint_frames", "warnings",
                        "torque_by_actuator"})


def _flat(tree: dict, prefix: str = "") -> dict:
    """Scalar leaves of nested dicts as ``prefix_key`` columns. At the top level the
    ``kinematic``, ``dynamics`` and ``tracking`` groups add no prefix (their keys are
    distinct; tracking's modes do: ``free_error_deg_rms``)."""
    out = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            if key in _JSON_ONLY:
                continue
            group = not prefix and key in ("kinematic", "dynamics", "tracking")
            out.update(_flat(value, "" if group else f"{prefix}{key}_"))
        elif _scalar(value):
            out[f"{prefix}{key}"] = value
    return out


def _scalar(value) -> bool:
    return value is None or isinstance(value, (bool, int, float, str))


def _num(x) -> float | None:
    x = float(x)
    return round(x, 5) if math.isfinite(x) else None


def _clean(obj):
    """JSON-ready: numpy scalars to Python, non-finite floats to None."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    return obj
