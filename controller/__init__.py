"""Driving the MuJoCo humanoid with motions: qpos mapping and contact queries."""

from controller.qpos import from_qpos, posture_to_ctrl, to_qpos

__all__ = ["from_qpos", "posture_to_ctrl", "to_qpos"]
