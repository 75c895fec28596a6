"""Foot placement: where the swing foot should land for the body to stay balanced.

Joint tracking and a whole-body QP keep the character's pose, but the horizontal motion of
its centre of mass can only be corrected while a foot is on the floor by shifting the
centre of pressure, which the ankles' strength allows over a few centimetres. Walking
balance comes from where the next foot lands (SIMBICON, Yin et al. 2007; the capture
point, Pratt et al. 2006). Here the swing foot is moved, relative to where the reference's
joint angles put it, by the difference between the character's and the reference's
*capture offset*: the centre of mass's horizontal offset from the stance foot plus its
horizontal velocity times ``sqrt(h / g)`` (``h`` the centre of mass height), the
reference's taken at the frame nearest the current one where it has the character's stance
foot down (the current one when it has). The shift is made by the swing hip's three hinges
(the least-norm change that moves the ankle by it, from the ankle's Jacobian).

A leg swings when none of its foot's bodies touch the floor while the other's do; with
both feet down or both up nothing is changed.
"""

from __future__ import annotations

import math

import numpy as np

from controller.balance.leg_kernels import capture_shift, move_point
from controller.checks.contacts import floor_contacts
from controller.config import DEFAULT, ControllerConfig

_SIDES = ("l", "r")


class FootPlacement:
    """Swing-hip corrections for one model and reference.

    Parameters
    ----------
    model : mujoco.MjModel
    reference_qpos : ndarray, shape (T, nq)
    fps : float
    config : controller.config.ControllerConfig
        Its ``placement`` section (:class:`controller.config.sections.PlacementConfig`):
        the default gain, the largest shift, when a reference foot is down, the swing
        height and clearance, the leg's inverse kinematics.
    """

    def __init__(self, model, reference_qpos, fps: float,
                 config: ControllerConfig = DEFAULT):
        import mujoco

        self._mj_subtreeVel, self._mj_jac = mujoco.mj_subtreeVel, mujoco.mj_jac

        def body(name):
            i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            if i < 0:
                raise ValueError(f"the model has no body {name!r}")
            return i

        self.model = model
        settings = config.placement
        self.settings = settings
        self.gain = float(settings.gain)
        self.max_turn_rad = math.radians(settings.max_turn_deg)
        self.ankle = np.array([body(f"{s}foot") for s in _SIDES])
        self.foot_bodies = [
            {b for b in range(model.nbody) if _descends(model, b, body(f"{s}foot"))}
            for s in _SIDES]
        hips = []
        for s in _SIDES:
            dofs = [int(model.jnt_dofadr[j]) for j in range(model.njnt)
                    if (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or "")
                    .startswith(f"{s}femur_")]
            qadr = [int(model.jnt_qposadr[j]) for j in range(model.njnt)
                    if (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or "")
                    .startswith(f"{s}femur_")]
            if settings.swing_height:
                knee = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"{s}tibia_rx")
                dofs.append(int(model.jnt_dofadr[knee]))
                qadr.append(int(model.jnt_qposadr[knee]))
            hips.append((np.array(dofs), np.array(qadr)))
        self.hips = hips
        # which foot (0 left, 1 right) each body belongs to, -1 neither
        self._side_of_body = [-1] * model.nbody
        for side, bodies in enumerate(self.foot_bodies):
            for b in bodies:
                self._side_of_body[b] = side
        self._jacp = np.zeros((3, model.nv))
        # the reference's centre of mass, its velocity and the ankles, per frame
        data = mujoco.MjData(model)
        n = reference_qpos.shape[0]
        self.ref_com = np.empty((n, 3))
        self.ref_ankle = np.empty((n, 2, 3))
        for t in range(n):
            data.qpos[:] = reference_qpos[t]
            mujoco.mj_kinematics(model, data)
            mujoco.mj_comPos(model, data)
            self.ref_com[t] = data.subtree_com[1]
            self.ref_ankle[t] = data.xpos[self.ankle]
        self.ref_com_vel = np.gradient(self.ref_com, 1.0 / fps, axis=0)
        # the reference's feet on the floor: slow and low (mocap contact detection)
        speed = np.linalg.norm(np.gradient(self.ref_ankle, 1.0 / fps, axis=0), axis=2)
        height = self.ref_ankle[:, :, 2]
        low = height < height.min(axis=0) + settings.foot_down_height_m
        self.ref_down = (speed < settings.foot_down_speed_mps) & low  # (T, 2)
        self._down_frames = [np.flatnonzero(self.ref_down[:, side]) for side in range(2)]
        # per frame and side, the nearest frame with that foot down (:meth:`_nearest_down`)
        self.down_frame = np.array([[self._nearest_down(t, side) for side in range(2)]
                                    for t in range(n)], dtype=int).reshape(n, 2)
        g = float(np.linalg.norm(model.opt.gravity))
        self.time_constant_s = math.sqrt(max(float(np.median(self.ref_com[:, 2])), 0.1) / g)

    def _nearest_down(self, frame: int, side: int) -> int:
        """The frame nearest ``frame`` at which the reference has foot ``side`` down
        (``frame`` itself when it is down, or never is; the earlier on a tie)."""
        down = self._down_frames[side]
        if self.ref_down[frame, side] or not down.size:
            return frame
        k = int(np.searchsorted(down, frame))
        near = [down[j] for j in (k - 1, k) if 0 <= j < down.size]
        return int(min(near, key=lambda d: abs(d - frame)))

    def swing_bodies(self, frame: int) -> set:
        """The bodies of the feet that the reference has in the air at a frame."""
        out = set()
        for side in range(2):
            if not self.ref_down[frame, side]:
                out |= self.foot_bodies[side]
        return out

    def touching(self, floor_bodies) -> tuple[bool, bool]:
        """Whether each foot (left, right) touches the floor, given the bodies of the
        state's floor contacts (:func:`controller.checks.contacts.floor_contacts`)."""
        out = [False, False]
        side_of_body = self._side_of_body
        for b in floor_bodies:
            side = side_of_body[b]
            if side >= 0:
                out[side] = True
        return out[0], out[1]

    def adjust(self, data, frame: int, q_ref, gain: float | None = None,
               clearance_m: float | None = None, floor_bodies=None) -> np.ndarray:
        """Shift the swing hip's angles in ``q_ref`` (in place) for the current state.

        Parameters
        ----------
        data : mujoco.MjData
            After ``mj_step1`` (positions, centre of mass; velocities are read from
            ``qvel``).
        frame : int
            The reference frame of the step.
        q_ref : ndarray, shape (nq,)
        gain : float, optional
            This step's gain (default the placement's own).
        clearance_m : float, optional
            This step's swing clearance (default the configuration's
            ``placement.swing_clearance_m``).
        floor_bodies : list of int, optional
            The bodies of the state's floor contacts, if already found
            (:func:`controller.checks.contacts.floor_contacts`).

        Returns
        -------
        ndarray, shape (2,)
            The horizontal shift asked of the swing foot (zero when no leg swings), m.
        """
        if floor_bodies is None:
            floor_bodies = floor_contacts(self.model, data)[1].tolist()
        left, right = self.touching(floor_bodies)
        if left == right:
            return np.zeros(2)
        swing = 0 if right else 1
        stance = 1 - swing
        self._mj_subtreeVel(self.model, data)
        xpos = data.xpos
        # the reference at the frame nearest this one where it has the stance foot down:
        # a foot the character put down early or lifted late is compared with the
        # reference as it lands it or last stood on it, its centre of mass then, not now
        # (the character out of phase with the reference, not off balance: on 09_06,
        # whose flights the character cuts short, the reference 0.15 s before it lands is
        # still in the air, its centre of mass 0.66 m behind the foot, and after it lifts
        # the foot it is in the air ahead of it: the late lifts' half carries the run, the
        # early landings' halves its search, and without it the walk sequences joined
        # whole fall in 16 of their 42 runs against 8)
        gain = self.gain if gain is None else gain
        down = self.down_frame[frame, stance]
        settings = self.settings
        shift = capture_shift(
            data.subtree_com[1], data.subtree_linvel[1], xpos[self.ankle[stance]],
            self.ref_com[down], self.ref_com_vel[down],
            self.ref_ankle[down, stance], self.time_constant_s,
            gain, settings.max_shift_m)
        if gain:
            capture_error_m(data)[:] = math.hypot(shift[0], shift[1]) / gain
        dofs, qadr = self.hips[swing]
        self._mj_jac(self.model, data, self._jacp, None, xpos[self.ankle[swing]],
                     int(self.ankle[swing]))
        if settings.swing_height:
            # and the ankle at least at the reference's height above the floor (plus a
            # clearance while the reference swings it: a toe that scrapes trips; not
            # lower: a swing foot that lands early lands on its toes, behind the body)
            lift = self.ref_ankle[frame, swing, 2] - xpos[self.ankle[swing], 2]
            if not self.ref_down[frame, swing]:
                lift += settings.swing_clearance_m if clearance_m is None else clearance_m
            move = np.array((shift[0], shift[1], max(0.0, lift)))
        else:
            move = shift
        move_point(self._jacp, dofs, move, settings.ik_damping_m, self.max_turn_rad, q_ref,
                   qadr)
        return shift


def _descends(model, body: int, ancestor: int) -> bool:
    while body > 0:
        if body == ancestor:
            return True
        body = int(model.body_parentid[body])
    return False


def capture_error_m(data) -> np.ndarray:
    """The state's slot (a view, shape (1,) or (0,)) for the length of the difference
    between the character's and the reference's capture offsets at the last
    single-support step, m (at most ``placement.max_shift_m`` over that step's gain):
    the last entry of ``userdata``, so that a saved state and a rollout from it carry
    it."""
    return data.userdata[-1:]
