"""The in-betweening literature's metrics and baselines: L2P, L2Q and NPSS of the LaFAN1
benchmark (Harvey, Yurick, Nowrouzezahrai and Pal 2020, "Robust Motion In-betweening",
ACM Transactions on Graphics 39(4); definitions read from the paper and from the official
benchmark code, ``lafan1/benchmarks.py``, ``lafan1/utils.py`` and ``lafan1/extract.py`` of
github.com/ubisoft/ubisoft-laforge-animation-dataset). Pure functions on arrays, no data.

- **L2Q**: per frame, the L2 norm of the difference of the global (world) joint
  quaternions, all joints' 4 components as one vector; averaged over the transition's
  frames (and then over windows).
- **L2P**: the same on global joint positions, each coordinate of each joint first divided
  by its standard deviation over the training windows (the protocol normalises by the
  training set's mean and standard deviation; the mean cancels in a difference).
- **NPSS** (Gopalakrishnan et al. 2019, as the benchmark code computes it): per feature
  (every component of every global quaternion) the power spectrum of the transition's
  frames -- the square of the *real part* of the DFT, all T bins, as the code does -- made
  a distribution by its total; the earth mover's distance between the ground truth's
  and the prediction's (the L1 norm of the difference of their cumulative sums); the
  features' distances averaged with the ground truth's total power as weights. Over
  windows the benchmark takes one weighted average over every window and feature, which
  is :func:`pooled_npss` of the per-window figures and their weights.

Frames: every window is turned about the vertical so that the root faces a fixed way at
the last context frame (the protocol's ``rotate_at_frame``; it changes L2P through the
per-axis deviations and NPSS through the mixing of components, not L2Q). Training
statistics windows are also centred on their mean horizontal root position first (the
protocol's ``get_lafan1_set``).

Joints: the CMU skeleton has 31 bones; the points are the root and the distal ends of
the 21 posture joints' bones (knees, ankles, toe bases and tips, the spine, neck and
head, shoulders, elbows, wrists and hands), and the rotations those of the root and the
21 joints: 22, like LaFAN1's 22 joints, but not the same ones. Quaternions ``(w, x, y,
z)``; ``q`` and ``-q`` are one rotation, so a prediction is first put in the ground
truth's hemisphere frame by frame (the benchmark's quaternions come from one continuous
sequence and needed no such step).
"""

from __future__ import annotations

import numpy as np

from upm.motion.kinematics import global_transforms
from upm.motion.skeleton import JOINTS, Skeleton
from upm.ops.rotations import (
    axis_rotation,
    euler_to_matrix,
    matrix_to_euler_deg,
    matrix_to_quaternion,
    rotation_exp,
    rotation_log,
)

#: The protocol's transition lengths, frames at 30 fps.
LAFAN_LENGTHS = (5, 15, 30)
#: The protocol's frame rate.
LAFAN_FPS = 30.0
#: Frames of past context (the protocol's seed frames, at 30 fps).
PAST_FRAMES = 10
#: The protocol's training-statistics windows: 50 frames at 30 fps, every 20 frames.
STATS_WINDOW = 50
STATS_OFFSET = 20
#: The protocol's baselines, by the name their rows carry.
ZERO_VELOCITY = "zerovel"
INTERPOLATION = "interp"
BASELINES = (ZERO_VELOCITY, INTERPOLATION)


def joint_bones(skeleton: Skeleton) -> np.ndarray:
    """The bones measured: the root and the 21 posture joints, (22,) bone indices."""
    return np.array([0] + [skeleton.bone_index(j) for j in JOINTS])


def facing_rotation(skeleton: Skeleton, root_row) -> np.ndarray:
    """The turn about the vertical (ASF y) that makes the root of ``root_row`` (6,) face
    heading 0, (3, 3): applied to both the ground truth and every prediction of a window.
    """
    from upm.transitions.root import heading_deg

    root = np.asarray(root_row, dtype=float)
    orientation = euler_to_matrix(root[None, 3:6], skeleton.root_axis_order)[0]
    return axis_rotation(-float(heading_deg(orientation)), "Y")


def joint_frames(skeleton: Skeleton, posture_deg, root, facing=None):
    """Global positions and quaternions of the 22 measured joints.

    Parameters
    ----------
    skeleton : Skeleton
    posture_deg : array_like, shape (T, 63)
        All three angles of a joint are used, declared or not (the interpolation baseline
        slerps whole rotations).
    root : array_like, shape (T, 6)
    facing : ndarray, shape (3, 3), optional
        A turn about the vertical applied to everything (:func:`facing_rotation`).

    Returns
    -------
    positions_m : ndarray, shape (T, 22, 3)
        ASF world frame, y up.
    quaternions : ndarray, shape (T, 22, 4)
        ``(w, x, y, z)``, ``w >= 0``.
    """
    rotations, positions = global_transforms(skeleton, posture_deg, root)
    bones = joint_bones(skeleton)
    rotations, positions = rotations[:, bones], positions[:, bones]
    if facing is not None:
        rotations = facing @ rotations
        positions = positions @ facing.T
    return positions, matrix_to_quaternion(rotations)


def same_hemisphere(q, reference) -> np.ndarray:
    """``q`` with each quaternion's sign chosen to be nearest ``reference`` (same shape,
    (..., 4)): q and -q are the same rotation."""
    q = np.asarray(q, dtype=float)
    dot = np.einsum("...i,...i->...", q, np.asarray(reference, dtype=float))
    return np.where(dot[..., None] < 0.0, -q, q)


def continuous_in_time(q) -> np.ndarray:
    """Quaternions (T, J, 4) with signs flipped so that each is nearest the one before it
    (no sign jumps along time; the protocol's ``remove_quat_discontinuities``)."""
    out = np.array(q, dtype=float)
    for t in range(1, out.shape[0]):
        out[t] = same_hemisphere(out[t], out[t - 1])
    return out


def l2q(predicted, truth) -> float:
    """L2Q of one window: the mean over frames of the L2 norm of the difference of all
    joints' global quaternions.

    Parameters
    ----------
    predicted, truth : array_like, shape (T, J, 4)

    Returns
    -------
    float
        0 for the same rotations, whatever their signs.
    """
    truth = np.asarray(truth, dtype=float)
    diff = same_hemisphere(predicted, truth) - truth
    return float(np.sqrt(np.einsum("tjc,tjc->t", diff, diff)).mean())


def l2p(predicted_m, truth_m, std_m) -> float:
    """L2P of one window: the mean over frames of the L2 norm of the difference of all
    joints' global positions, each coordinate divided by its training deviation.

    Parameters
    ----------
    predicted_m, truth_m : array_like, shape (T, J, 3)
    std_m : array_like, shape (J, 3)
        :func:`position_std`.

    Returns
    -------
    float
        Dimensionless.
    """
    diff = (np.asarray(predicted_m, dtype=float) - np.asarray(truth_m, dtype=float)) / std_m
    return float(np.sqrt(np.einsum("tjc,tjc->t", diff, diff)).mean())


def npss(truth, predicted) -> tuple[float, float]:
    """NPSS of one window and its weight in the protocol's pooled figure.

    Parameters
    ----------
    truth, predicted : array_like, shape (T, D)
        Features along time (the protocol: every component of every global quaternion,
        D = 4 J; make them continuous in time first, :func:`continuous_in_time`).

    Returns
    -------
    npss : float
        The features' earth mover's distances between normalised power spectra, averaged
        with the truth's total power per feature as weights; 0 for a window and itself.
    power : float
        The truth's total power summed over the features (the window's weight in
        :func:`pooled_npss`).
    """
    power_true = np.square(np.real(np.fft.fft(np.asarray(truth, dtype=float), axis=0)))
    power_pred = np.square(np.real(np.fft.fft(np.asarray(predicted, dtype=float), axis=0)))
    total_true, total_pred = power_true.sum(axis=0), power_pred.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        cdf_true = np.cumsum(power_true / total_true, axis=0)
        cdf_pred = np.cumsum(power_pred / total_pred, axis=0)
    emd = np.abs(cdf_pred - cdf_true).sum(axis=0)
    # A feature with no power at all (identically zero) carries no weight and no spectrum.
    keep = total_true > 0
    emd = np.where(np.isfinite(emd), emd, 0.0)
    weight = float(total_true[keep].sum())
    return (float((emd[keep] * total_true[keep]).sum() / weight) if weight > 0 else 0.0,
            weight)


def pooled_npss(values, powers) -> float:
    """The protocol's NPSS over windows: one power-weighted average over every window and
    feature, from per-window NPSS ``values`` (N,) and their ``powers`` (N,)."""
    v, w = np.asarray(values, dtype=float), np.asarray(powers, dtype=float)
    return float((v * w).sum() / w.sum()) if w.sum() > 0 else float("nan")


def window_metrics(skeleton: Skeleton, facing, std_m, truth: tuple, predicted: tuple) -> dict:
    """L2P, L2Q and NPSS (with its power) of one transition.

    Parameters
    ----------
    skeleton : Skeleton
    facing : ndarray, shape (3, 3)
        :func:`facing_rotation` of the last context frame.
    std_m : ndarray, shape (22, 3)
    truth, predicted : (posture_deg (T, 63), root (T, 6))
        The transition's frames at 30 fps.

    Returns
    -------
    dict
        ``l2p``, ``l2q``, ``npss``, ``npss_power``.
    """
    p_true, q_true = joint_frames(skeleton, *truth, facing=facing)
    p_pred, q_pred = joint_frames(skeleton, *predicted, facing=facing)
    q_true = continuous_in_time(q_true)
    # The prediction starts in the truth's hemisphere and stays continuous from there.
    q_pred = np.array(q_pred)
    q_pred[0] = same_hemisphere(q_pred[0], q_true[0])
    q_pred = continuous_in_time(q_pred)
    n = q_true.shape[0]
    value, power = npss(q_true.reshape(n, -1), q_pred.reshape(n, -1))
    return {"l2p": l2p(p_pred, p_true, std_m), "l2q": l2q(q_pred, q_true), "npss": value,
            "npss_power": power}


# --- the protocol's baselines -------------------------------------------------------------


def zero_velocity(posture_deg, root, frames: int) -> tuple[np.ndarray, np.ndarray]:
    """The zero-velocity baseline: the last context frame held over the transition.

    Parameters
    ----------
    posture_deg : array_like, shape (63,)
    root : array_like, shape (6,)
    frames : int

    Returns
    -------
    posture_deg : ndarray, shape (frames, 63)
    root : ndarray, shape (frames, 6)
    """
    return (np.tile(np.asarray(posture_deg, dtype=float), (frames, 1)),
            np.tile(np.asarray(root, dtype=float), (frames, 1)))


def _slerp(a, b, s) -> np.ndarray:
    """Rotations ``a exp(s log(a^T b))``: a (..., 3, 3), b (..., 3, 3), s (S,) ->
    (S, ..., 3, 3), the shortest arc."""
    step = rotation_log(np.swapaxes(a, -1, -2) @ b)
    return a @ rotation_exp(np.asarray(s, dtype=float).reshape(-1, *[1] * step.ndim)
                            * step)


def interpolation(skeleton: Skeleton, start: tuple, end: tuple, frames: int):
    """The interpolation baseline: the root position linear (LERP) and every joint's
    rotation, the root's included, spherical-linear (SLERP) from the last context frame to
    the target, at ``k / (frames + 1)``, k = 1 .. frames (the protocol's
    ``interpolate_local``).

    Parameters
    ----------
    skeleton : Skeleton
    start, end : (posture_deg (63,), root (6,))
        The last context frame and the target.
    frames : int

    Returns
    -------
    posture_deg : ndarray, shape (frames, 63)
        Each joint's three angles of the slerped rotation (a 1- or 2-DOF joint's
        rotation may use an undeclared axis, as a ball joint would).
    root : ndarray, shape (frames, 6)
    """
    s = np.arange(1, frames + 1) / (frames + 1)
    (pa, ra), (pb, rb) = ([np.asarray(x, dtype=float) for x in pair] for pair in (start, end))
    joints_a = euler_to_matrix(pa.reshape(-1, 3), "XYZ")
    joints_b = euler_to_matrix(pb.reshape(-1, 3), "XYZ")
    posture = matrix_to_euler_deg(_slerp(joints_a, joints_b, s), "XYZ").reshape(frames, -1)
    order = skeleton.root_axis_order
    turn = _slerp(euler_to_matrix(ra[3:6], order), euler_to_matrix(rb[3:6], order), s)
    root = np.empty((frames, 6))
    root[:, :3] = ra[:3] + s[:, None] * (rb[:3] - ra[:3])
    root[:, 3:] = matrix_to_euler_deg(turn, order)
    return posture, root


# --- training statistics ------------------------------------------------------------------


def stats_windows(skeleton: Skeleton, posture_deg, root, window: int = STATS_WINDOW,
                  offset: int = STATS_OFFSET, past: int = PAST_FRAMES) -> np.ndarray:
    """Global joint positions of one clip's training windows, as the protocol builds them.

    Windows of ``window`` frames every ``offset`` frames (while one fits with a frame to
    spare, as the protocol's loop does), each centred on its mean horizontal root position
    and turned to face heading 0 at frame ``past - 1``.

    Parameters
    ----------
    posture_deg : array_like, shape (T, 63)
    root : array_like, shape (T, 6)
        At 30 fps.

    Returns
    -------
    ndarray, shape (W, window, 22, 3)
    """
    posture, root = np.asarray(posture_deg, dtype=float), np.asarray(root, dtype=float)
    out = []
    for i in range(0, posture.shape[0] - window, offset):
        r = root[i:i + window].copy()
        r[:, [0, 2]] -= r[:, [0, 2]].mean(axis=0)
        facing = facing_rotation(skeleton, r[past - 1])
        out.append(joint_frames(skeleton, posture[i:i + window], r, facing)[0])
    return np.array(out).reshape(-1, window, len(JOINTS) + 1, 3)


def position_std(windows) -> np.ndarray:
    """Per joint and coordinate, the standard deviation of the positions over every
    window and frame: ``windows`` a list of (W, T, 22, 3) arrays -> (22, 3)."""
    stacked = np.concatenate([w.reshape(-1, *w.shape[-2:]) for w in windows if w.size])
    return stacked.std(axis=0)
