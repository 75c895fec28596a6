"""The humanoid's kinematic checks for the ``feasible`` transition method.

:mod:`upm.transitions.feasible` must not import MuJoCo; it calls a duck-typed checker.
This module is that checker, :class:`HumanoidChecker` (self-collision of postures on a
skeleton's humanoid, the study's definition: a contact between two bodies the model does
not exclude, deeper than :data:`controller.contacts.SELF_COLLISION_DEPTH_M`), and
:func:`feasible_key_source`, the method's key-source builder that the registry names
lazily.
"""

from __future__ import annotations

import numpy as np

from controller.contacts import SELF_COLLISION_DEPTH_M

#: Root height while checking postures, metres: far above the floor, so that only
#: self-contacts can occur (self-collision does not depend on the root).
_CHECK_HEIGHT_M = 10.0


class HumanoidChecker:
    """Self-collision of postures on the humanoid of one skeleton.

    Parameters
    ----------
    skeleton : upm.skeleton.Skeleton
        The humanoid is built from it (:func:`humanoid_xml.build_mjcf`), so bone lengths
        match the motion's.
    """

    def __init__(self, skeleton):
        import mujoco

        from controller.qpos import joint_layout
        from humanoid_xml import build_mjcf

        self.model = mujoco.MjModel.from_xml_string(build_mjcf(skeleton))
        self.data = mujoco.MjData(self.model)
        layout = joint_layout(self.model)
        self._posture_index, self._qpos_address = layout.posture_index, layout.qpos_address
        free = layout.free_qpos
        self._base = np.asarray(self.model.qpos0, dtype=float).copy()
        self._base[free:free + 3] = (0.0, 0.0, _CHECK_HEIGHT_M)
        self._base[free + 3:free + 7] = (1.0, 0.0, 0.0, 0.0)
        names = [mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_BODY, b)
                 for b in range(self.model.nbody)]
        self._pair_names = np.array([[f"{a}-{b}" for b in names] for a in names], dtype=object)
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
        import mujoco

        model, data = self.model, self.data
        postures = np.atleast_2d(np.asarray(postures_deg, dtype=float))
        qpos = np.tile(self._base, (postures.shape[0], 1))
        qpos[:, self._qpos_address] = np.deg2rad(postures[:, self._posture_index])
        out = []
        for q in qpos:
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_collision(model, data)
            n = data.ncon
            if not n:
                out.append(frozenset())
                continue
            deep = -data.contact.dist[:n] > SELF_COLLISION_DEPTH_M
            bodies = np.sort(self._geom_body[data.contact.geom[:n][deep]], axis=1)
            out.append(frozenset(self._pair_names[b1, b2] for b1, b2 in bodies if b1 != 0))
        return out

def feasible_key_source(context):
    """The key source of ``feasible``: the UPM of ``context`` with the humanoid's checks.

    Parameters
    ----------
    context : upm.transitions.registry.KeySourceContext

    Returns
    -------
    upm.transitions.feasible.FeasibleKeys
    """
    from upm.transitions.feasible import FeasibleKeys

    return FeasibleKeys(context.posture_map("upm"), checker_for=HumanoidChecker)
