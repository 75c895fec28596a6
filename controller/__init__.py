"""Driving the MuJoCo humanoid with motions: qpos mapping, the physical checks
(:mod:`controller.checks`), servo tracking (:mod:`controller.tracking`) and the balance
controller (:mod:`controller.balance`).

Importing the package registers the humanoid's kinematic checker for the ``feasible``
transition method (:mod:`controller.checks.kinematic_check`).
"""

from controller.checks import kinematic_check  # noqa: F401
from controller.qpos import from_qpos, posture_to_ctrl, to_qpos

__all__ = ["from_qpos", "posture_to_ctrl", "to_qpos"]
