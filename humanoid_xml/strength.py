"""Joint strength: the largest torque each servo may apply (the actuator's ``forcerange``).

Peak isometric joint torques of adults, from published measurements, scaled to the
model's body: a value given as a fraction of body weight x stature (``"bwh"``: torque /
(m g H), the normalisation of Anderson et al. 2007) is multiplied by the model's own
``m g H``; a value given per kilogram (``"per_kg"``) by its mass. Where a source reports
a mean and a standard deviation, the limit is the mean + 2 SD: the strength of a strong
healthy adult (about the 98th percentile), so that the limit forbids superhuman torques
without forbidding what strong people do. Isometric peaks at the strongest joint angle,
without the loss of torque with angle and speed: an upper bound.

Each DOF has a limit for each direction of its hinge (``negative``: the torque that turns
the hinge angle down), following the CMU axes: on the sagittal ``rx`` hinges a positive
angle is hip extension, knee flexion, ankle plantar flexion, toe flexion, elbow flexion,
wrist flexion, and trunk and neck flexion, on both sides. Frontal and transverse DOFs
are given one value for both directions.

Sources
-------
- **Anderson et al. 2007**: D. E. Anderson, M. L. Madigan, M. A. Nussbaum, Maximum
  voluntary joint torque as a function of joint angle and angular velocity: model
  development and application to the lower limb, J. Biomech. 40 (2007) 3105-3113,
  Table 3, young men (18-25 years): the peak isometric torque ``C1`` in units of body
  weight x height, mean (SD): hip extension 0.161 (0.049), hip flexion 0.113 (0.025),
  knee extension 0.163 (0.040), knee flexion 0.087 (0.015), ankle plantar flexion
  0.095 (0.022), dorsiflexion 0.033 (0.005).
- **Millard et al. whole-body set**: M. Millard, A.-L. Kleesattel, M. Harant, K. Mombaur,
  the whole-body torque set of one young elite male gymnast (69.6 kg, 1.732 m) compiled
  from Jackson (2010, doctoral thesis, Loughborough University) and Kentel, King &
  Mitchell (2011, J. Appl. Biomech. 27: 345-354), as distributed in RBDL's muscle addon
  (``Millard2016TorqueMuscle``, data set "Gymnast"); peak isometric torques, N m:
  shoulder flexion 91.1, extension 127.4, horizontal adduction 128.5, horizontal
  abduction 94.7, internal rotation 50.5, external rotation 43.6; elbow flexion 101.4,
  extension 69.9; wrist flexion 39.2, extension 15.6, ulnar deviation 31.4, radial
  deviation 23.8. One trained subject, no spread: taken as they are, per kilogram.
- **Sugimoto et al. 2014**: D. Sugimoto, C. G. Mattacola, D. R. Mullineaux, T. G.
  Palmer, T. E. Hewett, Comparison of isokinetic hip abduction and adduction peak
  torques and ratio between sexes, Clin. J. Sport Med. 24 (2014) 422-428: male hip
  abductors 1.29 (0.24) N m/kg (concentric, 60 degrees/s: below isometric).
- **Chaffin et al. 1999**: D. B. Chaffin, G. B. J. Andersson, B. J. Martin, Occupational
  Biomechanics, 3rd ed., Table 4.5: male torso extension 288 N m (at 20 degrees of
  flexion); torso flexion from the extension : flexion ratio of 1.3 : 1 most often
  reported (Beimborn & Morrissey 1988, Spine 13: 655-660).
- **Neck, Ann. Biomed. Eng. 2014**: "Prediction of three-dimensional maximum isometric
  neck strength", Ann. Biomed. Eng. (2014), doi:10.1007/s10439-014-1046-0, nine men:
  flexion 30 (6), lateral bending 32 (9), extension 51 (11), axial rotation 13 (5) N m.
- Sources that give N m without their subjects' body mass are taken per kilogram of
  :data:`REFERENCE_MASS_KG`.

**Estimates** (no measured value was found; ``measured=False`` in the table, listed in
the README): hip adduction (taken equal to abduction), hip rotation (half the
abduction), ankle inversion/eversion, toe flexion/extension, trunk lateral bending (taken
equal to trunk flexion) and axial twist (half of it), and the clavicles' (scapular)
elevation and protraction (taken equal to the shoulder's rotation strength).
"""

from __future__ import annotations

from dataclasses import dataclass

#: Body mass of the subjects of a source that reports absolute torques only, kg.
REFERENCE_MASS_KG = 75.0
#: Standard gravity, m/s^2 (the ``bwh`` unit).
GRAVITY = 9.81
_GYMNAST_KG = 69.6


@dataclass(frozen=True)
class Strength:
    """The strength of one DOF (side-less), both directions.

    Attributes
    ----------
    dof : str
        ``"femur.rx"``: applies to ``lfemur_rx`` and ``rfemur_rx``.
    negative, positive : float
        The largest torque turning the hinge angle down / up, in ``unit``.
    unit : str
        ``"bwh"`` (x body weight x stature, N m) or ``"per_kg"`` (x body mass, N m).
    basis : str
        The movement of each direction, the source and the arithmetic.
    measured : bool
        False where no measured value was found and the limit is an estimate.
    """

    dof: str
    negative: float
    positive: float
    unit: str
    basis: str
    measured: bool = True

    def limits_nm(self, mass_kg: float, stature_m: float) -> tuple[float, float]:
        """(negative, positive) torque limits for a body, N m (both positive numbers)."""
        scale = mass_kg * GRAVITY * stature_m if self.unit == "bwh" else mass_kg
        return self.negative * scale, self.positive * scale


def _sd2(mean: float, sd: float) -> float:
    return round(mean + 2.0 * sd, 6)


def _per_kg(torque_nm: float, mass_kg: float = REFERENCE_MASS_KG) -> float:
    return round(torque_nm / mass_kg, 6)


_TRUNK_EXT = _per_kg(288.0)
_TRUNK_FLEX = _per_kg(288.0 / 1.3)
_HIP_ABD = _sd2(1.29, 0.24)
_SHOULDER_ROT = _per_kg(50.5, _GYMNAST_KG)

#: The strength of every DOF of the 21 joints, by side-less DOF name.
STRENGTH: dict[str, Strength] = {s.dof: s for s in (
    # Legs (sagittal): Anderson et al. 2007, young men, mean + 2 SD.
    Strength("femur.rx", _sd2(0.113, 0.025), _sd2(0.161, 0.049), "bwh",
             "- hip flexion / + hip extension; Anderson et al. 2007"),
    Strength("tibia.rx", _sd2(0.163, 0.040), _sd2(0.087, 0.015), "bwh",
             "- knee extension / + knee flexion; Anderson et al. 2007"),
    Strength("foot.rx", _sd2(0.033, 0.005), _sd2(0.095, 0.022), "bwh",
             "- ankle dorsiflexion / + plantar flexion; Anderson et al. 2007"),
    # Hip, frontal and transverse.
    Strength("femur.rz", _HIP_ABD, _HIP_ABD, "per_kg",
             "abduction / adduction; Sugimoto et al. 2014 abductors, mean + 2 SD "
             "(adduction taken equal: estimate)"),
    Strength("femur.ry", 0.5 * _HIP_ABD, 0.5 * _HIP_ABD, "per_kg",
             "internal / external rotation: half the hip abduction (estimate)", False),
    # Foot.
    Strength("foot.rz", 0.5, 0.5, "per_kg",
             "inversion / eversion (toe-in / toe-out): estimate", False),
    Strength("toes.rx", 0.3, 0.3, "per_kg", "toe extension / flexion: estimate", False),
    # Trunk: Chaffin et al. 1999 (extension), Beimborn & Morrissey 1988 (ratio).
    *(Strength(f"{bone}.rx", _TRUNK_EXT, _TRUNK_FLEX, "per_kg",
               f"- trunk extension / + flexion; Chaffin et al. 1999 / 1.3, per "
               f"{REFERENCE_MASS_KG:g} kg")
      for bone in ("lowerback", "upperback", "thorax")),
    *(Strength(f"{bone}.rz", _TRUNK_FLEX, _TRUNK_FLEX, "per_kg",
               "lateral bending: taken equal to trunk flexion (estimate)", False)
      for bone in ("lowerback", "upperback", "thorax")),
    *(Strength(f"{bone}.ry", 0.5 * _TRUNK_FLEX, 0.5 * _TRUNK_FLEX, "per_kg",
               "axial twist: half the trunk flexion (estimate)", False)
      for bone in ("lowerback", "upperback", "thorax")),
    # Neck and head: Ann. Biomed. Eng. 2014, mean + 2 SD, per REFERENCE_MASS_KG.
    *(Strength(f"{bone}.rx", _per_kg(_sd2(51, 11)), _per_kg(_sd2(30, 6)), "per_kg",
               "- neck extension / + flexion; Ann. Biomed. Eng. 2014")
      for bone in ("lowerneck", "head")),
    *(Strength(f"{bone}.rz", _per_kg(_sd2(32, 9)), _per_kg(_sd2(32, 9)), "per_kg",
               "neck lateral bending; Ann. Biomed. Eng. 2014")
      for bone in ("lowerneck", "head")),
    *(Strength(f"{bone}.ry", _per_kg(_sd2(13, 5)), _per_kg(_sd2(13, 5)), "per_kg",
               "neck axial rotation; Ann. Biomed. Eng. 2014")
      for bone in ("lowerneck", "head")),
    # Shoulder girdle and arm: Millard et al. whole-body set (gymnast), per kg.
    Strength("clavicle.ry", _SHOULDER_ROT, _SHOULDER_ROT, "per_kg",
             "scapular protraction / retraction: taken equal to the shoulder's rotation "
             "(estimate)", False),
    Strength("clavicle.rz", _SHOULDER_ROT, _SHOULDER_ROT, "per_kg",
             "scapular elevation / depression: taken equal to the shoulder's rotation "
             "(estimate)", False),
    Strength("humerus.rx", _per_kg(128.5, _GYMNAST_KG), _per_kg(128.5, _GYMNAST_KG), "per_kg",
             "shoulder elevation in the T-pose frame (a mix of horizontal ad/abduction and "
             "ab/adduction): the strongest shoulder direction, horizontal adduction; "
             "Millard et al. set"),
    Strength("humerus.rz", _per_kg(128.5, _GYMNAST_KG), _per_kg(128.5, _GYMNAST_KG), "per_kg",
             "as humerus.rx (the other mix of the two); Millard et al. set"),
    Strength("humerus.ry", _SHOULDER_ROT, _SHOULDER_ROT, "per_kg",
             "shoulder internal / external rotation (the stronger, internal); Millard et "
             "al. set"),
    Strength("radius.rx", _per_kg(69.9, _GYMNAST_KG), _per_kg(101.4, _GYMNAST_KG), "per_kg",
             "- elbow extension / + flexion; Millard et al. set"),
    Strength("hand.rx", _per_kg(15.6, _GYMNAST_KG), _per_kg(39.2, _GYMNAST_KG), "per_kg",
             "- wrist extension / + flexion; Millard et al. set"),
    Strength("hand.rz", _per_kg(31.4, _GYMNAST_KG), _per_kg(31.4, _GYMNAST_KG), "per_kg",
             "wrist ulnar / radial deviation (the stronger, ulnar); Millard et al. set"),
)}


def side_less(hinge: str) -> str:
    """``"lfemur_rx"`` -> ``"femur.rx"``; ``"lowerback_rx"`` -> ``"lowerback.rx"``."""
    bone, _, dof = hinge.rpartition("_")
    if bone[:1] in ("l", "r") and f"{bone[1:]}.{dof}" in STRENGTH:
        bone = bone[1:]
    return f"{bone}.{dof}"


def torque_limits_nm(hinges, mass_kg: float, stature_m: float) -> dict[str, tuple[float, float]]:
    """The (negative, positive) torque limit of each hinge for a body, N m.

    Parameters
    ----------
    hinges : iterable of str
        Hinge names (``"lfemur_rx"``).
    mass_kg, stature_m : float
        The body's mass and stature.

    Returns
    -------
    dict of str to (float, float)
        Both numbers positive: the actuator's ``forcerange`` is ``[-negative, positive]``.

    Raises
    ------
    KeyError
        For a hinge outside the 21 joints' DOF.
    """
    return {h: STRENGTH[side_less(h)].limits_nm(mass_kg, stature_m) for h in hinges}
