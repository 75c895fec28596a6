"""Kinematic validity of every frame of a motion (SPEC section 6).

Per frame, with the humanoid set to the frame's posture (``mj_kinematics`` +
``mj_collision``, no dynamics):

- **joint-limit violation**: for each of the 63 posture DOFs, the degrees beyond its ASF
  range, 0 inside (on the circle, tolerance 1e-6 degrees:
  :func:`upm.motion.limits.limit_excess_deg`);
- **self-collision**: contacts between humanoid bodies that the model does not exclude,
  with their depth; a frame is in self-collision when one is deeper than 1 mm, and the
  body pairs are named;
- **floor penetration**: the deepest geom below the floor; it counts beyond 1 cm.

A frame is **valid** when it has none of the three. Real CMU frames break their own ASF
limits often, so for a transition window the report also gives the **added** excess: per
DOF, what a window frame exceeds beyond the larger excess of its two end postures (clip
1's last frame before the window, clip 2's first frame after it) — what the method added.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.checks.contacts import SELF_COLLISION_DEPTH_M, ContactTable
from upm.motion.skeleton import POSTURE_DOF_NAMES

#: A geom deeper than this below the floor makes a frame invalid, metres.
FLOOR_TOLERANCE_M = 0.01


@dataclass(frozen=True)
class Validity:
    """The kinematic checks of every frame of one motion.

    Attributes
    ----------
    name : str
        The motion's name.
    fps : float
    limit_excess_deg : ndarray, shape (T, 63)
        Degrees beyond each posture DOF's ASF range (0 inside).
    contacts : ContactTable
        Every self- and floor contact of every frame (depth >= 0).
    windows : tuple of slice
        Transition windows (frame ranges) within the motion; empty for a plain clip.
    added_excess_deg : ndarray, shape (T, 63)
        Inside a window: the excess beyond the larger excess of the window's two end
        postures, per DOF; 0 outside windows.
    """

    name: str
    fps: float
    limit_excess_deg: np.ndarray
    contacts: ContactTable
    windows: tuple[slice, ...]
    added_excess_deg: np.ndarray

    @property
    def n_frames(self) -> int:
        return self.limit_excess_deg.shape[0]

    @property
    def limit_violation(self) -> np.ndarray:
        """Frames with a DOF beyond its limit, bool (T,)."""
        return self.limit_excess_deg.max(axis=1, initial=0.0) > 0

    @property
    def max_excess_deg(self) -> np.ndarray:
        """The largest excess of each frame, (T,) degrees."""
        return self.limit_excess_deg.max(axis=1, initial=0.0)

    @property
    def added_limit_violation(self) -> np.ndarray:
        """Window frames with a DOF beyond what the window's ends already exceed, (T,)."""
        return self.added_excess_deg.max(axis=1, initial=0.0) > 0

    @property
    def self_depth_m(self) -> np.ndarray:
        """Deepest self-contact per frame, (T,) metres (0 if none)."""
        return self.contacts.max_self_depth_m()

    @property
    def floor_depth_m(self) -> np.ndarray:
        """Deepest geom below the floor per frame, (T,) metres (0 if none)."""
        return self.contacts.floor_depth_m()

    @property
    def self_collision(self) -> np.ndarray:
        """Frames with a self-contact deeper than 1 mm, bool (T,)."""
        return self.self_depth_m > SELF_COLLISION_DEPTH_M

    @property
    def floor_penetration(self) -> np.ndarray:
        """Frames with a geom more than 1 cm below the floor, bool (T,)."""
        return self.floor_depth_m > FLOOR_TOLERANCE_M

    @property
    def valid(self) -> np.ndarray:
        """Frames with no limit violation, no self-collision and no floor penetration."""
        return ~(self.limit_violation | self.self_collision | self.floor_penetration)

    @property
    def valid_beyond_ends(self) -> np.ndarray:
        """As :attr:`valid`, with the *added* limit excess in place of the raw one (the
        same as :attr:`valid` outside windows), bool (T,)."""
        limits = np.where(self.in_window >= 0, self.added_limit_violation,
                          self.limit_violation)
        return ~(limits | self.self_collision | self.floor_penetration)

    @property
    def in_window(self) -> np.ndarray:
        """Index of the window each frame lies in, -1 outside windows, int (T,)."""
        out = np.full(self.n_frames, -1)
        for k, window in enumerate(self.windows):
            out[window] = k
        return out

    def violating_dofs(self, frame: int) -> dict[str, float]:
        """The DOFs beyond their limits in one frame: ``{"lfemur.rx": degrees}``,
        largest first."""
        row = self.limit_excess_deg[frame]
        order = np.argsort(-row, kind="stable")
        return {POSTURE_DOF_NAMES[i]: float(row[i]) for i in order if row[i] > 0}

    def self_pairs(self, depth_m: float = SELF_COLLISION_DEPTH_M) -> list[dict[str, float]]:
        """Per frame, the body pairs in self-collision and their depth:
        ``[{"lhand-rhand": 0.004}, ...]`` (metres; one dict per frame, empty if none)."""
        c = self.contacts
        keep = ~c.is_floor & (c.depth_m > depth_m)
        out: list[dict[str, float]] = [{} for _ in range(self.n_frames)]
        for t, a, b, d in zip(c.frame[keep], c.body1[keep], c.body2[keep], c.depth_m[keep],
                              strict=True):
            key = f"{c.body_names[a]}-{c.body_names[b]}"
            out[t][key] = max(out[t].get(key, 0.0), float(d))
        return out

    def frames_of(self, part: slice | None = None) -> np.ndarray:
        """Frame indices of a part of the motion (all frames if ``part`` is None)."""
        return np.arange(self.n_frames)[part if part is not None else slice(None)]


def limit_excess(posture_deg, limits_deg) -> np.ndarray:
    """Degrees beyond each DOF's range (see :func:`upm.motion.limits.limit_excess_deg`).

    Parameters
    ----------
    posture_deg : array_like, shape (T, 63)
    limits_deg : array_like, shape (63, 2)

    Returns
    -------
    ndarray, shape (T, 63)
    """
    from upm.motion.limits import limit_excess_deg

    return limit_excess_deg(np.atleast_2d(posture_deg), limits_deg)


def added_excess(excess_deg, windows) -> np.ndarray:
    """The excess of window frames beyond what their two end postures already have.

    Parameters
    ----------
    excess_deg : array_like, shape (T, D)
        Per-frame excess (:func:`limit_excess`).
    windows : sequence of slice
        Window frame ranges; a window's ends are the frames just before and just after
        it (the frame inside the motion where the window touches an end of the motion).

    Returns
    -------
    ndarray, shape (T, D)
        ``max(excess - max(excess[before], excess[after]), 0)`` per DOF inside each
        window, 0 elsewhere.
    """
    excess = np.asarray(excess_deg, dtype=float)
    out = np.zeros_like(excess)
    n = excess.shape[0]
    for window in windows:
        start, stop, _ = window.indices(n)
        if start >= stop:
            continue
        before = excess[max(start - 1, 0)]
        after = excess[min(stop, n - 1)]
        out[start:stop] = np.maximum(excess[start:stop] - np.maximum(before, after), 0.0)
    return out


def check_motion(model, motion, windows=()) -> Validity:
    """The kinematic checks of every frame of a motion.

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid of the motion's skeleton (:func:`humanoid_xml.subject_model_path`),
        so that bone lengths match.
    motion : upm.Motion
        Its limits are its skeleton's (``motion.skeleton.limits_deg``).
    windows : sequence of slice
        Transition windows within the motion, if any.

    Returns
    -------
    Validity
    """
    from controller.checks.contacts import contacts_over_frames
    from controller.qpos import to_qpos

    windows = tuple(windows)
    excess = limit_excess(motion.posture_deg, motion.skeleton.limits_deg)
    table = contacts_over_frames(model, to_qpos(model, motion))
    return Validity(name=motion.name, fps=float(motion.fps), limit_excess_deg=excess,
                    contacts=table, windows=windows,
                    added_excess_deg=added_excess(excess, windows))


def summarize(validity: Validity, part: slice | None = None) -> dict:
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
        "floor_penetration_frames": int(validity.floor_penetration[index].sum()),
        "floor_penetration_pct": _pct(validity.floor_penetration[index].sum(), n),
        "floor_depth_peak_mm": round(1000 * float(validity.floor_depth_m[index].max(initial=0)),
                                     3),
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
    out["dofs"] = {POSTURE_DOF_NAMES[i]: int(dof_frames[i])
                   for i in np.argsort(-dof_frames, kind="stable") if dof_frames[i] > 0}
    return out


def frame_records(validity: Validity) -> list[dict]:
    """One JSON-ready record per frame: ``frame``, ``time_s``, ``window`` (index or None),
    ``valid``, ``limit_violation``, ``limit_excess_max_deg``, ``limit_dofs`` (DOF ->
    degrees beyond), ``self_collision``, ``self_depth_mm``, ``self_pairs`` (pair -> mm),
    ``floor_penetration``, ``floor_depth_mm``; in windows also ``added_excess_max_deg``,
    ``added_dofs`` and ``valid_beyond_ends``."""
    pairs = validity.self_pairs()
    window = validity.in_window
    max_excess = validity.max_excess_deg
    added = validity.added_excess_deg
    self_depth, floor_depth = validity.self_depth_m, validity.floor_depth_m
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
            "floor_penetration": bool(floor[t]),
            "floor_depth_mm": round(1000 * float(floor_depth[t]), 3),
        }
        if window[t] >= 0:
            row = added[t]
            record["added_excess_max_deg"] = round(float(row.max()), 4)
            record["added_dofs"] = {POSTURE_DOF_NAMES[i]: round(float(row[i]), 4)
                                    for i in np.flatnonzero(row > 0)}
            record["valid_beyond_ends"] = bool(beyond[t])
        records.append(record)
    return records


@dataclass(frozen=True)
class Calibration:
    """The kinematic checks of real clips, each on its own subject's model.

    Attributes
    ----------
    clips : dict of str to dict
        Per clip, :func:`summarize` of the whole clip (plus ``split``).
    """

    clips: dict[str, dict]

    def totals(self, names=None) -> dict:
        """Frame-weighted totals over some clips (all by default), JSON-ready."""
        rows = [self.clips[n] for n in (self.clips if names is None else names)]
        frames = sum(r["frames"] for r in rows)
        out = {"clips": len(rows), "frames": frames}
        for key in ("valid", "limit_violation", "self_collision", "floor_penetration"):
            count = sum(r[f"{key}_frames"] for r in rows)
            out[f"{key}_frames"] = count
            out[f"{key}_pct"] = _pct(count, frames)
        out["limit_excess_mean_deg"] = round(
            sum(r["limit_excess_mean_deg"] * r["frames"] for r in rows) / max(frames, 1), 4)
        out["limit_excess_peak_deg"] = max((r["limit_excess_peak_deg"] for r in rows),
                                           default=0.0)
        return out


def calibrate(catalog, names=None) -> Calibration:
    """The kinematic checks of real clips: the calibration of every validity figure.

    Parameters
    ----------
    catalog : upm.motion.catalog.Catalog
    names : iterable of str, optional
        Clip names (default: every clip).
    """
    from humanoid_xml import catalog_model_path, load_model
    from upm.core.progress import progress

    names = list(catalog.names() if names is None else names)
    models: dict[str, object] = {}
    clips = {}
    for name in progress(names, desc="checking clips", unit="clip"):
        info = catalog.info(name)
        if info.subject not in models:
            models[info.subject] = load_model(catalog_model_path(catalog, info.subject))
        summary = summarize(check_motion(models[info.subject], catalog.load(name)))
        clips[name] = {"split": info.split, **summary}
    return Calibration(clips=clips)


def _pct(count, total) -> float:
    return round(100.0 * float(count) / total, 2) if total else 0.0
