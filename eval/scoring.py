"""Score one window of a motion on the humanoid: every metric of :data:`eval.metrics.METRICS`.

The same function scores a transition's window (the joined motion: segment 1, the L new
frames, segment 2 re-anchored) and a real window of a test clip (the calibration row):

- **kinematic** (controller.checks.validity) on the window and its two end postures (A, the
  frame before it, and B, the frame after): valid frames, the limit excess *added*
  beyond what A and B already have, self-collision, floor penetration;
- **nearest real posture** (:class:`eval.realdata.RealPostures`) of each window frame;
- **joint jerk** over the stencils touching the window (its joins included);
- **dynamics** (controller.checks.dynamics.root_residual) on the window with
  :data:`RESIDUAL_CONTEXT` frames of the motion on each side, for the 12 Hz low-pass and
  the finite differences; the figures are read on the window's frames only;
- **foot skating** from the same frames' foot geoms;
- **tracking** (controller.tracking.servo, root driven) over the same frames, read on the window.
"""

from __future__ import annotations

import numpy as np

from eval.metrics import foot_skate_mps, window_jerk_rms

#: Motion frames on each side of a window given to the inverse dynamics, so that the
#: low-pass filter and the finite differences see real context (0.25 s at 120 fps; the
#: window's figures change by less than 0.01 body weights from 15 to 60 frames).
RESIDUAL_CONTEXT = 30
#: The bodies of each foot whose geoms can touch the floor.
FEET = (("lfoot", "ltoes"), ("rfoot", "rtoes"))


def foot_geoms(model) -> tuple[np.ndarray, np.ndarray]:
    """The geoms of the feet and the foot each belongs to.

    Returns
    -------
    geoms : ndarray of int, shape (G,)
    foot : ndarray of int, shape (G,)
        0 for the left foot, 1 for the right.
    """
    import mujoco

    geoms, foot = [], []
    for f, bodies in enumerate(FEET):
        ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in bodies]
        mine = np.flatnonzero(np.isin(model.geom_bodyid, [i for i in ids if i >= 0]))
        if not mine.size:
            raise ValueError(f"the model has no geoms on the bodies {bodies}")
        geoms += list(mine)
        foot += [f] * mine.size
    return np.array(geoms), np.array(foot)


def geom_bottoms(model, geoms, centres_m, rotations) -> np.ndarray:
    """Height of the lowest point of geoms, metres, over any number of states.

    Exact for spheres, capsules, cylinders, boxes and ellipsoids.

    Parameters
    ----------
    model : mujoco.MjModel
    geoms : ndarray of int, shape (G,)
    centres_m : ndarray, shape (..., G, 3)
        The geoms' centres (``data.geom_xpos``), z up.
    rotations : ndarray, shape (..., G, 3, 3)
        Their orientations (``data.geom_xmat``).

    Returns
    -------
    ndarray, shape (..., G)
    """
    import mujoco

    kinds = model.geom_type[geoms]
    size = model.geom_size[geoms]
    up = rotations[..., 2, :]  # the z component of each local axis
    g = mujoco.mjtGeom
    drop = np.full(up.shape[:-1], np.nan)
    drop = np.where(kinds == g.mjGEOM_SPHERE, size[:, 0], drop)
    drop = np.where(kinds == g.mjGEOM_CAPSULE, np.abs(size[:, 1] * up[..., 2]) + size[:, 0],
                    drop)
    drop = np.where(kinds == g.mjGEOM_CYLINDER,
                    np.abs(size[:, 1] * up[..., 2])
                    + size[:, 0] * np.sqrt(np.clip(1.0 - up[..., 2] ** 2, 0.0, 1.0)), drop)
    drop = np.where(kinds == g.mjGEOM_BOX, np.abs(size * up).sum(axis=-1), drop)
    drop = np.where(kinds == g.mjGEOM_ELLIPSOID, np.sqrt(((size * up) ** 2).sum(axis=-1)),
                    drop)
    if np.isnan(drop).any():
        raise ValueError("foot geoms must be spheres, capsules, cylinders, boxes or "
                         "ellipsoids")
    return centres_m[..., 2] - drop


def feet_over_frames(model, qpos) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres and lowest points of the foot geoms in every state.

    Parameters
    ----------
    qpos : array_like, shape (T, nq)

    Returns
    -------
    centres_m : ndarray, shape (T, G, 3)
    bottoms_m : ndarray, shape (T, G)
    foot : ndarray of int, shape (G,)
    """
    import mujoco

    geoms, foot = foot_geoms(model)
    qpos = np.atleast_2d(qpos)
    data = mujoco.MjData(model)
    centres = np.empty((qpos.shape[0], len(geoms), 3))
    rotations = np.empty((qpos.shape[0], len(geoms), 9))
    for t, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        centres[t] = data.geom_xpos[geoms]
        rotations[t] = data.geom_xmat[geoms]
    bottoms = geom_bottoms(model, geoms, centres, rotations.reshape(*rotations.shape[:2], 3, 3))
    return centres, bottoms, foot


def added_self_collision(frame_pairs: list[dict]) -> np.ndarray:
    """Which inner frames have a self-collision between a body pair that is not in
    self-collision at either end.

    Parameters
    ----------
    frame_pairs : list of dict
        Per frame, the body pairs in self-collision (``Validity.self_pairs()``): the first
        and last frames are the window's two end postures.

    Returns
    -------
    ndarray of bool, shape (len(frame_pairs) - 2,)
    """
    at_ends = set(frame_pairs[0]) | set(frame_pairs[-1])
    return np.array([bool(set(p) - at_ends) for p in frame_pairs[1:-1]], dtype=bool)


def end_self_collision(model, motion, window: slice) -> list[bool]:
    """Whether the window's two end postures (the frames just before and after it) are
    themselves in self-collision: [A, B]."""
    from controller.checks.validity import check_motion

    n = motion.n_frames
    w0, w1, _ = window.indices(n)
    index = [w0 - 1, w1]
    both = motion.replace(posture_deg=motion.posture_deg[index], root=motion.root[index],
                          extra_deg=None)
    return [bool(x) for x in check_motion(model, both).self_collision]


def score_window(model, motion, window: slice, real, zones) -> dict[str, float]:
    """Every metric of one window.

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid of ``motion``'s skeleton.
    motion : upm.Motion
        The window and the motion around it (at least one frame on each side).
    window : slice
        The window's frames in ``motion``.
    real : eval.realdata.RealPostures
        The real postures the nearest-real distance searches.
    zones : list of eval.pairs.Segment
        The real frames it ignores.

    Returns
    -------
    dict of str to float
        By metric name (:data:`eval.metrics.METRICS`), rounded to 6 decimals.
    """
    from controller.checks.dynamics import root_residual
    from controller.checks.validity import check_motion
    from controller.qpos import to_qpos
    from controller.tracking.servo import track

    n = motion.n_frames
    w0, w1, _ = window.indices(n)
    if w0 < 1 or w1 > n - 1 or w1 <= w0:
        raise ValueError(f"window {w0}:{w1} needs a frame on each side in a motion of {n}")
    length = w1 - w0

    ends = motion.frames(w0 - 1, w1 + 1)
    validity = check_motion(model, ends, (slice(1, length + 1),))
    inside = slice(1, length + 1)
    added = validity.added_excess_deg[inside].max(axis=1)
    added_self = added_self_collision(validity.self_pairs())
    valid_added = ~(validity.added_limit_violation[inside] | added_self
                    | validity.floor_penetration[inside])

    nearest = real.nearest_rms_deg(motion.posture_deg[w0:w1], zones)
    jerk = window_jerk_rms(motion.posture_deg, slice(w0, w1), motion.fps, real.dofs)

    c0, c1 = max(0, w0 - RESIDUAL_CONTEXT), min(n, w1 + RESIDUAL_CONTEXT)
    qpos = to_qpos(model, motion.frames(c0, c1))
    residual = root_residual(model, qpos, motion.fps).force_bw[w0 - c0:w1 - c0]
    centres, bottoms, foot = feet_over_frames(model, qpos)
    skate = foot_skate_mps(centres, bottoms, foot, motion.fps)[w0 - c0:w1 - c0]
    tracking = track(model, motion.frames(c0, c1), mode="driven").summary(
        slice(w0 - c0, w1 - c0))

    values = {
        "valid_pct": 100.0 * validity.valid_beyond_ends[inside].mean(),
        "raw_valid_pct": 100.0 * validity.valid[inside].mean(),
        "valid_added_pct": 100.0 * valid_added.mean(),
        "added_limit_mean_deg": added.mean(),
        "added_limit_max_deg": added.max(),
        "self_collision_pct": 100.0 * validity.self_collision[inside].mean(),
        "self_collision_added_pct": 100.0 * added_self.mean(),
        "self_depth_max_mm": 1000.0 * validity.self_depth_m[inside].max(),
        "floor_penetration_pct": 100.0 * validity.floor_penetration[inside].mean(),
        "beyond_asf_pct": 100.0 * validity.beyond_asf[inside].mean(),
        "nearest_real_mean_deg": nearest.mean(),
        "nearest_real_max_deg": nearest.max(),
        "jerk_rms_deg_s3": jerk,
        "foot_skate_mps": skate.mean(),
        "residual_force_mean_bw": residual.mean(),
        "residual_force_peak_bw": residual.max(),
        "tracking_error_deg": tracking["error_all_deg_rms"],
    }
    return {k: round(float(v), 6) for k, v in values.items()}
