"""Inverse dynamics of a motion: the external force and torque ("hand of god") it needs
beyond what contact with the floor can supply (SPEC section 6).

Per frame:

1. **Smoothing**: the trajectory is low-passed (:func:`lowpass_qpos`: zero-phase
   2nd-order Butterworth, ``residual.lowpass_hz`` = 12 Hz, on the unwrapped hinge angles, the
   root position and the root quaternion's components). Mocap noise, twice
   differentiated, swamps the physics otherwise: on the walk 02_01 the needed force
   averages 1.57 body weights unfiltered (walking needs 1.0 on average) and 1.01 filtered,
   and the residual drops from 0.41 to 0.04 body weights. Every motion, real or made by
   any transition method, goes through the same filter (``lowpass_hz=None`` turns it off).
2. **Finite differences** at the motion's own frame rate: half-step velocities
   ``v(t+1/2) = mj_differentiatePos(q(t), q(t+1)) * fps`` (the free joint's rotation on
   the quaternion, hinges unwrapped along time first); ``qvel(t)`` is the mean of the two
   half-step velocities around t (central difference) and
   ``qacc(t) = (v(t+1/2) - v(t-1/2)) * fps`` (the second central difference). The first
   and last frames take their neighbour's acceleration and the one-sided velocity.
3. **Needed wrench**: ``mj_inverse`` with every constraint (contacts, joint limits)
   disabled gives the generalised force that produces the motion; its free-joint part is
   the net external force and torque the whole body needs (at the root, the pelvis).
   Joint-limit and self-contact forces are internal and do not change it.
4. **Support**: every point where a geom comes within ``residual.support_distance_m`` of the
   floor (MuJoCo's collision with that margin on the floor) may push with a force inside a
   friction pyramid (4 edges ``n +- mu t1``, ``n +- mu t2``, ``mu`` =
   ``residual.friction``, the simulated floor's 1.0: what a contact could supply at most;
   the balance controller plans with less, ``contact.friction``). The non-negative
   combination of the edge forces that best supplies the needed wrench is found by
   non-negative least squares (``scipy.optimize.nnls``), torque rows divided by the body's
   stature so both are in newtons.
5. **Residual**: needed minus supplied — what no contact could give. Reported as force /
   body weight (1.0 = the body's weight) and torque about the root / (body weight x
   stature).

Why not ``mj_inverse`` with MuJoCo's own contacts: soft contacts give a force only from
penetration and velocity, so a foot resting exactly on the floor gets none (the residual
of standing still would be the whole weight) and a foot 1 mm in gets a stiff spring's
force. :func:`raw_inverse_with_contacts` gives that number for comparison.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.config import DEFAULT

# The check's settings are the configuration's ``residual`` section
# (controller.config.sections.ResidualConfig), where the measurements that chose them are.
_RESIDUAL = DEFAULT.residual


def unwrap_hinges(model, qpos) -> np.ndarray:
    """``qpos`` with every hinge unwrapped along time (no 2 pi jumps between frames).

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : array_like, shape (T, nq)

    Returns
    -------
    ndarray, shape (T, nq)
    """
    from controller.qpos import joint_layout

    qpos = np.array(qpos, dtype=float, ndmin=2)
    columns = joint_layout(model).qpos_address
    qpos[:, columns] = np.unwrap(qpos[:, columns], axis=0)
    return qpos


def lowpass_qpos(model, qpos, fps: float,
                 cutoff_hz: float = _RESIDUAL.lowpass_hz) -> np.ndarray:
    """A trajectory low-passed by a zero-phase 2nd-order Butterworth filter.

    Hinges are unwrapped first; the root quaternion's sign is made continuous, its four
    components filtered and renormalised. Trajectories of fewer than 3 frames, or a
    cut-off at or above the Nyquist frequency, come back unchanged.

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : array_like, shape (T, nq)
    fps : float
    cutoff_hz : float

    Returns
    -------
    ndarray, shape (T, nq)
    """
    from scipy.signal import butter, filtfilt

    from controller.qpos import joint_layout

    qpos = unwrap_hinges(model, qpos)
    n = qpos.shape[0]
    if n < 3 or cutoff_hz >= 0.5 * fps:
        return qpos
    start = joint_layout(model).free_qpos
    quat = qpos[:, start + 3:start + 7]
    flips = np.sum(quat[1:] * quat[:-1], axis=1) < 0
    quat *= np.concatenate([[1.0], np.where(np.cumsum(flips) % 2 == 1, -1.0, 1.0)])[:, None]
    b, a = butter(2, cutoff_hz / (0.5 * fps))
    out = filtfilt(b, a, qpos, axis=0, padlen=min(n - 1, 3 * max(len(a), len(b))))
    out[:, start + 3:start + 7] /= np.linalg.norm(out[:, start + 3:start + 7], axis=1,
                                                  keepdims=True)
    return out


def half_step_velocities(model, qpos, fps: float) -> np.ndarray:
    """``mj_differentiatePos(q(t), q(t+1)) * fps``: the velocity between consecutive
    states (the free joint's rotation on the quaternion manifold), shape (T-1, nv)."""
    import mujoco

    qpos = np.atleast_2d(qpos)
    out = np.zeros((max(qpos.shape[0] - 1, 0), model.nv))
    for t in range(qpos.shape[0] - 1):
        mujoco.mj_differentiatePos(model, out[t], 1.0 / fps, qpos[t], qpos[t + 1])
    return out


def finite_differences(model, qpos, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and accelerations of a trajectory by central differences.

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : array_like, shape (T, nq)
    fps : float
        Frames per second of ``qpos``.

    Returns
    -------
    qvel : ndarray, shape (T, nv)
    qacc : ndarray, shape (T, nv)
        Zero for a single frame; ``qacc`` is zero for two.
    """
    qpos = unwrap_hinges(model, qpos)
    n = qpos.shape[0]
    half = half_step_velocities(model, qpos, fps)
    qvel = np.zeros((n, model.nv))
    qacc = np.zeros((n, model.nv))
    if n < 2:
        return qvel, qacc
    qvel[0], qvel[-1] = half[0], half[-1]
    qvel[1:-1] = 0.5 * (half[:-1] + half[1:])
    if n > 2:
        qacc[1:-1] = (half[1:] - half[:-1]) * fps
        qacc[0], qacc[-1] = qacc[1], qacc[-2]
    return qvel, qacc


@dataclass(frozen=True)
class RootResidual:
    """The external wrench a motion needs, per frame (world frame, at the root).

    Attributes
    ----------
    fps : float
    weight_n : float
        The body's weight (newtons), the unit of the normalised force.
    stature_m : float
        The body's stature; torques are normalised by ``weight_n * stature_m``.
    needed_force_n, needed_torque_nm : ndarray, shape (T, 3)
        The net external force and torque (about the root) the motion needs.
    residual_force_n, residual_torque_nm : ndarray, shape (T, 3)
        What remains once the best floor support is subtracted.
    support_points : ndarray of int, shape (T,)
        Contact points within ``support_distance_m`` of the floor.
    """

    fps: float
    weight_n: float
    stature_m: float
    needed_force_n: np.ndarray
    needed_torque_nm: np.ndarray
    residual_force_n: np.ndarray
    residual_torque_nm: np.ndarray
    support_points: np.ndarray

    @property
    def n_frames(self) -> int:
        return self.residual_force_n.shape[0]

    @property
    def force_bw(self) -> np.ndarray:
        """Residual force magnitude / body weight, (T,)."""
        return np.linalg.norm(self.residual_force_n, axis=1) / self.weight_n

    @property
    def torque_bwh(self) -> np.ndarray:
        """Residual torque magnitude / (body weight x stature), (T,)."""
        return (np.linalg.norm(self.residual_torque_nm, axis=1)
                / (self.weight_n * self.stature_m))

    @property
    def needed_force_bw(self) -> np.ndarray:
        """Needed force magnitude / body weight, before any support, (T,)."""
        return np.linalg.norm(self.needed_force_n, axis=1) / self.weight_n

    def summary(self, part: slice | None = None) -> dict:
        """Mean and peak of the normalised residuals over a part (all frames by default),
        JSON-ready."""
        part = part if part is not None else slice(None)
        force, torque = self.force_bw[part], self.torque_bwh[part]
        if force.size == 0:
            return {"residual_force_bw_mean": 0.0, "residual_force_bw_peak": 0.0,
                    "residual_torque_bwh_mean": 0.0, "residual_torque_bwh_peak": 0.0}
        return {
            "residual_force_bw_mean": round(float(force.mean()), 4),
            "residual_force_bw_peak": round(float(force.max()), 4),
            "residual_torque_bwh_mean": round(float(torque.mean()), 4),
            "residual_torque_bwh_peak": round(float(torque.max()), 4),
        }


def root_residual(model, qpos, fps: float,
                  support_distance_m: float = _RESIDUAL.support_distance_m,
                  friction: float = _RESIDUAL.friction,
                  lowpass_hz: float | None = _RESIDUAL.lowpass_hz) -> RootResidual:
    """The external wrench a trajectory needs beyond what floor contact can supply.

    Parameters
    ----------
    model : mujoco.MjModel
        A humanoid made by :func:`humanoid_xml.build_mjcf` (not modified: flags and
        margins are restored on return).
    qpos : array_like, shape (T, nq)
        E.g. :func:`controller.to_qpos` of a motion.
    fps : float
        Its frame rate (the finite differences' step).
    support_distance_m : float
        Geoms closer than this to the floor can be pushed, m.
    friction : float
        Friction coefficient of the support pyramid.
    lowpass_hz : float or None
        Cut-off of the smoothing filter (:func:`lowpass_qpos`); None: no smoothing.
        (The defaults: :class:`controller.config.sections.ResidualConfig`.)

    Returns
    -------
    RootResidual

    Raises
    ------
    UsageError
        If ``qpos`` or the wrench it needs is not finite (a motion whose values are far
        beyond any physical range): never a silent NaN or a solver traceback.
    """
    from scipy.optimize import nnls

    from controller.body import body_figures
    from upm.core.errors import UsageError

    if not np.all(np.isfinite(qpos)) or not np.isfinite(fps) or fps <= 0:
        raise UsageError("root residual: the trajectory holds NaN or infinite positions "
                         "(or the frame rate is not a positive number)")
    figures = body_figures(model)
    qpos = (unwrap_hinges(model, qpos) if lowpass_hz is None
            else lowpass_qpos(model, qpos, fps, lowpass_hz))
    qvel, qacc = finite_differences(model, qpos, fps)
    needed, contacts = _needed_and_contacts(model, qpos, qvel, qacc, support_distance_m)
    if not np.all(np.isfinite(needed)):
        raise UsageError("root residual: the motion's accelerations overflow (values far "
                         "beyond any physical range)")
    frame, pos, normal, t1, t2 = contacts
    n = qpos.shape[0]
    # Everything in the world frame from here: the root force is world-frame already,
    # the torque was turned from the root's frame; a unit force along edge d at point p
    # gives the wrench [d, (p - x_root) x d].
    edges = np.stack([normal + friction * t1, normal - friction * t1,
                      normal + friction * t2, normal - friction * t2], axis=1)  # (K, 4, 3)
    arms = np.broadcast_to(pos[:, None, :], edges.shape)
    columns = np.concatenate([edges, np.cross(arms, edges)], axis=2)  # (K, 4, 6)
    weights = np.array([1.0, 1.0, 1.0] + [1.0 / figures.stature_m] * 3)
    residual = needed.copy()
    points = np.bincount(frame, minlength=n)
    bounds = np.concatenate([[0], np.cumsum(points)])
    for t in np.flatnonzero(points):
        block = columns[bounds[t]:bounds[t + 1]].reshape(-1, 6).T  # (6, 4k)
        lam, _ = nnls(weights[:, None] * block, weights * needed[t])
        residual[t] = needed[t] - block @ lam
    return RootResidual(
        fps=float(fps), weight_n=figures.weight_n, stature_m=figures.stature_m,
        needed_force_n=needed[:, :3], needed_torque_nm=needed[:, 3:],
        residual_force_n=residual[:, :3], residual_torque_nm=residual[:, 3:],
        support_points=points,
    )


def _needed_and_contacts(model, qpos, qvel, qacc, support_distance_m: float):
    """Per frame, the needed root wrench (world frame, torque about the root) and the
    floor contact points within ``support_distance_m``.

    Returns
    -------
    needed : ndarray, shape (T, 6)
    contacts : tuple of arrays
        ``frame`` (K,) sorted, and per contact ``arm`` (position relative to the root),
        ``normal`` (pushing the body away from the floor), ``t1``, ``t2`` (K, 3).
    """
    import mujoco

    from controller.qpos import free_joint, joint_layout

    layout = joint_layout(model)
    root_dofs = slice(layout.free_dof, layout.free_dof + 6)
    root_body = int(model.jnt_bodyid[free_joint(model)])
    floor = np.flatnonzero(model.geom_bodyid == 0)
    geom_body = model.geom_bodyid
    n = qpos.shape[0]
    needed = np.zeros((n, 6))
    frames, arms, frames_9, signs = [], [], [], []
    data = mujoco.MjData(model)
    saved_flags, saved_margin = model.opt.disableflags, model.geom_margin[floor].copy()
    try:
        for t in range(n):
            data.qpos[:], data.qvel[:], data.qacc[:] = qpos[t], qvel[t], qacc[t]
            model.opt.disableflags = saved_flags | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
            mujoco.mj_inverse(model, data)
            model.opt.disableflags = saved_flags
            force = data.qfrc_inverse[root_dofs]
            rot = data.xmat[root_body].reshape(3, 3)
            needed[t, :3] = force[:3]
            needed[t, 3:] = rot @ force[3:]  # the rotational DOFs are in the root's frame
            model.geom_margin[floor] = support_distance_m
            mujoco.mj_collision(model, data)
            model.geom_margin[floor] = saved_margin
            k = data.ncon
            if not k:
                continue
            bodies = geom_body[data.contact.geom[:k]]
            on_floor = (bodies[:, 0] == 0) != (bodies[:, 1] == 0)
            if on_floor.any():
                frames.append(np.full(int(on_floor.sum()), t))
                arms.append(data.contact.pos[:k][on_floor] - data.xpos[root_body])
                frames_9.append(data.contact.frame[:k][on_floor])
                # The normal points from geom1 to geom2: make it push the body.
                signs.append(np.where(bodies[on_floor, 0] == 0, 1.0, -1.0))
    finally:
        model.opt.disableflags = saved_flags
        model.geom_margin[floor] = saved_margin
    if not frames:
        empty = np.zeros((0, 3))
        return needed, (np.zeros(0, dtype=int), empty, empty, empty, empty)
    frame9 = np.concatenate(frames_9).reshape(-1, 3, 3)
    sign = np.concatenate(signs)[:, None]
    return needed, (np.concatenate(frames), np.concatenate(arms), sign * frame9[:, 0],
                    frame9[:, 1], frame9[:, 2])


def raw_inverse_with_contacts(model, qpos, fps: float,
                              lowpass_hz: float | None = _RESIDUAL.lowpass_hz) -> np.ndarray:
    """The free-joint force of plain ``mj_inverse`` with MuJoCo's soft contacts, for
    comparison with :func:`root_residual` (see the module docstring).

    Returns
    -------
    ndarray, shape (T, 3)
        World-frame force at the root, newtons.
    """
    import mujoco

    from controller.qpos import joint_layout

    qpos = (unwrap_hinges(model, qpos) if lowpass_hz is None
            else lowpass_qpos(model, qpos, fps, lowpass_hz))
    qvel, qacc = finite_differences(model, qpos, fps)
    start = joint_layout(model).free_dof
    data = mujoco.MjData(model)
    out = np.zeros((qpos.shape[0], 3))
    for t in range(qpos.shape[0]):
        data.qpos[:], data.qvel[:], data.qacc[:] = qpos[t], qvel[t], qacc[t]
        mujoco.mj_inverse(model, data)
        out[t] = data.qfrc_inverse[start:start + 3]
    return out
