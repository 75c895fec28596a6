"""The humanoid's kinematic checks for the ``feasible`` transition method.

:mod:`upm.transitions.feasible` must not import MuJoCo; it calls a duck-typed checker.
This module is that checker, :class:`HumanoidChecker` (self-collision of postures on a
skeleton's humanoid, the study's definition: a contact between two bodies the model does
not exclude, deeper than the soft tissue of that pair allows; and, given the root, a geom
deeper below the floor than its class allows: :mod:`controller.checks.tissue`).
Importing it (the ``controller``
package does) registers the checker with
:func:`upm.transitions.feasible_keys.register_kinematic_checker`.
"""

from __future__ import annotations

import numpy as np

from controller.checks.tissue import allowance_table
from upm.transitions.feasible_keys import register_kinematic_checker

#: Root height while checking postures, metres: far above the floor, so that only
#: self-contacts can occur (self-collision does not depend on the root).
_CHECK_HEIGHT_M = 10.0


class HumanoidChecker:
    """Self-collision of postures on the humanoid of one skeleton.

    Parameters
    ----------
    skeleton : upm.motion.skeleton.Skeleton
        The humanoid is built from it (:func:`humanoid_xml.build_mjcf`), so bone lengths
        match the motion's.
    """

    def __init__(self, skeleton):
        import mujoco

        from controller.qpos import joint_layout
        from humanoid_xml import build_mjcf

        self._root_axis_order = skeleton.root_axis_order
        self.model = mujoco.MjModel.from_xml_string(build_mjcf(skeleton))
        self.data = mujoco.MjData(self.model)
        layout = joint_layout(self.model)
        self._posture_index, self._qpos_address = layout.posture_index, layout.qpos_address
        free = layout.free_qpos
        self._free = free
        self._last_root: tuple = (None, None)
        self._base = np.asarray(self.model.qpos0, dtype=float).copy()
        self._base[free:free + 3] = (0.0, 0.0, _CHECK_HEIGHT_M)
        self._base[free + 3:free + 7] = (1.0, 0.0, 0.0, 0.0)
        names = [mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_BODY, b)
                 for b in range(self.model.nbody)]
        self._pair_names = np.array([[f"{a}-{b}" for b in names] for a in names], dtype=object)
        self._allowed_m = allowance_table(names)
        self._geom_body = np.asarray(self.model.geom_bodyid)

    def self_collision_pairs(self, postures_deg) -> list[frozenset]:
        """The body pairs in self-collision in each posture.

        Parameters
        ----------
        postures_deg : array_like, shape (N, 63)

        Returns
        -------
        list of frozenset of str
            Per posture, ``"body1-body2"`` names (sorted by body id), empty if none.
        """
        return self.frame_checks(postures_deg)[0]

    def frame_checks(self, postures_deg, root=None, names: bool = True):
        """Self-collision and, with the root, floor penetration of each posture.

        Parameters
        ----------
        postures_deg : array_like, shape (N, 63)
        root : array_like, shape (N, 6), optional
            tx, ty, tz metres, rx, ry, rz degrees (the skeleton's root axis order).
            Without it the body is held far above the floor.
        names : bool
            Name the body pairs (else only say whether there is one: faster).

        Returns
        -------
        pairs : list of frozenset of str, or ndarray of bool, shape (N,)
            Per posture, the body pairs in self-collision (as :meth:`self_collision_pairs`);
            with ``names=False``, whether there is one.
        floor : ndarray of bool, shape (N,)
            A geom deeper below the floor than its class allows (the study's rule).
        """
        import mujoco

        model, data = self.model, self.data
        postures = np.atleast_2d(np.asarray(postures_deg, dtype=float))
        qpos = np.tile(self._base, (postures.shape[0], 1))
        qpos[:, self._qpos_address] = np.deg2rad(postures[:, self._posture_index])
        if root is not None:
            qpos[:, self._free:self._free + 7] = self._root_qpos(root)
        pairs = [] if names else np.zeros(postures.shape[0], dtype=bool)
        floor = np.zeros(postures.shape[0], dtype=bool)
        for t, q in enumerate(qpos):
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_collision(model, data)
            n = data.ncon
            if not n:
                if names:
                    pairs.append(frozenset())
                continue
            depth = -data.contact.dist[:n]
            bodies = np.sort(self._geom_body[data.contact.geom[:n]], axis=1)
            on_floor = bodies[:, 0] == 0
            beyond = depth > self._allowed_m[bodies[:, 0], bodies[:, 1]]
            floor[t] = bool(np.any(beyond & on_floor))
            deep = ~on_floor & beyond
            if names:
                pairs.append(frozenset(self._pair_names[b1, b2] for b1, b2 in bodies[deep]))
            else:
                pairs[t] = bool(deep.any())
        return pairs, floor

    def _root_qpos(self, root) -> np.ndarray:
        """The free joint's ``qpos`` (T, 7) of a root, as :func:`controller.qpos.root_to_qpos`
        but with the project's vectorised quaternion (scipy's Rotation costs about half
        of a 20-frame window check). The same root is checked under several candidate
        windows: the last one is kept."""
        if root is not self._last_root[0]:
            from humanoid_xml.frames import ASF_TO_MJ, rotations_to_mj
            from upm.ops.rotations import euler_to_matrix, matrix_to_quaternion

            values = np.atleast_2d(np.asarray(root, dtype=float))
            out = np.empty((values.shape[0], 7))
            out[:, :3] = values[:, :3] @ ASF_TO_MJ.T
            out[:, 3:] = matrix_to_quaternion(rotations_to_mj(
                euler_to_matrix(values[:, 3:6], self._root_axis_order)))
            self._last_root = (root, out)
        return self._last_root[1]


register_kinematic_checker(HumanoidChecker)
