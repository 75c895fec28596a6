"""Position-servo gains: stiff enough for the load each joint bears, critically damped.

A joint's servo has two jobs. It moves what hangs from it (a swinging leg, an arm, the
head), which asks for ``kp = I w^2`` with ``I`` the inertia the joint moves; and it
holds what rests on it against gravity (in stance the ankle, knee and hip carry the body
above them; the spine and neck carry what is above them), which asks for a stiffness
that keeps the sag under that load small. The rule takes the larger of the two:

    kp = max(I w^2, min(m g l, tau_max) / theta_sag),      kv = 2 zeta sqrt(kp I)

- ``I``: the joint-space inertia of the hinge at rest (the diagonal of MuJoCo's mass
  matrix, armature included: everything the joint moves, about its axis).
- ``w = 2 pi x`` :data:`SERVO_FREQUENCY_HZ`.
- ``m``: the mass the joint carries. For a leg joint (femur, tibia, foot, toes) in
  stance, the whole body except the joint's own distal part (what lies between it and
  the floor); for every other joint, the part it holds up (its subtree).
- ``l``: the distance from that mass's centre (at rest) to the hinge axis, so that
  ``m g l`` is the largest gravity torque the load can exert about the joint (its lever
  horizontal).
- ``tau_max``: the joint's strength (the larger of its two torque limits,
  :mod:`humanoid_xml.strength`). A servo cannot hold more than that; asking it to hold
  the whole body over the toes within a few degrees would only make it chatter at its
  limit (measured: the toes saturated on 40-57 % of the steps of a walk and a run).
- ``theta_sag`` (:data:`SAG_DEG`, 2 degrees): the deflection at which the servo pushes
  with that torque. An inverted pendulum (the body over the ankle) needs a stiffness
  above ``m g l`` to stand at all (Winter et al. 1998, J. Neurophysiol. 80: 1211,
  "critical stiffness"); 2 degrees is measured, not assumed: at 5 degrees the hips,
  knees and ankles of the standing rest pose sag together by about half a degree, which
  takes the centre of mass a centimetre back onto the heels, and subjects 05 and 16
  tipped over backward after 2.1-2.2 s.
- ``zeta`` (:data:`SERVO_DAMPING_RATIO`): critical damping for the inertia the joint
  moves (the servo's swing mode; in stance the body's sway over the foot is lightly
  damped, as in quiet standing).

The gains keep the spirit of "gains scaled by the mass each joint moves": both terms are
a mass times a length (squared), the first for moving it, the second for holding it up.
How hard the servos may push is bounded by the joints' strength (the actuators'
``forcerange``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Natural frequency of each servo on the inertia it moves, Hz (``kp >= I (2 pi f)^2``).
SERVO_FREQUENCY_HZ = 6.0
#: Damping ratio on the inertia the joint moves (``kv = 2 zeta sqrt(kp I)``).
SERVO_DAMPING_RATIO = 1.0
#: Deflection at which a servo pushes with its load's gravity torque (or its strength),
#: degrees.
SAG_DEG = 2.0
#: Bones whose joints carry the body above them in stance (side-less names).
STANCE_BONES = ("femur", "tibia", "foot", "toes")
#: Gravity used for the load torque, m/s^2 (the models' own).
GRAVITY = 9.81


@dataclass(frozen=True)
class ServoGains:
    """The gains of one hinge's servo and what they come from.

    Attributes
    ----------
    joint : str
        The hinge (``"lfemur_rx"``).
    inertia_kgm2 : float
        ``I``, the inertia the joint moves (armature included).
    load_kg : float
        ``m``, the mass the joint carries.
    lever_m : float
        ``l``, from the load's centre of mass to the hinge axis.
    strength_nm : float
        ``tau_max``, the larger torque limit of the joint (inf if none was given).
    kp : float
        Stiffness, N m / rad.
    kv : float
        Damping, N m s / rad.
    rule : str
        ``"inertia"`` or ``"load"``: which term set ``kp``.
    """

    joint: str
    inertia_kgm2: float
    load_kg: float
    lever_m: float
    strength_nm: float
    kp: float
    kv: float
    rule: str

    @property
    def load_torque_nm(self) -> float:
        """``m g l``: the largest gravity torque of the load about the joint, N m."""
        return self.load_kg * GRAVITY * self.lever_m

    @property
    def held_torque_nm(self) -> float:
        """``min(m g l, tau_max)``: what the servo pushes with at ``theta_sag``, N m."""
        return min(self.load_torque_nm, self.strength_nm)


def _carries_the_body(bone: str) -> bool:
    return bone[:1] in ("l", "r") and bone[1:] in STANCE_BONES


def servo_gains(model, strength_nm=None) -> dict[str, ServoGains]:
    """The gains of every hinge of a compiled humanoid (in its rest pose, ``qpos0``).

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid (its actuators, if any, are ignored).
    strength_nm : dict of str to (float, float), optional
        Each hinge's torque limits (:func:`humanoid_xml.strength.torque_limits_nm`): the
        load term uses ``min(m g l, tau_max)``, the most the joint can hold. Without
        them, ``tau_max`` is infinite.

    Returns
    -------
    dict of str to ServoGains
        By hinge name, in the model's joint order.
    """
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    omega = 2.0 * math.pi * SERVO_FREQUENCY_HZ
    sag = math.radians(SAG_DEG)
    total = float(model.body_subtreemass[0])
    centre = data.subtree_com[0]
    unit, column = np.zeros(model.nv), np.zeros(model.nv)
    out: dict[str, ServoGains] = {}
    for j in range(model.njnt):
        if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE:
            continue
        dof = model.jnt_dofadr[j]
        unit[:] = 0.0
        unit[dof] = 1.0
        mujoco.mj_mulM(model, data, column, unit)
        inertia = float(column[dof])
        body = model.jnt_bodyid[j]
        bone = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body)
        sub_mass = float(model.body_subtreemass[body])
        sub_centre = data.subtree_com[body]
        if _carries_the_body(bone) and total > sub_mass:
            load = total - sub_mass
            load_centre = (total * centre - sub_mass * sub_centre) / load
        else:
            load, load_centre = sub_mass, sub_centre
        axis = data.xaxis[j]
        arm = load_centre - data.xanchor[j]
        lever = float(np.linalg.norm(arm - np.dot(arm, axis) * axis))
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        strength = math.inf if strength_nm is None else float(max(strength_nm[name]))
        moving = inertia * omega * omega
        holding = min(load * GRAVITY * lever, strength) / sag
        kp = float(f"{max(moving, holding):.3g}")
        kv = float(f"{2.0 * SERVO_DAMPING_RATIO * math.sqrt(kp * inertia):.3g}")
        out[name] = ServoGains(joint=name, inertia_kgm2=inertia, load_kg=load, lever_m=lever,
                               strength_nm=strength, kp=kp, kv=kv,
                               rule="load" if holding > moving else "inertia")
    return out
