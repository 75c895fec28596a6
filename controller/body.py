"""Figures of the humanoid's body that the physical checks are normalised by: its mass and
weight, its stature, and the standing heights of the pelvis and the head."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BodyFigures:
    """The humanoid standing in its rest pose (``qpos0``: the ASF rest pose on the floor).

    Attributes
    ----------
    mass_kg : float
        Total mass.
    weight_n : float
        ``mass_kg * |gravity|``, newtons.
    stature_m : float
        Highest point of any geom above the floor at rest (top of the head), metres.
    pelvis_height_m : float
        Height of the root body (the pelvis, at the hip-joint centres' level) at rest.
    head_height_m : float
        Height of the ``head`` body's distal end (site ``head_end``) at rest.
    """

    mass_kg: float
    weight_n: float
    stature_m: float
    pelvis_height_m: float
    head_height_m: float


def body_figures(model) -> BodyFigures:
    """The :class:`BodyFigures` of a humanoid made by :func:`humanoid_xml.build_mjcf`."""
    import mujoco

    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    mujoco.mj_kinematics(model, data)
    mass = float(np.sum(model.body_mass))
    capsule = model.geom_type == mujoco.mjtGeom.mjGEOM_CAPSULE
    # A capsule's top: its centre plus its half-length along the axis' vertical part,
    # plus its radius.
    axis_z = np.abs(data.geom_xmat[capsule].reshape(-1, 3, 3)[:, 2, 2])
    tops = (data.geom_xpos[capsule, 2] + model.geom_size[capsule, 1] * axis_z
            + model.geom_size[capsule, 0])
    head_site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "head_end")
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "root")
    if head_site < 0 or root < 0:
        raise ValueError("the model has no root body or head_end site (not a humanoid_xml "
                         "model?)")
    return BodyFigures(
        mass_kg=mass,
        weight_n=mass * float(np.linalg.norm(model.opt.gravity)),
        stature_m=float(tops.max()) if tops.size else 0.0,
        pelvis_height_m=float(data.xpos[root, 2]),
        head_height_m=float(data.site_xpos[head_site, 2]),
    )
