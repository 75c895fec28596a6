"""Whether a simulated character has fallen: its pelvis or head below a share of its
standing height while the reference's is not, and well below the reference's (a
reference that crouches or lies down is not a fall, nor is a character that follows a
reference bending through that height a few centimetres lower). The share and the margin
are the configuration's ``falls`` section (:class:`controller.config.sections.FallsConfig`:
half the standing height, and a tenth of it)."""

from __future__ import annotations

import numpy as np

from controller.config import DEFAULT


def fallen(pelvis_m, head_m, reference_pelvis_m, reference_head_m, figures,
           falls=DEFAULT.falls) -> np.ndarray:
    """Frames at which the character is down, bool, the shape of the inputs.

    Parameters
    ----------
    pelvis_m, head_m : array_like, shape (T,)
        Simulated pelvis and head heights (NaN: not simulated, not down).
    reference_pelvis_m, reference_head_m : array_like, shape (T,)
    figures : controller.body.BodyFigures
        The standing heights.
    falls : controller.config.sections.FallsConfig
        The share of the standing height and the margin.
    """
    def down(sim_m, ref_m, standing_m):
        sim_m, ref_m = np.asarray(sim_m), np.asarray(ref_m)
        low = falls.fraction * standing_m
        return (sim_m < low) & (ref_m >= low) & (ref_m - sim_m > falls.margin * standing_m)

    with np.errstate(invalid="ignore"):
        return (down(pelvis_m, reference_pelvis_m, figures.pelvis_height_m)
                | down(head_m, reference_head_m, figures.head_height_m))


def fall_frame(pelvis_m, head_m, reference_pelvis_m, reference_head_m, figures,
               falls=DEFAULT.falls) -> int | None:
    """The first frame at which the character is down (:func:`fallen`), or None."""
    hits = np.flatnonzero(fallen(pelvis_m, head_m, reference_pelvis_m, reference_head_m,
                                 figures, falls))
    return int(hits[0]) if hits.size else None


def fall_rule(figures, falls=DEFAULT.falls) -> str:
    """The rule in words, with the thresholds."""
    return rule_text(figures.pelvis_height_m, figures.head_height_m, falls)


def rule_text(standing_pelvis_m: float, standing_head_m: float, falls=DEFAULT.falls) -> str:
    """:func:`fall_rule` for the standing pelvis and head heights, m."""
    share, margin = falls.fraction, falls.margin
    return (f"pelvis or head below {share:g} x standing height "
            f"({share * standing_pelvis_m:.3f} m, "
            f"{share * standing_head_m:.3f} m) while the reference's is not, and "
            f"more than {margin:g} x standing height "
            f"({margin * standing_pelvis_m:.3f} m, {margin * standing_head_m:.3f} m) "
            "below the reference's")


def reference_heights(model, qpos, root_body: int, head_site: int):
    """Pelvis (root body) and head (site) heights of every frame, two arrays (T,)."""
    import mujoco

    data = mujoco.MjData(model)
    pelvis = np.empty(qpos.shape[0])
    head = np.empty(qpos.shape[0])
    for t in range(qpos.shape[0]):
        data.qpos[:] = qpos[t]
        mujoco.mj_kinematics(model, data)
        pelvis[t] = data.xpos[root_body, 2]
        head[t] = data.site_xpos[head_site, 2]
    return pelvis, head
