"""Whether a simulated character has fallen: its pelvis or head below a share of its
standing height while the reference's is not, and well below the reference's (a
reference that crouches or lies down is not a fall, nor is a character that follows a
reference bending through that height a few centimetres lower)."""

from __future__ import annotations

import numpy as np

#: Fallen: pelvis or head below this share of its standing height (the reference's not) ...
FALL_FRACTION = 0.5
#: ... and more than this share of its standing height below the reference's. On 02_06
#: (bend over and scoop up) the character's head passed half its standing height 4 cm
#: under the reference's, which it was following down and up again: without the margin,
#: a fall at 0.98 s. Only a reference that comes within this margin of the threshold
#: is judged differently (of the data's clips, 02_06, 02_10 and 05_06).
FALL_MARGIN = 0.1


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
    def down(sim_m, ref_m, standing_m):
        sim_m, ref_m = np.asarray(sim_m), np.asarray(ref_m)
        low = FALL_FRACTION * standing_m
        return (sim_m < low) & (ref_m >= low) & (ref_m - sim_m > FALL_MARGIN * standing_m)

    with np.errstate(invalid="ignore"):
        return (down(pelvis_m, reference_pelvis_m, figures.pelvis_height_m)
                | down(head_m, reference_head_m, figures.head_height_m))


def fall_frame(pelvis_m, head_m, reference_pelvis_m, reference_head_m, figures) -> int | None:
    """The first frame at which the character is down (:func:`fallen`), or None."""
    hits = np.flatnonzero(fallen(pelvis_m, head_m, reference_pelvis_m, reference_head_m,
                                 figures))
    return int(hits[0]) if hits.size else None


def fall_rule(figures) -> str:
    """The rule in words, with the thresholds."""
    return rule_text(figures.pelvis_height_m, figures.head_height_m)


def rule_text(standing_pelvis_m: float, standing_head_m: float) -> str:
    """:func:`fall_rule` for the standing pelvis and head heights, m."""
    return (f"pelvis or head below {FALL_FRACTION:g} x standing height "
            f"({FALL_FRACTION * standing_pelvis_m:.3f} m, "
            f"{FALL_FRACTION * standing_head_m:.3f} m) while the reference's is not, and "
            f"more than {FALL_MARGIN:g} x standing height "
            f"({FALL_MARGIN * standing_pelvis_m:.3f} m, {FALL_MARGIN * standing_head_m:.3f} m) "
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
