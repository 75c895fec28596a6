"""The study's metrics: what each one measures, its unit and which way is better (the
registry :data:`METRICS`), and the pure batched functions behind the motion metrics.

Kinematic validity and the root residual come from :mod:`controller.checks.validity` and
:mod:`controller.checks.dynamics`; this module adds the rest: joint jerk, foot skating and the
distance to the nearest real posture. Every function works on arrays (shapes in the
docstrings) and knows nothing of MuJoCo.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from upm.maps.angular_search import diff_of_wrapped
from upm.ops.angles import angle_diff_deg, wrap_deg

#: A foot is planted while its lowest point is below this height, metres.
FOOT_CONTACT_HEIGHT_M = 0.05


@dataclass(frozen=True)
class Metric:
    """One figure measured on every transition window (and every real window).

    Attributes
    ----------
    name : str
        Key in ``results.json`` (the unit is in the name).
    label : str
        Short column header.
    unit : str
    better : str
        ``"higher"`` or ``"lower"``.
    description : str
        What it is, over which frames.
    """

    name: str
    label: str
    unit: str
    better: str
    description: str

    def as_dict(self) -> dict:
        return {"label": self.label, "unit": self.unit, "better": self.better,
                "description": self.description}


_METRICS = (
    Metric("valid_pct", "valid", "% of window frames", "higher",
           "window frames within the human range of motion (or beyond it no more than the "
           "two end postures already are), with no self-contact deeper than its body pair's "
           "soft-tissue allowance and no geom deeper below the floor than its class allows "
           "(controller.checks.validity: valid_beyond_ends)"),
    Metric("raw_valid_pct", "valid (raw)", "% of window frames", "higher",
           "as valid_pct, but any excess beyond the human range counts, even one the end "
           "postures already have"),
    Metric("valid_added_pct", "valid (added)", "% of window frames", "higher",
           "as valid_pct, with self-collision also counted only where the method added it: "
           "a contact deeper than its allowance between a body pair that is not in "
           "self-collision at either end posture (clip 2's postures on clip 1's body often "
           "are)"),
    Metric("added_limit_mean_deg", "added limit", "deg", "lower",
           "per window frame the largest excess of a rule of the human range over the "
           "larger excess of that rule at the two end postures, averaged over the window"),
    Metric("added_limit_max_deg", "added limit max", "deg", "lower",
           "the largest such added excess in the window"),
    Metric("self_collision_pct", "self-coll.", "% of window frames", "lower",
           "window frames with a self-contact deeper than its body pair's soft-tissue "
           "allowance (controller.checks.tissue) between bodies the model does not exclude"),
    Metric("self_collision_added_pct", "self-coll. (added)", "% of window frames", "lower",
           "window frames with a self-collision between a body pair not in self-collision "
           "at either end posture"),
    Metric("self_depth_max_mm", "self depth max", "mm", "lower",
           "the deepest self-contact in the window"),
    Metric("floor_penetration_pct", "floor", "% of window frames", "lower",
           "window frames with a geom deeper below the floor than its class allows (a foot "
           "5 cm, anything else 1 cm)"),
    Metric("beyond_asf_pct", "beyond ASF", "% of window frames", "lower",
           "window frames beyond a limit the ASF declares (the CMU's nominal boxes): "
           "reported, not judged -- most real frames are"),
    Metric("nearest_real_mean_deg", "nearest real", "deg RMS", "lower",
           "per window frame, the wrapped distance to the nearest real posture of the test "
           "clips outside the pair's exclusion zones, as an RMS over the 45 declared DOFs; "
           "averaged over the window"),
    Metric("nearest_real_max_deg", "nearest real max", "deg RMS", "lower",
           "the largest such distance in the window"),
    Metric("jerk_rms_deg_s3", "jerk", "deg/s^3", "lower",
           "third difference of the joint angles at 120 fps (unwrapped), RMS over the 45 "
           "declared DOFs and over every 4-frame stencil that touches a window frame "
           "(L + 3 stencils, from the one ending at the first window frame to the one "
           "starting at the last): a velocity jump at a join counts"),
    Metric("foot_skate_mps", "foot skate", "m/s", "lower",
           "per foot and window frame, the horizontal speed of the foot's lowest capsule "
           "(central difference) while its lowest point is below 5 cm, 0 while it is "
           "higher; averaged over both feet and the window"),
    Metric("residual_force_mean_bw", "residual", "body weights", "lower",
           "the root force the motion needs beyond what floor contact can supply "
           "(inverse dynamics, 12 Hz low-pass, 30 real context frames on each side), "
           "averaged over the window frames"),
    Metric("residual_force_peak_bw", "residual peak", "body weights", "lower",
           "the largest residual force in the window"),
    Metric("tracking_error_deg", "tracking", "deg RMS", "lower",
           "the humanoid's servos (human-strength torque limits) following the motion with "
           "the root driven along it, from 30 frames before the window: joint error to the "
           "reference over the window frames, RMS over the 45 hinges -- what the body cannot "
           "do, or what its contacts and limits stop (controller.tracking.servo, mode driven)"),
)

#: Every metric, by name, in table order.
METRICS: dict[str, Metric] = {m.name: m for m in _METRICS}

#: The metrics of the headline table.
HEADLINE: tuple[str, ...] = ("valid_pct", "added_limit_mean_deg", "self_collision_pct",
                             "nearest_real_mean_deg", "residual_force_mean_bw",
                             "jerk_rms_deg_s3", "foot_skate_mps", "tracking_error_deg")


def unwrap_time_deg(angles_deg) -> np.ndarray:
    """Angles made continuous along time (axis 0) by summing wrapped frame-to-frame
    differences from the first frame.

    Parameters
    ----------
    angles_deg : array_like, shape (T, D)

    Returns
    -------
    ndarray, shape (T, D)
    """
    a = np.asarray(angles_deg, dtype=float)
    steps = angle_diff_deg(a[1:], a[:-1])
    return np.concatenate([a[:1], a[:1] + np.cumsum(steps, axis=0)])


def third_difference(values, fps: float) -> np.ndarray:
    """Jerk by third differences: ``(x[k+3] - 3 x[k+2] + 3 x[k+1] - x[k]) fps^3``.

    Parameters
    ----------
    values : array_like, shape (T, D)
        Continuous along time (unwrap angles first).
    fps : float

    Returns
    -------
    ndarray, shape (T - 3, D)
        Row k is the stencil of frames k .. k+3 (units of ``values`` per s^3).
    """
    x = np.asarray(values, dtype=float)
    return (x[3:] - 3.0 * x[2:-1] + 3.0 * x[1:-2] - x[:-3]) * fps ** 3


def window_jerk_rms(posture_deg, window: slice, fps: float, dofs) -> float:
    """RMS joint jerk over the stencils touching a window.

    Parameters
    ----------
    posture_deg : array_like, shape (T, 63)
        The motion the window sits in (at least 3 frames on each side of it for every
        stencil to exist).
    window : slice
        The window's frames ``start:stop``.
    fps : float
    dofs : array_like of bool, shape (63,), or of int
        The DOFs measured (the declared ones).

    Returns
    -------
    float
        deg/s^3: the RMS over the DOFs and over the stencils k = start-3 .. stop-1 (those
        holding at least one window frame) that lie inside the motion.
    """
    posture = np.asarray(posture_deg, dtype=float)[:, dofs]
    n = posture.shape[0]
    start, stop, _ = window.indices(n)
    first, last = max(start - 3, 0), min(stop + 3, n)
    jerk = third_difference(unwrap_time_deg(posture[first:last]), fps)
    return float(np.sqrt(np.mean(jerk ** 2))) if jerk.size else 0.0


def horizontal_speed_mps(points_m, fps: float) -> np.ndarray:
    """Horizontal speed of points along time (z up), central differences inside, one-sided
    at the ends.

    Parameters
    ----------
    points_m : array_like, shape (T, P, 3)
        Positions, metres, z up (MuJoCo's frame).
    fps : float

    Returns
    -------
    ndarray, shape (T, P)
        m/s (0 for a single frame).
    """
    xy = np.asarray(points_m, dtype=float)[..., :2]
    if xy.shape[0] < 2:
        return np.zeros(xy.shape[:2])
    velocity = np.gradient(xy, 1.0 / fps, axis=0)
    return np.linalg.norm(velocity, axis=-1)


def foot_skate_mps(centres_m, bottoms_m, foot_of_geom, fps: float,
                   contact_height_m: float = FOOT_CONTACT_HEIGHT_M) -> np.ndarray:
    """Foot skating per foot and frame.

    For each foot, its geom with the lowest point at that frame; the skate is that geom
    centre's horizontal speed while its lowest point is below ``contact_height_m``, and 0
    while the foot is higher.

    Parameters
    ----------
    centres_m : array_like, shape (T, G, 3)
        Centres of the feet's geoms (z up), metres.
    bottoms_m : array_like, shape (T, G)
        Height of each geom's lowest point above the floor, metres.
    foot_of_geom : array_like of int, shape (G,)
        Which foot (0 .. F-1) each geom belongs to.
    fps : float
    contact_height_m : float

    Returns
    -------
    ndarray, shape (T, F)
        m/s.
    """
    speed = horizontal_speed_mps(centres_m, fps)
    bottoms = np.asarray(bottoms_m, dtype=float)
    feet = np.asarray(foot_of_geom)
    n_feet = int(feet.max()) + 1
    out = np.zeros((bottoms.shape[0], n_feet))
    for foot in range(n_feet):
        geoms = np.flatnonzero(feet == foot)
        lowest = geoms[np.argmin(bottoms[:, geoms], axis=1)]
        rows = np.arange(bottoms.shape[0])
        planted = bottoms[rows, lowest] < contact_height_m
        out[:, foot] = np.where(planted, speed[rows, lowest], 0.0)
    return out


def nearest_rms_deg(points_deg, bank_deg, chunk_bytes: int = 1 << 24) -> np.ndarray:
    """Distance from each point to its nearest bank posture, as an RMS per DOF.

    Exact (brute force over the bank, in chunks), under wrapped angle differences.

    Parameters
    ----------
    points_deg : array_like, shape (M, D)
    bank_deg : array_like, shape (N, D)
        N >= 1; both wrapped here.
    chunk_bytes : int
        Memory of the difference array per chunk.

    Returns
    -------
    ndarray, shape (M,)
        ``sqrt(min_n sum_d wrap(p_d - b_nd)^2 / D)``, degrees.
    """
    points = wrap_deg(np.atleast_2d(points_deg))
    bank = wrap_deg(np.atleast_2d(bank_deg))
    if bank.shape[0] == 0:
        raise ValueError("the bank of real postures is empty")
    n, d = bank.shape
    best = np.full(points.shape[0], np.inf)
    rows = max(1, chunk_bytes // (8 * n * d))
    for s in range(0, points.shape[0], rows):
        diff = diff_of_wrapped(points[s:s + rows, None, :], bank[None, :, :])
        best[s:s + rows] = np.einsum("mnd,mnd->mn", diff, diff).min(axis=1)
    return np.sqrt(best / d)


def pose_distance_rms_deg(a_deg, b_deg) -> np.ndarray:
    """Wrapped distance between postures as an RMS per DOF.

    Parameters
    ----------
    a_deg, b_deg : array_like, shape (..., D)

    Returns
    -------
    ndarray, shape (...)
        Degrees.
    """
    diff = angle_diff_deg(a_deg, b_deg)
    return np.sqrt(np.mean(diff ** 2, axis=-1))
