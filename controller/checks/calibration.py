"""The kinematic checks of real clips: the calibration of every validity figure."""

from __future__ import annotations

from dataclasses import dataclass

from controller.checks.validity import check_motion
from controller.checks.validity_report import _pct, summarize


@dataclass(frozen=True)
class Calibration:
    """The kinematic checks of real clips, each on its own subject's model.

    Attributes
    ----------
    clips : dict of str to dict
        Per clip, :func:`summarize` of the whole clip (plus ``split``).
    """

    clips: dict[str, dict]

    def totals(self, names=None) -> dict:
        """Frame-weighted totals over some clips (all by default), JSON-ready."""
        rows = [self.clips[n] for n in (self.clips if names is None else names)]
        frames = sum(r["frames"] for r in rows)
        out = {"clips": len(rows), "frames": frames}
        for key in ("valid", "limit_violation", "self_collision", "floor_penetration",
                    "beyond_asf"):
            count = sum(r[f"{key}_frames"] for r in rows)
            out[f"{key}_frames"] = count
            out[f"{key}_pct"] = _pct(count, frames)
        out["limit_excess_mean_deg"] = round(
            sum(r["limit_excess_mean_deg"] * r["frames"] for r in rows) / max(frames, 1), 4)
        out["limit_excess_peak_deg"] = max((r["limit_excess_peak_deg"] for r in rows),
                                           default=0.0)
        return out


def calibrate(catalog, names=None, limits=None) -> Calibration:
    """The kinematic checks of real clips: the calibration of every validity figure.

    Parameters
    ----------
    catalog : upm.motion.catalog.Catalog
    names : iterable of str, optional
        Clip names (default: every clip).
    limits : str, optional
        The range model (default ``"human"``).
    """
    from humanoid_xml import catalog_model_path, load_model
    from upm.core.progress import progress

    names = list(catalog.names() if names is None else names)
    models: dict[str, object] = {}
    clips = {}
    for name in progress(names, desc="checking clips", unit="clip"):
        info = catalog.info(name)
        if info.subject not in models:
            models[info.subject] = load_model(catalog_model_path(catalog, info.subject))
        summary = summarize(check_motion(models[info.subject], catalog.load(name),
                                         limits=limits))
        clips[name] = {"split": info.split, **summary}
    return Calibration(clips=clips)
