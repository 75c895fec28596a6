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
- hip joints and upperneck carry no geom of their own (the pelvis and neck cover them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from humanoid_xml.frames import vectors_to_mj
from upm.kinematics import rest_positions
from upm.skeleton import Skeleton

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
        In ``skeleton.bone_names`` order.
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
    return out


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
