"""MJCF generator: a MuJoCo humanoid from an ASF skeleton.

The model (``build_mjcf``):

- **Frames.** MuJoCo's world is z up: every ASF vector is turned by the fixed rotation
  of :mod:`humanoid_xml.frames` (``(x, y, z)_asf -> (x, -z, y)_mj``, +90 degrees about
  x). Every body frame is aligned with the world in the rest pose (no body ``quat``).
- **Bodies.** One body per ASF bone, named after it, placed at the distal end of its
  parent bone (``pos`` = the parent's rest offset, direction x length, in metres), so the
  body's origin is the joint at the bone's proximal end. A site ``<bone>_end`` marks the
  distal end of every bone (``root_end`` is the root position itself).
- **Joints.** The root has a free joint ``root``. Each of the 21 posture joints has one
  hinge per DOF its ASF declares, named ``<bone>_<dof>`` (``lfemur_rx``), listed in the
  order rz, ry, rx with axes ``C e_z, C e_y, C e_x`` (``C`` the bone's ASF axis frame):
  MuJoCo composes a body's joints in listed order, which gives Acclaim's
  ``C Rz Ry Rx C^T`` (x applied first). ``range`` is the human range of motion, in
  degrees (:func:`upm.motion.human_boxes.human_dof_boxes`: a hinge joint's anatomical
  range exactly; for a joint of two or three DOFs, the envelope of its coupled human
  range, so that the body can reach every posture a human reaches — not the ASF's
  nominal boxes, which 61-85 % of real frames break). The other
  bones (hip joints, upperneck, wrists, fingers, thumbs) have no joint: they weld to their
  parent, keeping their offsets, exactly as in the project's kinematics.
- **Geoms and masses** (:mod:`humanoid_xml.body`): capsules sized from the bones, masses
  from de Leva's segment fractions of ``BMI 23 x stature^2``, and a heel on each foot
  (CMU has no heel bone): a capsule across the foot 22.5 % of the foot length (0.152 x
  stature) behind the ankle, its underside at the sole's level, so that the rest pose
  stands on heel and forefoot.
- **Collision.** Every geom collides with the floor and with every other body, except
  inside a weld group, between a weld group and its parent's (MuJoCo's parent filter),
  and the pairs of :data:`humanoid_xml.exclusions.EXCLUDED_PAIRS`.
- **Joint limits that hold.** ``range`` is enforced by a stiff limit constraint
  (``solreflimit`` :data:`LIMIT_SOLREF`: time constant 5 ms, critically damped;
  ``solimplimit`` :data:`LIMIT_SOLIMP`: impedance 0.95 rising to 0.99 within 0.001 rad),
  instead of MuJoCo's default (20 ms, 0.9-0.95) through which a servo pushing at its
  strength went 4-10 degrees past the limit; now a few hundredths of a degree at rest
  and under one degree at the moment of impact (measured in the tests).
- **Actuators.** A position actuator per hinge, named like its joint, listed in posture
  order (``upm.motion.skeleton.POSTURE_DOF_NAMES``, declared DOFs only), so a posture is a
  control vector (radians). ``ctrlrange`` is inherited from the joint range (radians).
  Gains (:mod:`humanoid_xml.servos`) scale with the mass each joint moves *and* the
  load it bears: ``kp = max(I w^2, min(m g l, tau_max) / theta_sag)``, ``kv = 2 sqrt(kp
  I)`` (critical damping on the inertia moved), with ``I`` the joint-space inertia of the
  hinge at rest (the diagonal of the mass matrix: everything the joint moves, about its
  axis, plus the joint's 0.01 kg m^2 armature), ``w = 2 pi x 6 Hz``, ``m`` the mass the
  joint carries (for hip, knee, ankle and toes: the whole body but the joint's distal
  part, as in stance; elsewhere the joint's subtree), ``l`` the distance from that
  mass's centre to the hinge axis, ``tau_max`` the joint's strength and ``theta_sag = 2``
  degrees the deflection at which the servo pushes with that torque. ``forcerange``
  bounds each servo by the joint's strength (:mod:`humanoid_xml.strength`: published
  peak isometric torques, per direction, scaled by the model's mass and stature), so
  tracking cannot use superhuman torques. Damped position actuators need the
  ``implicitfast`` integrator.
- **Floor.** A plane at z = 0; the root's rest height puts the lowest geom on it.
"""

from __future__ import annotations

import numpy as np

from humanoid_xml.body import Capsule, body_mass_kg, capsules, stature_m, with_masses
from humanoid_xml.exclusions import EXCLUDED_PAIRS
from humanoid_xml.frames import vectors_to_mj
from humanoid_xml.servos import servo_gains
from humanoid_xml.strength import torque_limits_nm
from humanoid_xml.validate import check_skeleton
from upm.core.errors import DataFileError
from upm.motion.human_boxes import human_dof_boxes
from upm.motion.skeleton import JOINTS, POSTURE_DOF_NAMES, Skeleton, joint_dof_index

#: Bumped by hand when the model changes in a way the source digest would not show.
GENERATOR_VERSION = "5"
#: Joint limits: MuJoCo's constraint reference (time constant s, damping ratio) and
#: impedance (d0, d_width, width rad, midpoint, power), see the module docstring.
LIMIT_SOLREF = (0.005, 1.0)
#: Numbers of user data carried with the MuJoCo state (``mjData.userdata``): controllers'
#: memory from one step to the next that must travel with a saved state (the balance
#: controller's QP warm start, :mod:`controller.balance.wbc`, and in the last entry the foot
#: placement's capture-offset difference, :func:`controller.balance.placement.capture_error_m`).
#: It takes no part in the physics.
USERDATA_SIZE = 100
LIMIT_SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)
#: Simulation time step, seconds.
TIMESTEP_S = 0.002
_HINGE_ORDER = ("rz", "ry", "rx")
_AXIS_COLUMN = {"rx": 0, "ry": 1, "rz": 2}


def _num(x: float) -> str:
    """A number as MJCF text: 6 significant digits, no ``-0``."""
    x = round(float(x), 9)
    text = f"{x:.6g}"
    return "0" if text in ("-0", "0") else text


def _vec(v) -> str:
    return " ".join(_num(x) for x in v)


def hinge_names(skeleton: Skeleton) -> list[str]:
    """Names of the model's hinges in actuator (posture) order, e.g. ``lclavicle_ry``."""
    return [name.replace(".", "_") for name, declared
            in zip(POSTURE_DOF_NAMES, skeleton.declared, strict=True) if declared]


def _body_xml(skeleton: Skeleton, geoms: list[Capsule], root_height_m: float) -> list[str]:
    offsets = vectors_to_mj(skeleton.offsets_m)
    children: dict[int, list[int]] = {b: [] for b in range(skeleton.n_bones)}
    for b, parent in enumerate(skeleton.parents):
        if parent >= 0:
            children[int(parent)].append(b)
    geoms_of: dict[str, list[Capsule]] = {}
    for g in geoms:
        geoms_of.setdefault(g.bone, []).append(g)
    joints = set(JOINTS)
    lines: list[str] = []
    human_boxes = human_dof_boxes(skeleton)

    def emit(b: int, depth: int) -> None:
        pad = "  " * depth
        bone = skeleton.bone_names[b]
        if b == 0:
            lines.append(f'{pad}<body name="root" pos="0 0 {_num(root_height_m)}" '
                         'childclass="body">')
            lines.append(f'{pad}  <freejoint name="root"/>')
            lines.append(f'{pad}  <camera name="track" mode="trackcom" pos="0 -4 0.4" '
                         'xyaxes="1 0 0 0 0.1 1"/>')
        else:
            parent_offset = offsets[skeleton.parents[b]]
            lines.append(f'{pad}<body name="{bone}" pos="{_vec(parent_offset)}">')
        if bone in joints:
            axes = vectors_to_mj(skeleton.axis_matrices[b].T)  # row k = C e_k in MuJoCo axes
            for dof in _HINGE_ORDER:
                if dof in skeleton.dofs[b]:
                    lo, hi = human_boxes[joint_dof_index(bone, dof)]
                    lines.append(f'{pad}  <joint name="{bone}_{dof}" '
                                 f'axis="{_vec(axes[_AXIS_COLUMN[dof]])}" '
                                 f'range="{_num(lo)} {_num(hi)}"/>')
        for g in geoms_of.get(bone, []):
            lines.append(f'{pad}  <geom name="{g.name}" fromto="{_vec(g.p0_m)} {_vec(g.p1_m)}" '
                         f'size="{_num(g.radius_m)}" mass="{_num(g.mass_kg)}"/>')
        lines.append(f'{pad}  <site name="{bone}_end" pos="{_vec(offsets[b])}"/>')
        for child in children[b]:
            emit(child, depth + 1)
        lines.append(f"{pad}</body>")

    emit(0, 2)
    return lines


def model_name(skeleton: Skeleton) -> str:
    """The model's name: ``humanoid_<ASF file stem>`` (CMU ASFs are all called "VICON"),
    or ``humanoid_<skeleton name>`` for a skeleton not read from an ASF."""
    source = skeleton.source.replace("\\", "/").rsplit("/", 1)[-1]
    base = source[:-4] if source.lower().endswith(".asf") else skeleton.name
    return "humanoid_" + ("".join(c if c.isalnum() or c in "-_" else "_" for c in base)
                          or "model")


def _document(skeleton: Skeleton, geoms: list[Capsule], root_height_m: float,
              actuators: list[str], summary: str, stature: float) -> str:
    name = model_name(skeleton)
    lines = [
        f'<mujoco model="{name}">',
        f"  <!-- Generated by humanoid_xml (generator {GENERATOR_VERSION}) from the skeleton "
        f"{skeleton.source.replace(chr(92), '/').rsplit('/', 1)[-1]!r}: do not edit by hand.",
        f"       {summary} -->",
        '  <compiler angle="degree" autolimits="true"/>',
        f'  <option timestep="{_num(TIMESTEP_S)}" integrator="implicitfast"/>',
        f'  <size nuserdata="{USERDATA_SIZE}"/>',
        "  <custom>",
        "    <!-- the stature the masses and strengths were scaled by (legs straightened) -->",
        f'    <numeric name="stature_m" data="{_num(stature)}"/>',
        "  </custom>",
        "  <visual>",
        '    <global offwidth="1280" offheight="720"/>',
        "  </visual>",
        "  <default>",
        '    <default class="body">',
        '      <joint type="hinge" limited="true" armature="0.01" damping="0" '
        f'solreflimit="{_vec(LIMIT_SOLREF)}" solimplimit="{_vec(LIMIT_SOLIMP)}"/>',
        '      <geom type="capsule" condim="3" friction="1 0.005 0.0001" '
        'rgba="0.8 0.6 0.4 1"/>',
        '      <site size="0.01" group="4" rgba="1 0 0 1"/>',
        "    </default>",
        "  </default>",
        "  <asset>",
        '    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.55 0.7 0.85" '
        'rgb2="0.15 0.2 0.25" width="256" height="256"/>',
        '    <texture name="grid" type="2d" builtin="checker" width="512" height="512" '
        'rgb1="0.25 0.3 0.35" rgb2="0.35 0.4 0.45"/>',
        '    <material name="grid" texture="grid" texrepeat="2 2" texuniform="true" '
        'reflectance="0.1"/>',
        "  </asset>",
        "  <worldbody>",
        '    <light name="sun" pos="0 0 5" dir="0 0 -1" directional="true"/>',
        '    <geom name="floor" type="plane" size="0 0 0.05" material="grid" condim="3" '
        'friction="1 0.005 0.0001"/>',
        *_body_xml(skeleton, geoms, root_height_m),
        "  </worldbody>",
        "  <contact>",
        *[f'    <exclude name="{a}-{b}" body1="{a}" body2="{b}"/>'
          for a, b, _ in EXCLUDED_PAIRS],
        "  </contact>",
        *actuators,
        "</mujoco>",
    ]
    return "\n".join(lines) + "\n"


def _actuators(skeleton: Skeleton, gains: dict, strength: dict) -> list[str]:
    lines = ["  <actuator>"]
    for joint in hinge_names(skeleton):
        g = gains[joint]
        lo, hi = strength[joint]
        lines.append(f'    <position name="{joint}" joint="{joint}" kp="{_num(g.kp)}" '
                     f'kv="{_num(g.kv)}" inheritrange="1" '
                     f'forcerange="{_num(-lo)} {_num(hi)}"/>')
    lines.append("  </actuator>")
    return lines


def build_mjcf(skeleton: Skeleton) -> str:
    """The MJCF text of the humanoid for an ASF skeleton (see the module docstring).

    Parameters
    ----------
    skeleton : Skeleton
        Any skeleton with the CMU bone set (``upm.read_asf``).

    Returns
    -------
    str
        A complete, self-contained MJCF document.

    Raises
    ------
    DataFileError
        Naming the skeleton's file, if the humanoid cannot be built from it
        (:func:`humanoid_xml.validate.check_skeleton`) or MuJoCo refuses the result.
    """
    check_skeleton(skeleton)
    geoms = capsules(skeleton)
    stature = stature_m(skeleton, geoms)
    mass = body_mass_kg(stature)
    geoms = with_masses(geoms, mass)
    origin_z = _rest_origin_z(skeleton)
    lowest = min(min(g.p0_m[2], g.p1_m[2]) - g.radius_m + origin_z[skeleton.bone_index(g.bone)]
                 for g in geoms)
    root_height = -lowest
    summary = (f"stature {stature:.3f} m, mass {mass:.1f} kg, "
               f"{int(skeleton.declared.sum())} hinges")
    import mujoco

    try:
        draft = mujoco.MjModel.from_xml_string(_document(skeleton, geoms, root_height, [],
                                                         summary, stature))
    except (ValueError, mujoco.FatalError) as exc:
        message = " ".join(str(exc).split())
        raise DataFileError(skeleton.source, f"MuJoCo refuses the humanoid built from it: "
                                             f"{message}") from None
    strength = torque_limits_nm(hinge_names(skeleton), mass, stature)
    gains = servo_gains(draft, strength)
    return _document(skeleton, geoms, root_height, _actuators(skeleton, gains, strength),
                     summary, stature)


def _rest_origin_z(skeleton: Skeleton) -> np.ndarray:
    """Height of each body's origin (its bone's proximal end) above the root in the rest
    pose (MuJoCo z), shape (B,) metres."""
    from upm.motion.kinematics import rest_positions

    ends_z = vectors_to_mj(rest_positions(skeleton))[:, 2]
    parents = skeleton.parents
    return np.where(parents >= 0, ends_z[np.maximum(parents, 0)], 0.0)
