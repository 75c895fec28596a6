"""The swing foot's sole at the reference's tilt, whatever the swing leg was moved by.

The foot placement (:mod:`controller.balance.placement`) moves the swing ankle by the hip's (and,
to lift it, the knee's) angles; the ankle's own angles stay the reference's, so the sole
turns with every such change, and with the pelvis's own tilt error: a hip flexed by 10
degrees to step further lands the foot with its toes 10 degrees higher than the
reference's, a hip extended lands it on its toes. Here, while a foot is in the air, its
ankle's targets become the angles that turn the foot to the reference's tilt at the
frame: the foot lands as the reference lands it, heel or forefoot first, flat where the
reference is flat. Only the tilt is asked for, not the heading (the character's heading
drifts from the reference's: :mod:`controller.balance.placement`); the CMU ankle has a flexion
hinge and a near-vertical one, so the pitch is put back and the roll only in part.

The tilt is compared through the reference's vertical as the foot's own frame sees it:
``up`` (per frame, from the reference's forward kinematics). In the character that
direction points along ``R @ up`` (``R`` the foot's orientation), and the rotation that
turns it back to the vertical is, to first order, ``w = (R @ up) x z``; the ankle's hinges
(axes ``a_k``, world frame) supply it by the damped least-squares ``delta`` of
``sum_k a_k delta_k = w``.
"""

from __future__ import annotations

import numpy as np

from controller.balance.leg_kernels import tilt_ankle
from controller.config import DEFAULT, ControllerConfig


class SwingFootTilt:
    """Ankle targets that keep each foot in the air at the reference's tilt.

    Parameters
    ----------
    model : mujoco.MjModel
    reference_qpos : ndarray, shape (T, nq)
        The targets' reference (the controller's low-passed one).
    foot_bodies : sequence of int
        The foot (ankle) body of each side, in :class:`controller.balance.placement.FootPlacement`
        order (left, right).
    config : controller.config.ControllerConfig
        Its ``foot_tilt.damping``: the damping of the ankle's least-squares turn.

    Attributes
    ----------
    up : ndarray, shape (T, sides, 3)
        The world vertical in each foot's frame, per reference frame.
    """

    def __init__(self, model, reference_qpos, foot_bodies,
                 config: ControllerConfig = DEFAULT):
        import mujoco

        self.foot_bodies = [int(b) for b in foot_bodies]
        self.hinges, self.qpos_address = [], []
        for foot in self.foot_bodies:
            joints = [j for j in range(model.njnt) if int(model.jnt_bodyid[j]) == foot
                      and model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]
            if not joints:
                raise ValueError(f"foot body {foot} has no hinge")
            self.hinges.append(np.array(joints))
            self.qpos_address.append(np.array([int(model.jnt_qposadr[j]) for j in joints]))
        data = mujoco.MjData(model)
        n = reference_qpos.shape[0]
        self.up = np.empty((n, len(self.foot_bodies), 3))
        for t in range(n):
            data.qpos[:] = reference_qpos[t]
            mujoco.mj_kinematics(model, data)
            # row 2 of the body's rotation: the world z axis in the body's frame
            self.up[t] = data.xmat[self.foot_bodies].reshape(-1, 3, 3)[:, 2, :]
        damping = config.foot_tilt.damping
        self._damping = [damping * np.eye(len(h)) for h in self.hinges]
        # the compiled kernel loads now, not at the first step with a foot in the air
        # (after the controller's clock has started)
        tilt_ankle(data.xmat[self.foot_bodies[0]], self.up[0, 0], data.xaxis, self.hinges[0],
                   self._damping[0], data.qpos, self.qpos_address[0], data.qpos.copy())

    def adjust(self, data, frame: int, q_ref, touching) -> None:
        """Set the ankle targets of every foot in the air in ``q_ref`` (in place).

        Parameters
        ----------
        data : mujoco.MjData
            After ``mj_step1`` (``xmat``, ``xaxis``).
        frame : int
            The reference frame of the step.
        q_ref : ndarray, shape (nq,)
        touching : sequence of bool
            Whether each foot touches the floor
            (:meth:`controller.balance.placement.FootPlacement.touching`).
        """
        for side, foot in enumerate(self.foot_bodies):
            if not touching[side]:
                tilt_ankle(data.xmat[foot], self.up[frame, side], data.xaxis,
                           self.hinges[side], self._damping[side], data.qpos,
                           self.qpos_address[side], q_ref)
