"""A reference put on the floor: its height shifted, frame by frame, so that the feet it
stands on touch the floor.

Mocap floors are not where the ASF's skeleton puts them: over a clip the lowest point of
the reference's body drifts by centimetres (02_01: median 4.4 cm above the floor after
its first frame is put on it, 02_03: 5.9 cm, 16_15: 0.9 cm into it). A character that
tracks such a pelvis height either lifts its stance foot or straightens its legs. Here,
at every frame in which the reference has a foot down, the root is shifted vertically so
that the body's lowest point is ``grounding.depth_m`` (1 mm) into the floor; frames with
no foot down (flight) take the shift interpolated from their neighbours, and the shift is
low-passed (``grounding.shift_hz``, 2 Hz) so that it adds no jerk of its own
(:class:`controller.config.sections.GroundingConfig`).
"""

from __future__ import annotations

import numpy as np

from controller.config import DEFAULT


def ground_reference(model, qpos, fps: float, down,
                     grounding=DEFAULT.grounding) -> tuple[np.ndarray, np.ndarray]:
    """The reference with its root height shifted onto the floor.

    Parameters
    ----------
    model : mujoco.MjModel
        A humanoid with one floor plane.
    qpos : ndarray, shape (T, nq)
    fps : float
    down : ndarray of bool, shape (T, 2)
        Whether the reference has its left and right foot down at each frame.
    grounding : controller.config.sections.GroundingConfig

    Returns
    -------
    qpos : ndarray, shape (T, nq)
        A copy, root height shifted.
    shift_m : ndarray, shape (T,)
        The vertical shift of each frame, metres.
    """
    from scipy.signal import butter, filtfilt

    from controller.qpos import free_joint

    out = np.array(qpos, dtype=float)
    n = out.shape[0]
    standing = np.flatnonzero(np.asarray(down).any(axis=1))
    shift = np.zeros(n)
    if standing.size:
        at = -floor_clearances(model, out[standing]) - grounding.depth_m
        shift = np.interp(np.arange(n), standing, at)
        cutoff_hz = grounding.shift_hz
        if n > 9 and cutoff_hz < 0.5 * fps:
            b, a = butter(2, cutoff_hz / (0.5 * fps))
            shift = filtfilt(b, a, shift)
    out[:, int(model.jnt_qposadr[free_joint(model)]) + 2] += shift
    return out, shift


def floor_clearance(model, data, qpos) -> float:
    """Signed distance from the floor to the body's lowest point in state ``qpos``,
    metres (negative: in the floor); ``data`` is used as scratch."""
    return float(floor_clearances(model, np.asarray(qpos)[None], data)[0])


def floor_clearances(model, qpos, data=None) -> np.ndarray:
    """:func:`floor_clearance` of every state of ``qpos`` (T, nq): an array (T,), metres
    (``mj_geomDistance`` of every body geom to the floor plane).

    Raises
    ------
    ValueError
        If the model has not exactly one floor plane.
    """
    import mujoco

    floor = np.flatnonzero((model.geom_bodyid == 0)
                           & (model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE))
    if floor.size != 1:
        raise ValueError("the model needs exactly one floor plane")
    floor = int(floor[0])
    body = np.flatnonzero(model.geom_bodyid != 0).tolist()
    data = mujoco.MjData(model) if data is None else data
    qpos = np.asarray(qpos, dtype=float)
    out = np.empty(qpos.shape[0])
    for t, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        out[t] = min(mujoco.mj_geomDistance(model, data, floor, g, 1.0, None) for g in body)
    return out
