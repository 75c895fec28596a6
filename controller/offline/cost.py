"""A state's cost against the reference (:class:`controller.config.OfflineWeights`): the
offline search (:mod:`controller.offline.samcon`) keeps the samples that cost least.

The features of a state (:class:`Features`) are what the cost compares: the hinge angles,
the pelvis's orientation and height, the end effectors (head, hands, feet) in the pelvis's
frame, and the capture point's horizontal offset from the middle of the feet (the centre
of mass moved by its velocity times ``sqrt(h / g)``, h its height above the feet: where
the body is heading to, so that a sample drifting off its support costs before it is
off); and the pelvis's and head's heights, for the fall rule."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.qpos import free_joint, joint_layout, wrap_rad

#: The end effectors' sites.
END_SITES = ("head_end", "lhand_end", "rhand_end", "lfoot_end", "rfoot_end")
#: The sites whose middle is the support the centre of mass is measured from.
FOOT_SITES = ("lfoot_end", "ltoes_end", "rfoot_end", "rtoes_end")


@dataclass(frozen=True)
class Features:
    """The features of N states.

    Attributes
    ----------
    hinges : ndarray, shape (N, H)
        Hinge angles, rad.
    root_quat : ndarray, shape (N, 4)
        The pelvis's orientation (w, x, y, z).
    root_height_m, head_height_m : ndarray, shape (N,)
    ends_m : ndarray, shape (N, E, 3)
        The end effectors in the pelvis's frame, m.
    balance_m : ndarray, shape (N, 2)
        The capture point's horizontal offset from the middle of the feet, m.
    """

    hinges: np.ndarray
    root_quat: np.ndarray
    root_height_m: np.ndarray
    head_height_m: np.ndarray
    ends_m: np.ndarray
    balance_m: np.ndarray


class FeatureMaker:
    """Computes :class:`Features` of states on one model (a scratch ``MjData``)."""

    def __init__(self, model):
        import mujoco

        self.model = model
        self.data = mujoco.MjData(model)
        layout = joint_layout(model)
        self.hinge_q = layout.qpos_address
        self.free_q = layout.free_qpos
        self.root_body = int(model.jnt_bodyid[free_joint(model)])

        def site(name):
            i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, name)
            if i < 0:
                raise ValueError(f"the model has no site {name!r} (not a humanoid_xml model?)")
            return i

        self.end_sites = np.array([site(s) for s in END_SITES])
        self.foot_sites = np.array([site(s) for s in FOOT_SITES])
        self.head_site = site("head_end")
        self.mass = np.asarray(model.body_mass)[:, None]
        self.total_mass = float(self.mass.sum())
        self.gravity = float(np.linalg.norm(model.opt.gravity))
        self.jac = np.zeros((3, model.nv))

    def reference(self, qpos, fps: float) -> Features:
        """The features of a reference ``qpos`` (T, nq) at ``fps`` (its centre of mass's
        velocity by central differences)."""
        com = self._com(qpos)
        return self(qpos, com_velocity=np.gradient(com, 1.0 / fps, axis=0))

    def _com(self, qpos) -> np.ndarray:
        import mujoco

        out = np.empty((qpos.shape[0], 3))
        for i in range(qpos.shape[0]):
            self.data.qpos[:] = qpos[i]
            mujoco.mj_kinematics(self.model, self.data)
            out[i] = (self.mass * self.data.xipos).sum(axis=0) / self.total_mass
        return out

    def __call__(self, qpos, qvel=None, com_velocity=None) -> Features:
        """The features of states ``qpos`` (N, nq) with velocities ``qvel`` (N, nv) or the
        centre of mass's velocities ``com_velocity`` (N, 3) (neither: at rest)."""
        import mujoco

        qpos = np.atleast_2d(qpos)
        n = qpos.shape[0]
        ends = np.empty((n, len(END_SITES), 3))
        balance = np.empty((n, 2))
        head = np.empty(n)
        data = self.data
        for i in range(n):
            data.qpos[:] = qpos[i]
            mujoco.mj_kinematics(self.model, data)
            root_pos = data.xpos[self.root_body]
            root_mat = data.xmat[self.root_body].reshape(3, 3)
            ends[i] = (data.site_xpos[self.end_sites] - root_pos) @ root_mat
            com = (self.mass * data.xipos).sum(axis=0) / self.total_mass
            if com_velocity is not None:
                velocity = com_velocity[i]
            elif qvel is not None:
                mujoco.mj_comPos(self.model, data)
                mujoco.mj_jacSubtreeCom(self.model, data, self.jac, self.root_body)
                velocity = self.jac @ qvel[i]
            else:
                velocity = np.zeros(3)
            feet = data.site_xpos[self.foot_sites]
            height = max(com[2] - feet[:, 2].mean(), 0.05)
            capture = com[:2] + velocity[:2] * np.sqrt(height / self.gravity)
            balance[i] = capture - feet[:, :2].mean(axis=0)
            head[i] = data.site_xpos[self.head_site, 2]
        quat = qpos[:, self.free_q + 3:self.free_q + 7]
        return Features(hinges=qpos[:, self.hinge_q], root_quat=quat,
                        root_height_m=qpos[:, self.free_q + 2].copy(), head_height_m=head,
                        ends_m=ends, balance_m=balance)


def state_cost(sim: Features, ref: Features, weights) -> np.ndarray:
    """The cost of each simulated state against its reference state, shape (N,).

    Parameters
    ----------
    sim, ref : Features
        N states each (``ref`` may hold one state, broadcast).
    weights : controller.config.OfflineWeights
    """
    pose = np.sum(wrap_rad(sim.hinges - ref.hinges) ** 2, axis=1)
    dot = np.abs(np.sum(sim.root_quat * ref.root_quat, axis=1))
    root = (2 * np.arccos(np.clip(dot / (np.linalg.norm(sim.root_quat, axis=1)
                                         * np.linalg.norm(ref.root_quat, axis=1)), 0, 1))) ** 2
    height = (sim.root_height_m - ref.root_height_m) ** 2
    end = np.sum((sim.ends_m - ref.ends_m) ** 2, axis=(1, 2))
    balance = np.sum((sim.balance_m - ref.balance_m) ** 2, axis=1)
    return (weights.pose * pose + weights.root * root + weights.height * height
            + weights.end * end + weights.balance * balance)
