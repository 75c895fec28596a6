"""Angle and rotation maths: pure batched functions over arrays (degrees, periodic angles
wrapped to [-180, 180); rotation matrices ``[..., 3, 3]`` and quaternions ``[..., 4]``)."""
