"""Whether a simulated character has fallen: its pelvis or head below a share of its
standing height while the reference's is not (a reference that crouches or lies down is
not a fall)."""

from __future__ import annotations

import numpy as np

#: Fallen: pelvis or head below this share of its standing height (the reference's not).
FALL_FRACTION = 0.5


def fallen(pelvis_m, head_m, reference_pelvis_m, reference_head_m, figures) -> np.ndarray:
    """Frames at which the character is down, bool, the shape of the inputs.

    Parameters
    ----------
    pelvis_m, head_m : array_like, shape (T,)
        Simulated pelvis and head heights (NaN: not simulated, not down).
    reference_pelvis_m, reference_head_m : array_like, shape (T,)
    figures : controller.body.BodyFigures
        The standing heights.
    """
    low_p = FALL_FRACTION * figures.pelvis_height_m
    low_h = FALL_FRACTION * figures.head_height_m
    with np.errstate(invalid="ignore"):
        return (((np.asarray(pelvis_m) < low_p) & (np.asarray(reference_pelvis_m) >= low_p))
                | ((np.asarray(head_m) < low_h) & (np.asarray(reference_head_m) >= low_h)))


def fall_frame(pelvis_m, head_m, reference_pelvis_m, reference_head_m, figures) -> int | None:
    """The first frame at which the character is down (:func:`fallen`), or None."""
    hits = np.flatnonzero(fallen(pelvis_m, head_m, reference_pelvis_m, reference_head_m,
                                 figures))
    return int(hits[0]) if hits.size else None


def fall_rule(figures) -> str:
    """The rule in words, with the thresholds."""
    return (f"pelvis or head below {FALL_FRACTION:g} x standing height "
            f"({FALL_FRACTION * figures.pelvis_height_m:.3f} m, "
            f"{FALL_FRACTION * figures.head_height_m:.3f} m) while the reference's is not")


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
