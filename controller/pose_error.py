"""How far a simulated trajectory is from its reference, per frame: joint angles, body
pose (relative to the pelvis and its heading), the pelvis's horizontal drift and heading,
and the centre of mass's height (definitions in :mod:`controller.balance.run`)."""

from __future__ import annotations

import math

import numpy as np


def reference_errors(model, qpos, reference_qpos):
    """Per-frame errors of a simulated trajectory against its reference.

    Parameters
    ----------
    model : mujoco.MjModel
    qpos, reference_qpos : ndarray, shape (T, nq)
        Rows of ``qpos`` that are NaN give NaN.

    Returns
    -------
    joint_error_deg, body_error_mm, root_drift_m, heading_error_deg, com_height_error_m :
        ndarray, shape (T,) each, as defined in :mod:`controller.balance.run`
        (``heading_error_deg`` signed, in [-180, 180)).
    """
    import mujoco

    from controller.qpos import joint_layout, wrap_rad

    hinge = joint_layout(model).qpos_address
    n = qpos.shape[0]
    up = np.all(np.isfinite(qpos), axis=1)
    joint = np.full(n, np.nan)
    joint[up] = np.rad2deg(np.sqrt(np.mean(
        wrap_rad(qpos[up][:, hinge] - reference_qpos[up][:, hinge]) ** 2, axis=1)))
    body = np.full(n, np.nan)
    drift = np.full(n, np.nan)
    com = np.full(n, np.nan)
    heading_rad = np.full((n, 2), np.nan)  # simulated, reference
    data = mujoco.MjData(model)
    pelvis = 1
    for t in np.flatnonzero(up):
        poses = []
        for q in (qpos[t], reference_qpos[t]):
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_comPos(model, data)
            x = data.xpos[1:] - data.xpos[pelvis]
            heading = _heading(data.xmat[pelvis].reshape(3, 3))
            c, s = math.cos(-heading), math.sin(-heading)
            rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
            poses.append((x @ rot.T, data.xpos[pelvis, :2].copy(),
                          float(data.subtree_com[pelvis, 2]), heading))
        (sim_x, sim_xy, sim_com, sim_h), (ref_x, ref_xy, ref_com, ref_h) = poses
        body[t] = 1000.0 * float(np.mean(np.linalg.norm(sim_x - ref_x, axis=1)))
        drift[t] = float(np.linalg.norm(sim_xy - ref_xy))
        com[t] = sim_com - ref_com
        heading_rad[t] = sim_h, ref_h
    heading_deg = np.rad2deg(wrap_rad(heading_rad[:, 0] - heading_rad[:, 1]))
    return joint, body, drift, heading_deg, com


def _heading(rotation) -> float:
    """Heading of a body frame about the vertical: the angle of its x axis in the floor
    plane."""
    return math.atan2(rotation[1, 0], rotation[0, 0])
