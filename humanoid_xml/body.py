"""The humanoid's flesh: capsule geoms sized from the bones, and segment masses.

Every rule here is stated for a generic adult whose joint-centre height (the vertical
span of the bone ends in the rest pose, legs straightened) is
:data:`REFERENCE_JOINT_SPAN_M`; a subject's radii are scaled by the ratio of its own
joint-centre height to that. The mass of the whole body is ``BMI_KG_M2 * stature**2``,
with the stature measured on the model itself (top of the head geom to the sole, legs
straightened); it is shared among the body segments in de Leva's (1996) proportions, and
within a segment among its geoms by volume.

Geometry (radii for the reference adult, metres):

- limbs, neck, head, clavicles, hands and feet: capsules along their bone, from
  ``start`` to ``stop`` (fractions of the bone's length), some in two parts (a thicker
  proximal and a thinner distal capsule: thigh, shank, upper arm, forearm);
- trunk (lowerback, upperback, thorax): one capsule across the body (left-right) at the
  middle of the bone, whose breadth is a fixed share of the subject's shoulder breadth
  (the lateral reach of the clavicles), its depth twice its radius;
- pelvis (on the root body): a capsule from one hip-joint centre to the other;
- heel (on each foot body): CMU has no heel bone (the foot bone runs from the ankle to
  the ball of the foot), so the calcaneus is added as a capsule across the foot, behind
  the ankle, its underside at the sole's level (see :func:`heel_capsule`);
- hip joints and upperneck carry no geom of their own (the pelvis and neck cover them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from humanoid_xml.frames import vectors_to_mj
from upm.motion.kinematics import rest_positions
from upm.motion.skeleton import Skeleton

#: Body-mass index used to give a body of a stature its mass, kg/m^2.
BMI_KG_M2 = 23.0
#: Joint-centre height of the reference adult for which the radii below are given, m.
REFERENCE_JOINT_SPAN_M = 1.62

#: Capsules along a bone: bone -> ((start, stop, radius_m), ...), start/stop as fractions
#: of the bone's length from its proximal end; radius for the reference adult.
ALONG_BONE: dict[str, tuple[tuple[float, float, float], ...]] = {
    "femur": ((0.0, 0.5, 0.072), (0.5, 1.0, 0.055)),
    "tibia": ((0.0, 0.5, 0.050), (0.5, 1.0, 0.038)),
    "foot": ((0.0, 0.5, 0.036), (0.5, 1.0, 0.022)),
    "toes": ((0.0, 1.0, 0.018),),
    "humerus": ((0.0, 0.55, 0.046), (0.55, 1.0, 0.038)),
    "radius": ((0.0, 1.0, 0.035),),
    "wrist": ((0.0, 1.0, 0.030),),
    "hand": ((0.0, 1.0, 0.028),),
    "fingers": ((0.0, 1.0, 0.022),),
    "thumb": ((0.0, 1.0, 0.016),),
    "clavicle": ((0.3, 1.0, 0.050),),
    "lowerneck": ((0.0, 1.0, 0.055),),
    "head": ((0.2, 0.6, 0.090),),
}

#: Capsules across the trunk: bone -> (share of shoulder breadth, radius_m). The breadth
#: of the capsule (end to end, radii included) is share x the distance between the two
#: clavicle ends; it sits at the middle of its bone.
ACROSS_TRUNK: dict[str, tuple[float, float]] = {
    "lowerback": (0.70, 0.100),
    "upperback": (0.70, 0.100),
    "thorax": (0.70, 0.100),
}
#: Radius of the pelvis capsule (hip-joint centre to hip-joint centre), reference adult.
PELVIS_RADIUS_M = 0.078

#: Foot length as a share of stature (Drillis & Contini 1966, in Winter 2009, Fig. 4.1).
FOOT_LENGTH_H = 0.152
#: Where the heel meets the floor, behind the ankle, as a share of the foot length. The
#: calcaneus reaches 20-25 % of the foot length behind the ankle: 20 % in the foot split
#: of ``generic_adult.json`` (heel 0.20, ankle to ball 0.55, ball to toe tip 0.25); Delp
#: et al. (1990), the lower-limb model distributed with OpenSim as gait2392, puts the
#: calcaneus origin (the heel's posterior-inferior corner) 4.9 cm behind the ankle
#: (talocrural) centre of a 1.8 m man, 18 % of his 0.152 H foot length, the rounded back
#: of the heel a centimetre or two further. The middle of the range is taken. It matters:
#: the CMU rest pose puts the centre of mass 2.2-3.7 cm *behind* the ankles (a standing
#: adult carries it about 5 cm in front), so the heel's reach is the whole margin; at
#: 20 % subjects 01, 05 and 16 tip over backward after 2.3-2.8 s of standing still.
HEEL_SHARE_OF_FOOT = 0.225
#: Radius of the heel capsule (the rounded edge of the heel pad), reference adult, m.
HEEL_RADIUS_M = 0.015
#: Breadth of the heel (the capsule end to end, across the foot), reference adult, m:
#: about a quarter of the foot length.
HEEL_BREADTH_M = 0.065

#: de Leva (1996), adult male segment masses as fractions of body mass, and the CMU bones
#: that make up each segment (trunk split in its upper, middle and lower parts).
SEGMENT_MASS_FRACTIONS: dict[str, tuple[float, tuple[str, ...]]] = {
    "head_neck": (0.0694, ("lowerneck", "upperneck", "head")),
    "upper_trunk": (0.1596, ("thorax", "lclavicle", "rclavicle")),
    "middle_trunk": (0.1633, ("upperback", "lowerback")),
    "lower_trunk": (0.1117, ("root", "lhipjoint", "rhipjoint")),
    **{f"{s}_upper_arm": (0.0271, (f"{s}humerus",)) for s in "lr"},
    **{f"{s}_forearm": (0.0162, (f"{s}radius", f"{s}wrist")) for s in "lr"},
    **{f"{s}_hand": (0.0061, (f"{s}hand", f"{s}fingers", f"{s}thumb")) for s in "lr"},
    **{f"{s}_thigh": (0.1416, (f"{s}femur",)) for s in "lr"},
    **{f"{s}_shank": (0.0433, (f"{s}tibia",)) for s in "lr"},
    **{f"{s}_foot": (0.0137, (f"{s}foot", f"{s}toes")) for s in "lr"},
}


@dataclass(frozen=True)
class Capsule:
    """One capsule geom.

    Attributes
    ----------
    name : str
    bone : str
        The body it belongs to.
    p0_m, p1_m : ndarray, shape (3,)
        End points of its axis in the body frame (MuJoCo axes; at rest every body frame
        is aligned with the world), metres.
    radius_m : float
    mass_kg : float
    """

    name: str
    bone: str
    p0_m: np.ndarray
    p1_m: np.ndarray
    radius_m: float
    mass_kg: float = 0.0

    @property
    def volume_m3(self) -> float:
        length = float(np.linalg.norm(self.p1_m - self.p0_m))
        r = self.radius_m
        return math.pi * r * r * length + 4.0 / 3.0 * math.pi * r ** 3


def _side_less(bone: str) -> str:
    return bone[1:] if bone[:1] in ("l", "r") and bone[1:] in ALONG_BONE else bone


def joint_span_m(skeleton: Skeleton) -> float:
    """Joint-centre height: vertical span of the rest-pose bone ends, legs straightened.

    CMU's rest pose spreads the legs 20 degrees apart; here femurs and tibias point
    straight down, so the figure does not depend on that convention.
    """
    return float(np.ptp(_straight_leg_rest_m(skeleton)[:, 1]))


def _straight_leg_rest_m(skeleton: Skeleton) -> np.ndarray:
    """Rest positions (ASF frame, (B, 3) m) with femurs and tibias pointing down."""
    directions = skeleton.directions.copy()
    for b, name in enumerate(skeleton.bone_names):
        if name[1:] in ("femur", "tibia"):
            directions[b] = (0.0, -1.0, 0.0)
    return rest_positions(replace(skeleton, directions=directions))


def radius_scale(skeleton: Skeleton) -> float:
    """Factor applied to the reference radii for this skeleton."""
    return joint_span_m(skeleton) / REFERENCE_JOINT_SPAN_M


def capsules(skeleton: Skeleton) -> list[Capsule]:
    """The capsule geoms of every body, massless (see :func:`with_masses`).

    Returns
    -------
    list of Capsule
        In ``skeleton.bone_names`` order, then the heels (:func:`heel_capsule`).
    """
    scale = radius_scale(skeleton)
    offsets = vectors_to_mj(skeleton.offsets_m)
    index = skeleton.bone_index
    shoulder_breadth = float(np.linalg.norm(
        offsets[index("lclavicle")] - offsets[index("rclavicle")]))
    out: list[Capsule] = []
    for b, bone in enumerate(skeleton.bone_names):
        if bone == "root":
            p0 = offsets[index("lhipjoint")]
            p1 = offsets[index("rhipjoint")]
            out.append(Capsule("pelvis", bone, p0, p1, PELVIS_RADIUS_M * scale))
        elif bone in ACROSS_TRUNK:
            share, radius = ACROSS_TRUNK[bone]
            radius *= scale
            half = max(0.5 * share * shoulder_breadth - radius, 0.0)
            centre = 0.5 * offsets[b]
            lateral = np.array([half, 0.0, 0.0])
            out.append(Capsule(bone, bone, centre - lateral, centre + lateral, radius))
        else:
            rule = ALONG_BONE.get(_side_less(bone))
            if rule is None or skeleton.lengths_m[b] == 0:
                continue
            for k, (start, stop, radius) in enumerate(rule):
                name = bone if len(rule) == 1 else f"{bone}_{k + 1}"
                out.append(Capsule(name, bone, start * offsets[b], stop * offsets[b],
                                   radius * scale))
    foot_length = FOOT_LENGTH_H * stature_m(skeleton, out)
    for side in "lr":
        heel = heel_capsule(skeleton, out, f"{side}foot", foot_length, scale)
        if heel is not None:
            out.append(heel)
    return out


def heel_capsule(skeleton: Skeleton, geoms: list[Capsule], foot: str, foot_length_m: float,
                 scale: float) -> Capsule | None:
    """The heel of a foot: a capsule across the foot behind the ankle.

    Placed in the rest pose (every body frame aligned with the world): its axis is
    horizontal, across the foot, :data:`HEEL_SHARE_OF_FOOT` of the foot length behind the
    ankle (opposite the foot bone's horizontal direction), and its underside at the level
    of the lowest point of the foot's and toes' other capsules (the sole), so that the
    rest pose stands on heel and forefoot alike. The heel meets the floor along the
    capsule's underside; its rounded back reaches one radius further.

    Parameters
    ----------
    skeleton : Skeleton
    geoms : list of Capsule
        The along-bone capsules, those of ``foot`` and of its child bones among them.
    foot : str
        The foot bone (``"lfoot"``).
    foot_length_m : float
        The foot length (:data:`FOOT_LENGTH_H` x stature).
    scale : float
        :func:`radius_scale` of the skeleton.

    Returns
    -------
    Capsule or None
        Named ``<foot>_heel``, on the foot body; None if the skeleton has no such bone or
        its foot bone has no horizontal extent.
    """
    if foot not in skeleton.bone_names:
        return None
    b = skeleton.bone_index(foot)
    offsets = vectors_to_mj(skeleton.offsets_m)
    forward = offsets[b].copy()
    forward[2] = 0.0
    reach = float(np.linalg.norm(forward))
    if reach < 1e-9:
        return None
    forward /= reach
    lateral = np.array([-forward[1], forward[0], 0.0])
    # The sole: the lowest point of the foot's capsules and its children's (the toes sit
    # at the foot bone's end in the foot's frame).
    children = {skeleton.bone_names[c] for c in np.flatnonzero(skeleton.parents == b)}
    bottoms = [min(g.p0_m[2], g.p1_m[2]) - g.radius_m for g in geoms if g.bone == foot]
    bottoms += [offsets[b][2] + min(g.p0_m[2], g.p1_m[2]) - g.radius_m
                for g in geoms if g.bone in children]
    if not bottoms:
        return None
    radius = HEEL_RADIUS_M * scale
    half = max(0.5 * HEEL_BREADTH_M * scale - radius, 0.0)
    centre = -HEEL_SHARE_OF_FOOT * foot_length_m * forward
    centre[2] = min(bottoms) + radius
    return Capsule(f"{foot}_heel", foot, centre - half * lateral, centre + half * lateral,
                   radius)


def stature_m(skeleton: Skeleton, geoms: list[Capsule]) -> float:
    """Standing height of the model: top of its highest geom to the bottom of its lowest,
    in the rest pose with the legs straightened (metres)."""
    rest = vectors_to_mj(_straight_leg_rest_m(skeleton))
    parents = skeleton.parents
    top, bottom = -math.inf, math.inf
    for g in geoms:
        b = skeleton.bone_index(g.bone)
        origin = rest[parents[b]] if parents[b] >= 0 else rest[0]
        # Along-bone capsules of the straightened legs follow the bone: rescale them.
        direction = rest[b] - origin
        offset = vectors_to_mj(skeleton.offsets_m[b])
        if np.linalg.norm(offset) > 0 and g.bone[1:] in ("femur", "tibia"):
            f0 = float(np.dot(g.p0_m, offset) / np.dot(offset, offset))
            f1 = float(np.dot(g.p1_m, offset) / np.dot(offset, offset))
            z0, z1 = origin[2] + f0 * direction[2], origin[2] + f1 * direction[2]
        else:
            z0, z1 = origin[2] + g.p0_m[2], origin[2] + g.p1_m[2]
        top = max(top, z0 + g.radius_m, z1 + g.radius_m)
        bottom = min(bottom, z0 - g.radius_m, z1 - g.radius_m)
    return top - bottom


def body_mass_kg(stature: float) -> float:
    """Whole-body mass of a body of this stature: ``BMI_KG_M2 * stature**2``."""
    return BMI_KG_M2 * stature * stature


def with_masses(geoms: list[Capsule], total_mass_kg: float) -> list[Capsule]:
    """Give each geom its share of ``total_mass_kg``: de Leva's segment fraction, split
    among the segment's geoms by volume. A segment without volume (only possible for a
    hand-made skeleton with zero-length bones) passes its share on to the others, in
    proportion to theirs, so the total is always ``total_mass_kg``."""
    segment_of = {bone: seg for seg, (_, bones) in SEGMENT_MASS_FRACTIONS.items()
                  for bone in bones}
    volume = {seg: 0.0 for seg in SEGMENT_MASS_FRACTIONS}
    for g in geoms:
        volume[segment_of[g.bone]] += g.volume_m3
    present = sum(SEGMENT_MASS_FRACTIONS[seg][0] for seg, v in volume.items() if v > 0)
    if present == 0:
        raise ValueError("the skeleton has no geom to carry the body's mass")
    out = []
    for g in geoms:
        seg = segment_of[g.bone]
        share = SEGMENT_MASS_FRACTIONS[seg][0] / present
        out.append(replace(g, mass_kg=total_mass_kg * share * g.volume_m3 / volume[seg]))
    return out
