"""The calibration harness: does the verdict agree with what humans did?

- **specificity**: the share of real frames judged valid, per clip and per cause
  (:func:`controller.checks.calibration.calibrate`);
- **sensitivity**: the share of impossible frames judged invalid, per family
  (:mod:`upm.motion.impossible`), made from every ``every``-th real frame of the same
  clips, and which cause caught them.
"""

from __future__ import annotations

import numpy as np

from upm.motion.impossible import FAMILIES, make_family


def sensitivity(catalog, names, limits=None, every: int = 10) -> dict[str, dict]:
    """Each impossible family's frames judged invalid, JSON-ready.

    Returns
    -------
    dict of str to dict
        Per family: ``frames``, ``invalid_frames``, ``invalid_pct``, and the frames each
        cause flags: ``limit_frames``, ``self_frames``, ``floor_frames``.
    """
    from controller.checks.validity import check_motion
    from humanoid_xml import catalog_model_path, load_model
    from upm.core.progress import progress

    totals = {f: {"frames": 0, "invalid_frames": 0, "limit_frames": 0, "self_frames": 0,
                  "floor_frames": 0} for f in FAMILIES}
    models: dict[str, object] = {}
    for name in progress(list(names), desc="impossible postures", unit="clip"):
        subject = catalog.info(name).subject
        if subject not in models:
            models[subject] = load_model(catalog_model_path(catalog, subject))
        motion = catalog.load(name)
        extra = None if motion.extra_deg is None else motion.extra_deg[::every]
        frames = motion.replace(posture_deg=motion.posture_deg[::every],
                                root=motion.root[::every], extra_deg=extra)
        for family in FAMILIES:
            posture, root = make_family(family, frames.skeleton, frames.posture_deg,
                                        frames.root)
            v = check_motion(models[subject], frames.replace(posture_deg=posture, root=root),
                             limits=limits)
            row = totals[family]
            row["frames"] += v.n_frames
            row["invalid_frames"] += int((~v.valid).sum())
            row["limit_frames"] += int(v.limit_violation.sum())
            row["self_frames"] += int(v.self_collision.sum())
            row["floor_frames"] += int(v.floor_penetration.sum())
    for row in totals.values():
        row["invalid_pct"] = round(100.0 * row["invalid_frames"] / max(row["frames"], 1), 2)
    return totals


def harness(catalog, names, limits=None, every: int = 10) -> dict:
    """Specificity and sensitivity of the verdict on some clips, JSON-ready."""
    from controller.checks.calibration import calibrate

    names = list(names)
    calibration = calibrate(catalog, names, limits=limits)
    asf = calibrate(catalog, names, limits="asf")
    return {
        "limits": getattr(limits, "name", limits) or "human",
        "specificity": {"totals": calibration.totals(), "clips": calibration.clips,
                        "asf_totals": asf.totals()},
        "sensitivity": sensitivity(catalog, names, limits=limits, every=every),
    }


def figure(result: dict, path) -> None:
    """Two panels: real frames judged valid per clip (human and ASF verdicts), and
    impossible frames judged invalid per family. Written atomically (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from upm.core.fileio import atomic_path

    clips = result["specificity"]["clips"]
    names = list(clips)
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2),
                                      gridspec_kw={"width_ratios": [max(len(names), 4), 7]})
    x = np.arange(len(names))
    left.bar(x, [clips[n]["valid_pct"] for n in names], color="#3b7dd8",
             label=f"{result['limits']} verdict")
    left.bar(x, [100 - clips[n]["beyond_asf_pct"] for n in names], width=0.35,
             color="#bbbbbb", label="inside the ASF's boxes")
    left.axhline(98, color="k", lw=0.8, ls="--")
    left.set_xticks(x, names, rotation=70, fontsize=7)
    left.set_ylabel("real frames judged valid (%)")
    left.set_ylim(0, 100)
    left.legend(fontsize=7, loc="lower left")
    left.set_title("specificity: real motion", fontsize=9)
    sens = result["sensitivity"]
    fams = list(sens)
    right.bar(np.arange(len(fams)), [sens[f]["invalid_pct"] for f in fams], color="#d8543b")
    right.axhline(95, color="k", lw=0.8, ls="--")
    right.set_xticks(np.arange(len(fams)), fams, rotation=40, ha="right", fontsize=7)
    right.set_ylim(0, 100)
    right.set_ylabel("impossible frames judged invalid (%)")
    right.set_title("sensitivity: impossible postures", fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
