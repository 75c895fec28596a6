"""The result of a servo tracking simulation (:mod:`controller.tracking.servo`): per-frame
arrays and their summaries per part of the motion, JSON-ready."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controller.checks.contacts import SELF_COLLISION_DEPTH_M
from controller.config import DEFAULT, ControllerConfig
from controller.falls import rule_text


@dataclass(frozen=True)
class Tracking:
    """One tracking simulation of a motion.

    Attributes
    ----------
    mode : str
        ``"free"`` or ``"driven"``.
    fps : float
        The motion's frame rate (the per-frame arrays are at its frames).
    timestep_s : float
        The physics step used.
    steps : int
        Physics steps simulated.
    wall_s : float
        Wall-clock seconds of the stepping loop.
    hinge_names : tuple of str
        Posture DOF of each hinge (``"lfemur.rx"``), the columns of ``dof_error_deg``.
    qpos : ndarray, shape (T, nq)
        The simulated state at every frame (NaN after a divergence).
    dof_error_deg : ndarray, shape (T, H)
        Simulated minus reference hinge angle, wrapped to [-180, 180), degrees.
    dof_reachable_error_deg : ndarray, shape (T, H)
        Simulated angle minus the reference clamped into the hinge's range (what the
        servo is asked to reach: a reference beyond its ASF limit cannot be), degrees.
    limit_rows : ndarray of int, shape (T,)
        Active joint-limit constraint rows at each frame.
    limit_steps : int
        Steps with at least one joint-limit row active.
    limit_joint_frames : dict of str to int
        Per hinge, frames at which its limit was active (most first).
    self_contacts : ndarray of int, shape (T,)
        Self-contacts (any depth) at each frame.
    self_depth_m : ndarray, shape (T,)
        Deepest self-contact at each frame.
    torque_peak_nm : ndarray, shape (T,)
        Largest servo torque at each frame (absolute), N m.
    pelvis_height_m, head_height_m : ndarray, shape (T,)
        Simulated heights; ``reference_pelvis_height_m``, ``reference_head_height_m``
        the reference's.
    standing_pelvis_m, standing_head_m : float
        The model's standing heights (the fall thresholds' base).
    fall_frame : int or None
        First frame at which the character has fallen.
    diverged_frame : int or None
        Frame at which the simulation was stopped for a non-finite state or a fatal
        warning.
    warnings : dict of str to int
        MuJoCo's warning counters that are not zero (``"mjWARN_CONTACTFULL"``: n).
    messages : tuple of str
        MuJoCo's warning texts (the first 10 distinct ones).
    config : controller.config.ControllerConfig
        The configuration the simulation was made with (its physics step and fall rule).
    saturated_actuators : ndarray, shape (T,), or None
        Share of the actuators at their force limit at each frame (None: not recorded).
    floor_force_n : ndarray, shape (T,), or None
        Total normal force of the floor on the body at each frame, N (None: not recorded).
    """

    mode: str
    fps: float
    timestep_s: float
    steps: int
    wall_s: float
    hinge_names: tuple[str, ...]
    qpos: np.ndarray
    dof_error_deg: np.ndarray
    dof_reachable_error_deg: np.ndarray
    limit_rows: np.ndarray
    limit_steps: int
    limit_joint_frames: dict[str, int]
    self_contacts: np.ndarray
    self_depth_m: np.ndarray
    torque_peak_nm: np.ndarray
    pelvis_height_m: np.ndarray
    head_height_m: np.ndarray
    reference_pelvis_height_m: np.ndarray
    reference_head_height_m: np.ndarray
    standing_pelvis_m: float
    standing_head_m: float
    fall_frame: int | None
    diverged_frame: int | None
    warnings: dict[str, int]
    messages: tuple[str, ...] = ()
    config: ControllerConfig = DEFAULT
    saturated_actuators: np.ndarray | None = None
    floor_force_n: np.ndarray | None = None

    @property
    def n_frames(self) -> int:
        return self.qpos.shape[0]

    @property
    def error_deg(self) -> np.ndarray:
        """RMS over the hinges of the tracking error at each frame, (T,) degrees."""
        return np.sqrt(np.mean(self.dof_error_deg ** 2, axis=1))

    @property
    def fell(self) -> bool:
        return self.fall_frame is not None

    @property
    def fall_time_s(self) -> float | None:
        return None if self.fall_frame is None else self.fall_frame / self.fps

    @property
    def fallen(self) -> np.ndarray:
        """Frames at or after the fall, bool (T,)."""
        out = np.zeros(self.n_frames, dtype=bool)
        if self.fall_frame is not None:
            out[self.fall_frame:] = True
        return out

    def saturation_share(self, part: slice | None = None) -> float | None:
        """Share of the actuators at their force limit over the frames of ``part`` that
        were simulated before any fall (None: not recorded or no such frame)."""
        if self.saturated_actuators is None:
            return None
        index = np.arange(self.n_frames)[part if part is not None else slice(None)]
        if self.diverged_frame is not None:
            index = index[index < self.diverged_frame]
        index = index[~self.fallen[index]]
        if not index.size:
            return None
        return float(self.saturated_actuators[index].mean())

    @property
    def steps_per_s(self) -> float:
        return self.steps / self.wall_s if self.wall_s > 0 else math.inf

    def summary(self, part: slice | None = None) -> dict:
        """Figures over a part of the motion (all frames by default), JSON-ready.

        The tracking error is over the frames before the fall and divergence (``error_*``)
        and over all frames of the part that were simulated (``error_all_*``);
        ``reachable_error_deg_rms`` is the error to the reference clamped into the joint
        ranges, before the fall (the servos' own accuracy, without the targets they cannot
        reach).
        """
        index = np.arange(self.n_frames)[part if part is not None else slice(None)]
        simulated = index if self.diverged_frame is None else index[index < self.diverged_frame]
        standing = simulated[~self.fallen[simulated]]
        err = self.error_deg
        out = {
            "frames": int(index.size),
            "fell": bool(self.fall_frame is not None and self.fall_frame in set(index)),
            "error_deg_rms": _rms(self.dof_error_deg[standing]),
            "error_deg_peak": _round(err[standing].max()) if standing.size else None,
            "error_all_deg_rms": _rms(self.dof_error_deg[simulated]),
            "reachable_error_deg_rms": _rms(self.dof_reachable_error_deg[standing]),
            "limit_active_frames": int((self.limit_rows[simulated] > 0).sum()),
            "limit_active_pct": (round(100 * float((self.limit_rows[simulated] > 0).mean()),
                                       2) if simulated.size else None),
            "self_collision_frames": int((self.self_depth_m[simulated]
                                          > SELF_COLLISION_DEPTH_M).sum()),
            "self_contact_frames": int((self.self_contacts[simulated] > 0).sum()),
            "torque_peak_nm": (_round(self.torque_peak_nm[simulated].max())
                               if simulated.size else None),
        }
        return out

    def run_summary(self) -> dict:
        """Whole-run figures (steps, fall, warnings, speed), JSON-ready."""
        return {
            "mode": self.mode,
            "timestep_s": self.timestep_s,
            "steps": self.steps,
            "steps_per_s": round(self.steps_per_s, 1),
            "fell": self.fell,
            "fall_frame": self.fall_frame,
            "fall_time_s": None if self.fall_time_s is None else round(self.fall_time_s, 4),
            "fall_rule": rule_text(self.standing_pelvis_m, self.standing_head_m,
                                   self.config.falls),
            "diverged_frame": self.diverged_frame,
            "warnings": dict(self.warnings),
            "warning_messages": list(self.messages),
            "limit_active_steps_pct": round(100 * self.limit_steps / max(self.steps, 1), 2),
            "limit_joint_frames": dict(self.limit_joint_frames),
            **self.summary(),
        }


def _rms(x) -> float | None:
    x = np.asarray(x)
    return _round(np.sqrt(np.mean(x ** 2))) if x.size else None


def _round(x, digits: int = 4) -> float:
    return round(float(x), digits)
