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
        Standing height, metres: the stature the generator scaled the body's mass and
        strength by (the model's ``stature_m`` numeric: top of the head to the soles with
        the legs straightened), so every figure normalised by it uses the same height.
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
    stature = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, "stature_m")
    head_site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "head_end")
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "root")
    if head_site < 0 or root < 0 or stature < 0:
        raise ValueError("the model has no root body, head_end site or stature_m numeric "
                         "(not a humanoid_xml model?)")
    return BodyFigures(
        mass_kg=mass,
        weight_n=mass * float(np.linalg.norm(model.opt.gravity)),
        stature_m=float(model.numeric_data[model.numeric_adr[stature]]),
        pelvis_height_m=float(data.xpos[root, 2]),
        head_height_m=float(data.site_xpos[head_site, 2]),
    )


def floor_normal_force(model, data) -> float:
    """Total normal force of the floor on the body, N."""
    import mujoco

    total = 0.0
    force = np.zeros(6)
    geom_body = model.geom_bodyid
    for i in range(data.ncon):
        g = data.contact.geom[i]
        if (geom_body[g[0]] == 0) != (geom_body[g[1]] == 0):
            mujoco.mj_contactForce(model, data, i, force)
            total += force[0]
    return total
