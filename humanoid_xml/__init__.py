"""The MuJoCo 21-joint humanoid generated from an ASF skeleton (SPEC section 5).

- :func:`build_mjcf` makes the MJCF text of the humanoid for any CMU skeleton;
- :func:`default_model_path` is the generic adult kept in this package (built by the same
  generator from ``generic_adult.json``, :func:`generic_skeleton`);
- :func:`subject_model_path` / :func:`catalog_model_path` build a subject's model from its
  ASF on demand, cached outside the repository;
- :func:`servo_gains` (:mod:`humanoid_xml.servos`) gives each servo's gains and what they
  come from; :data:`STRENGTH` / :func:`torque_limits_nm` (:mod:`humanoid_xml.strength`)
  the joints' strength table with its sources.
"""

from humanoid_xml.description import generic_skeleton, read_skeleton_description
from humanoid_xml.frames import ASF_TO_MJ
from humanoid_xml.generator import build_mjcf, hinge_names
from humanoid_xml.models import (
    catalog_model_path,
    default_model_path,
    load_model,
    subject_model_path,
)
from humanoid_xml.servos import servo_gains
from humanoid_xml.strength import STRENGTH, torque_limits_nm

__all__ = [
    "ASF_TO_MJ",
    "STRENGTH",
    "build_mjcf",
    "catalog_model_path",
    "default_model_path",
    "generic_skeleton",
    "hinge_names",
    "load_model",
    "read_skeleton_description",
    "servo_gains",
    "subject_model_path",
    "torque_limits_nm",
]
