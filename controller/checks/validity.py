"""Kinematic validity of every frame of a motion (SPEC section 6, calibrated).

Per frame, with the humanoid set to the frame's posture (``mj_kinematics`` +
``mj_collision``, no dynamics):

- **beyond the human range**: per rule of the range model (default ``human``:
  :mod:`upm.motion.human_rom`, the hips and shoulders coupled), the degrees beyond it;
  ``--limits asf`` judges by the ASF's declared boxes instead. The degrees beyond the
  ASF's declared limits are always reported beside it (``beyond_asf``), not judged;
- **self-interpenetration**: a contact between two humanoid bodies deeper than soft
  tissue allows for that pair of body classes (:mod:`controller.checks.tissue`,
  calibrated on the train split); shallower contact is touching, and allowed;
- **through the floor**: a geom deeper below the floor than its class allows (a heel pad
  rolling on the floor is not a foot through it).

A frame is **valid** when it has none of the three. For a transition window the report
also gives the **added** excess: per rule, what a window frame exceeds beyond the larger
excess of its two end postures — what the method added.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.checks.contacts import ContactTable
from controller.checks.tissue import TOUCH_M, allowed_depth_m

#: The allowance of a body class the floor table does not list, metres (a geom deeper
#: than its class's allowance below the floor makes a frame invalid).
FLOOR_TOLERANCE_M = TOUCH_M


@dataclass(frozen=True)
class Validity:
    """The kinematic checks of every frame of one motion.

    Attributes
    ----------
    name : str
        The motion's name.
    fps : float
    limit_excess_deg : ndarray, shape (T, R)
        Degrees beyond each rule of the range model (0 inside).
    contacts : ContactTable
        Every self- and floor contact of every frame (depth >= 0).
    windows : tuple of slice
        Transition windows (frame ranges) within the motion; empty for a plain clip.
    added_excess_deg : ndarray, shape (T, R)
        Inside a window: the excess beyond the larger excess of the window's two end
        postures, per rule; 0 outside windows.
    rule_names : tuple of str, length R
        The range model's rules (``"ltibia.flexion"``, ``"lfemur.swing"``, or ASF DOFs).
    limits : str
        The range model's name (``"human"``, ``"asf"`` or a file).
    asf_excess_deg : ndarray, shape (T, 63)
        Degrees beyond the ASF's declared boxes (reported, not judged by ``human``).
    contact_excess_m : ndarray, shape (K,)
        Each contact's depth beyond its allowance (0 when touching).
    """

    name: str
    fps: float
    limit_excess_deg: np.ndarray
    contacts: ContactTable
    windows: tuple[slice, ...]
    added_excess_deg: np.ndarray
    rule_names: tuple[str, ...]
    limits: str
    asf_excess_deg: np.ndarray
    contact_excess_m: np.ndarray

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
    def beyond_asf(self) -> np.ndarray:
        """Frames beyond a limit the ASF declares (reported, not judged), bool (T,)."""
        return self.asf_excess_deg.max(axis=1, initial=0.0) > 0

    def _frame_max(self, values: np.ndarray, floor: bool) -> np.ndarray:
        c = self.contacts
        keep = c.is_floor if floor else ~c.is_floor
        out = np.zeros(self.n_frames)
        np.maximum.at(out, c.frame[keep], values[keep])
        return out

    @property
    def self_excess_m(self) -> np.ndarray:
        """Deepest self-contact beyond its pair's allowance per frame, (T,) metres."""
        return self._frame_max(self.contact_excess_m, floor=False)

    @property
    def floor_excess_m(self) -> np.ndarray:
        """Deepest floor contact beyond its class's allowance per frame, (T,) metres."""
        return self._frame_max(self.contact_excess_m, floor=True)

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
        """Frames with a self-contact deeper than its pair's allowance, bool (T,)."""
        return self.self_excess_m > 0

    @property
    def self_touch(self) -> np.ndarray:
        """Frames whose bodies touch (overlap within the allowance only), bool (T,)."""
        return (self.self_depth_m > 0) & ~self.self_collision

    @property
    def floor_penetration(self) -> np.ndarray:
        """Frames with a geom deeper below the floor than its class allows, bool (T,)."""
        return self.floor_excess_m > 0

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
        """The rules broken in one frame: ``{"lfemur.swing": degrees}``, largest first."""
        row = self.limit_excess_deg[frame]
        order = np.argsort(-row, kind="stable")
        return {self.rule_names[i]: float(row[i]) for i in order if row[i] > 0}

    def self_pairs(self) -> list[dict[str, float]]:
        """Per frame, the body pairs interpenetrating beyond their allowance and their
        depth: ``[{"lhand-rhand": 0.064}, ...]`` (metres; one dict per frame)."""
        c = self.contacts
        keep = ~c.is_floor & (self.contact_excess_m > 0)
        out: list[dict[str, float]] = [{} for _ in range(self.n_frames)]
        for t, a, b, d in zip(c.frame[keep], c.body1[keep], c.body2[keep], c.depth_m[keep],
                              strict=True):
            key = f"{c.body_names[a]}-{c.body_names[b]}"
            out[t][key] = max(out[t].get(key, 0.0), float(d))
        return out

    def frames_of(self, part: slice | None = None) -> np.ndarray:
        """Frame indices of a part of the motion (all frames if ``part`` is None)."""
        return np.arange(self.n_frames)[part if part is not None else slice(None)]


def limit_excess(posture_deg, limits_deg) -> np.ndarray:  # per-DOF boxes (feasible)
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


def check_motion(model, motion, windows=(), limits=None) -> Validity:
    """The kinematic checks of every frame of a motion.

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid of the motion's skeleton (:func:`humanoid_xml.subject_model_path`),
        so that bone lengths match.
    motion : upm.Motion
    windows : sequence of slice
        Transition windows within the motion, if any.
    limits : str or upm.motion.range_models.RangeModel, optional
        The range model (``"human"``, the default; ``"asf"``; a JSON file).

    Returns
    -------
    Validity
    """
    from controller.checks.contacts import contacts_over_frames
    from controller.qpos import to_qpos
    from upm.motion.range_models import asf_excess_deg, range_model

    windows = tuple(windows)
    ranges = range_model(limits)
    excess = ranges.excess_deg(motion.skeleton, motion.posture_deg)
    table = contacts_over_frames(model, to_qpos(model, motion))
    allowed = allowed_depth_m(table.body_names, table.body1, table.body2)
    return Validity(name=motion.name, fps=float(motion.fps), limit_excess_deg=excess,
                    contacts=table, windows=windows,
                    added_excess_deg=added_excess(excess, windows),
                    rule_names=ranges.rule_names, limits=ranges.name,
                    asf_excess_deg=asf_excess_deg(motion.skeleton, motion.posture_deg),
                    contact_excess_m=np.maximum(table.depth_m - allowed, 0.0))


from controller.checks.validity_report import (  # noqa: E402  (the report of a Validity)
    frame_records,
    summarize,
)

__all__ = ["Validity", "check_motion", "limit_excess", "added_excess", "summarize",
           "frame_records", "FLOOR_TOLERANCE_M"]
