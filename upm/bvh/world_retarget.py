"""Any BVH figure onto an ASF skeleton by carrying each mapped bone's world direction.

For figures whose hierarchy, rest pose and bone splits differ from the ASF's (DAZ-style,
Mixamo, the 19-joint figure), a :class:`~upm.bvh.joint_maps.JointMap` names the BVH
segment of each posture bone. Per frame, top-down over the ASF tree:

1. The **root** takes the world rotation of the map's root joint (every figure here, like
   the CMU ASFs, stands y up facing +z at rest), and its position puts the ASF's hip
   centre where the BVH's (its two femur start joints) is, scaled by the ratio of the
   ASF's leg length (femur + tibia) to the BVH's rest leg length, so the file's unit
   does not matter and the feet stay on the floor.
2. Each mapped bone gets a **desired world direction** ``d`` (where its BVH segment
   points) and a **desired twist**: the BVH segment's start joint's world rotation
   times the smallest rotation taking the ASF's rest direction onto the segment's rest
   direction (for a one-joint entry, that joint's rotation unchanged).
3. Its declared-DOF Euler angles (the AMC's ``Rz Ry Rx`` in the bone's axis frame, with
   the parent's already solved rotation) minimise, by damped Gauss-Newton from the
   closed-form 3-DOF solution projected on the declared DOFs:
   ``|R u - d|^2`` (the direction, weight 1) + ``0.1^2 |R v - R* v|^2`` for two vectors
   ``v`` across the bone (the twist, weak) + for each child that is a one-DOF hinge
   (knee, elbow, toes), ``3^2 ((R a) . d_child - a . u_child)^2``: the hinge axis ``a``
   must keep the child's direction reachable. So the femur's and humerus's twist comes
   from the knee's and elbow's bend plane whenever the limb is bent, and from the BVH
   segment's own rotation when it is straight; with fewer than 3 DOFs the fit is the
   least-squares compromise of the same terms. Without the hinge term the shins and
   forearms miss their BVH directions by up to 27 degrees (95th percentile 15, Mixamo);
   with it by at most 0.2 (the weights were chosen on that residual, not on any AMC).

Bones without a counterpart keep their rest angles (0). Bone lengths are the ASF's.
"""

from __future__ import annotations

import numpy as np

from upm.bvh.joint_maps import END_SITE, JointMap, check_map_against
from upm.bvh.kinematics import rest_positions, world_transforms
from upm.core.errors import DataFileError
from upm.motion.skeleton import JOINTS
from upm.ops.rotations import continuous_euler_deg, euler_to_matrix, matrix_to_euler_deg

#: Weight of the twist term against the direction term (see the module docstring).
TWIST_WEIGHT = 0.1
#: Weight of a one-DOF child's reachability term.
HINGE_WEIGHT = 3.0
#: A first frame is an added rest pose when every mapped joint's rotation channels are
#: within this of 0 ...
REST_FRAME_MAX_DEG = 5.0
#: ... and some mapped segment turns more than this, and more than twice any later
#: frame-to-frame turn, into frame 1.
REST_FRAME_MIN_JUMP_DEG = 20.0
_GN_ITERATIONS = 12


def added_rest_frame(bvh, joint_map: JointMap) -> bool:
    """Whether frame 0 is an added rest/T-pose frame (the DAZ-style conversions add one).

    Rule: every rotation channel of the mapped non-root joints is within
    :data:`REST_FRAME_MAX_DEG` of 0 in frame 0, and the turn of some mapped segment from
    frame 0 to 1 exceeds :data:`REST_FRAME_MIN_JUMP_DEG` and twice the largest later
    frame-to-frame turn. Measured: DAZ-style 05_11, 141_01, 141_04 jump 124, 102, 101 deg
    (later steps at most 24, 28, 26); Mixamo 9.5 and the 19-joint file 0.9 (their frame
    0 is not a rest pose: up to 68 and 87 deg).
    """
    sk = bvh.skeleton
    if bvh.n_frames < 3:
        return False
    index = {n: j for j, n in enumerate(sk.names)}
    rot = [sk.channel_start[index[n]] + k for n in joint_map.bvh_joints()[1:]
           for k, c in enumerate(sk.channels[index[n]]) if c.endswith("rotation")]
    if rot and np.abs(bvh.values[0, rot]).max() > REST_FRAME_MAX_DEG:
        return False
    _, pos, ends = world_transforms(bvh)
    dirs = [_unit(_end_point(e, index, pos, ends) - pos[:, index[e[0]]])
            for e in joint_map.bones.values() if len(e) == 2]
    if not dirs:
        return False
    d = np.stack(dirs, axis=1)
    turn = np.degrees(np.arccos(np.clip((d[1:] * d[:-1]).sum(-1), -1.0, 1.0))).max(axis=1)
    return bool(turn[0] > REST_FRAME_MIN_JUMP_DEG and turn[0] > 2.0 * turn[1:].max())


def retarget_world(bvh, skeleton, joint_map: JointMap, fps: float | None = None,
                   drop_first: bool | None = None, name: str = ""):
    """A BVH take of any figure as a :class:`~upm.Motion` on ``skeleton``.

    Parameters
    ----------
    bvh : upm.bvh.BvhMotion
    skeleton : upm.motion.skeleton.Skeleton
    joint_map : JointMap
    fps : float, optional
        The take's rate (default the file's ``Frame Time``).
    drop_first : bool, optional
        Drop frame 0 (default: when :func:`added_rest_frame` says it was added).

    Returns
    -------
    upm.Motion
        Posture ``(T, 63)`` (undeclared DOFs 0), root ``(T, 6)``.

    Raises
    ------
    DataFileError
        If the map names joints the BVH lacks, or a mapped segment has zero length.
    """
    from upm.motion.motion import Motion

    check_map_against(joint_map, bvh)
    drop = added_rest_frame(bvh, joint_map) if drop_first is None else bool(drop_first)
    if drop and bvh.n_frames < 2:
        raise DataFileError(bvh.source, "one frame only: nothing left after dropping it")
    sk = bvh.skeleton
    index = {n: j for j, n in enumerate(sk.names)}
    world, pos, ends = (a[1 if drop else 0:] for a in world_transforms(bvh))
    rest_pos, rest_ends = rest_positions(sk)
    n = world.shape[0]

    desired = {}  # bone -> (direction (T, 3), rotation (T, 3, 3))
    for bone, entry in joint_map.bones.items():
        b = skeleton.bone_index(bone)
        u = skeleton.directions[b]
        start = index[entry[0]]
        if len(entry) == 1:
            rot = world[:, start]
            desired[bone] = (rot @ u, rot)
            continue
        rest = _end_point(entry, index, rest_pos[None], rest_ends[None])[0] - rest_pos[start]
        if np.linalg.norm(rest) == 0.0:
            raise DataFileError(bvh.source, f"joint map {joint_map.name}: {bone!r} -> "
                                            f"{entry[0]!r}..{entry[1]!r} has zero length")
        direction = _unit(_end_point(entry, index, pos, ends) - pos[:, start])
        desired[bone] = (direction, world[:, start] @ _turn_onto(u, _unit(rest)))

    rotations = np.empty((n, skeleton.n_bones, 3, 3))
    rotations[:, 0] = world[:, index[joint_map.root]]
    posture = np.zeros((n, 63))
    joint_of = {skeleton.bone_index(j): k for k, j in enumerate(JOINTS)}
    for b in range(1, skeleton.n_bones):
        parent = rotations[:, skeleton.parents[b]]
        c = skeleton.axis_matrices[b]
        bone = skeleton.bone_names[b]
        if b in joint_of and bone in desired:
            k = joint_of[b]
            declared = skeleton.declared[3 * k:3 * k + 3]
            hinges = _hinge_terms(skeleton, b, desired)
            posture[:, 3 * k:3 * k + 3] = _solve_joint(
                parent, c, skeleton.directions[b], desired[bone], declared, hinges)
            m = euler_to_matrix(posture[:, 3 * k:3 * k + 3], "XYZ")
            rotations[:, b] = parent @ c @ m @ c.T
        else:
            rotations[:, b] = parent

    root = np.empty((n, 6))
    root[:, 3:] = continuous_euler_deg(rotations[:, 0], skeleton.root_axis_order,
                                       matrix_to_euler_deg(rotations[0, 0],
                                                           skeleton.root_axis_order))
    root[:, :3] = _root_position_m(bvh, skeleton, joint_map, index, pos, rest_pos,
                                   rest_ends, rotations[:, 0])
    return Motion(skeleton=skeleton, posture_deg=posture, root=root,
                  fps=float(fps) if fps else bvh.fps, name=name)


def _end_point(entry, index, pos, ends) -> np.ndarray:
    """Where a two-name entry's segment ends, ``(T, 3)``."""
    start, end = entry
    return ends[:, index[start]] if end == END_SITE else pos[:, index[end]]


def _unit(v: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(norm > 0, norm, 1.0)


def _turn_onto(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit ``a`` onto unit ``b``, (3, 3)."""
    axis = np.cross(a, b)
    s, c = np.linalg.norm(axis), float(np.dot(a, b))
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        # half a turn about any axis across a
        other = np.eye(3)[int(np.argmin(np.abs(a)))]
        axis = _unit(np.cross(a, other))
        return 2.0 * np.outer(axis, axis) - np.eye(3)
    k = axis / s
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * kx + (1 - c) * kx @ kx


def _hinge_terms(skeleton, b, desired) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """For each one-DOF posture child of bone ``b`` (through unarticulated bones) with a
    desired direction: its axis in ``b``'s rest frame, its desired direction (T, 3), and
    the invariant ``axis . u_child``."""
    out = []
    for child in range(b + 1, skeleton.n_bones):
        p = skeleton.parents[child]
        while p != b and p > 0 and skeleton.bone_names[p] not in JOINTS:
            p = skeleton.parents[p]
        name = skeleton.bone_names[child]
        if p != b or name not in JOINTS or name not in desired or len(
                skeleton.dofs[child]) != 1:
            continue
        axis = skeleton.axis_matrices[child][:, "xyz".index(skeleton.dofs[child][0][1])]
        out.append((axis, desired[name][0], float(axis @ skeleton.directions[child])))
    return out


def _solve_joint(parent, c, u, target, declared, hinges) -> np.ndarray:
    """Declared-DOF angles of one joint, ``(T, 3)`` degrees (undeclared 0)."""
    from upm.bvh.asf_bvh import _joint_angles

    if not declared.any():
        return np.zeros((parent.shape[0], 3))
    direction, rotation = target
    local = c.T @ np.swapaxes(parent, -1, -2) @ rotation @ c
    angles = _joint_angles(local, declared)
    angles[:, ~declared] = 0.0
    free = np.flatnonzero(declared)
    v1 = _unit(np.cross(u, np.eye(3)[int(np.argmin(np.abs(u)))]))
    across = np.stack([v1, np.cross(u, v1)])  # (2, 3)
    twist_target = np.einsum("tij,kj->tki", rotation, across)

    def residual(theta):
        full = angles.copy()
        full[:, free] = theta
        r = parent @ c @ euler_to_matrix(full, "XYZ") @ c.T
        parts = [r @ u - direction,
                 TWIST_WEIGHT * (np.einsum("tij,kj->tki", r, across)
                                 - twist_target).reshape(-1, 6)]
        for axis, child_direction, invariant in hinges:
            parts.append(HINGE_WEIGHT * (np.einsum("ti,ti->t", r @ axis, child_direction)
                                         - invariant)[:, None])
        return np.concatenate(parts, axis=1)

    theta = angles[:, free]
    r0 = residual(theta)
    cost = (r0 ** 2).sum(axis=1)
    damping = np.full(theta.shape[0], 1e-3)
    step_deg = 1e-4
    for _ in range(_GN_ITERATIONS):
        jac = np.stack([(residual(theta + step_deg * np.eye(len(free))[i]) - r0) / step_deg
                        for i in range(len(free))], axis=2)  # (T, m, k)
        jtj = np.einsum("tmi,tmj->tij", jac, jac)
        jtr = np.einsum("tmi,tm->ti", jac, r0)
        lhs = jtj + damping[:, None, None] * (np.eye(len(free)) + jtj)
        delta = -np.linalg.solve(lhs, jtr[..., None])[..., 0]
        r1 = residual(theta + delta)
        new_cost = (r1 ** 2).sum(axis=1)
        better = new_cost < cost
        theta = np.where(better[:, None], theta + delta, theta)
        r0 = np.where(better[:, None], r1, r0)
        cost = np.where(better, new_cost, cost)
        damping = np.where(better, damping * 0.3, damping * 10.0)
    angles[:, free] = theta
    return np.unwrap(angles, period=360.0, axis=0)


def _root_position_m(bvh, skeleton, joint_map, index, pos, rest_pos, rest_ends,
                     root_rotation) -> np.ndarray:
    """Root translation (T, 3) m: the ASF's hip centre on the BVH's, scaled by legs."""
    from upm.motion.kinematics import rest_positions as asf_rest

    asf_ends = asf_rest(skeleton)
    hips, legs_bvh, legs_asf, centre_asf = [], [], [], []
    for side in "lr":
        femur, tibia = joint_map.bones[side + "femur"], joint_map.bones[side + "tibia"]
        f, t = skeleton.bone_index(side + "femur"), skeleton.bone_index(side + "tibia")
        hips.append(pos[:, index[femur[0]]])
        knee = rest_pos[index[tibia[0]]]
        shin = (np.linalg.norm(_end_point(tibia, index, rest_pos[None], rest_ends[None])[0]
                               - knee) if len(tibia) == 2 else
                np.linalg.norm(knee - rest_pos[index[femur[0]]])
                * skeleton.lengths_m[t] / skeleton.lengths_m[f])
        legs_bvh.append(np.linalg.norm(knee - rest_pos[index[femur[0]]]) + shin)
        legs_asf.append(skeleton.lengths_m[f] + skeleton.lengths_m[t])
        centre_asf.append(asf_ends[skeleton.parents[f]])
    if min(legs_bvh) <= 0:
        raise DataFileError(bvh.source, f"joint map {joint_map.name}: the legs have zero "
                                        "length at rest")
    scale = float(np.mean(legs_asf) / np.mean(legs_bvh))
    hip_centre = scale * 0.5 * (hips[0] + hips[1])
    return hip_centre - root_rotation @ (0.5 * (centre_asf[0] + centre_asf[1]))
