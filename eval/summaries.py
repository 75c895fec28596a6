"""The study's statistics as long-form tables, computed from a :class:`eval.records.Records`.

:func:`summarise` turns the per-unit table (kinematic scores or free-root figures) into
three tables keyed by plain tuples, window lengths as ints:

- ``summary``: (window, group, method, metric) -> mean and 95 % bootstrap interval, for the
  groups ``all`` and ``flat_floor``, every method and the real windows (:data:`REAL`);
- ``paired``: (window, X, group, metric) -> reference - X (mean difference, interval,
  wins / ties / losses), every group of :data:`eval.statistics.GROUPS`;
- ``calibration``: (window, clip, metric) -> the real windows' mean per test clip.

Every writer (the Markdown and terminal tables, the CSVs, results.json, the figures) reads
them through :meth:`Summaries.interval`, :meth:`Summaries.comparison` and
:meth:`Summaries.clip_mean`, which refuse a metric not in the registry by name. A NaN value
in the records is a figure that does not exist for that unit (a free-root run that fell
before its window has no tracking error): means use the units that have it, paired
differences the pairs where both methods have it, and ``n`` says how many.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from eval.records import REAL, Records
from eval.statistics import (
    CONFIDENCE,
    GROUPS,
    RESAMPLES,
    bootstrap_mean,
    compare,
    pair_groups,
    round6,
)

#: The groups every method's summary is given for.
SUMMARY_GROUPS = ("all", "flat_floor")
#: Columns of :meth:`Summaries.summary_rows` (``summary.csv``).
SUMMARY_COLUMNS = ("window_frames", "group", "method", "metric", "unit", "better", "mean",
                   "ci_low", "ci_high", "n")
#: Columns of :meth:`Summaries.paired_rows` (``paired.csv``).
PAIRED_COLUMNS = ("window_frames", "upm_minus", "group", "metric", "unit", "better",
                  "mean_diff", "ci_low", "ci_high", "n", "upm_wins", "ties", "upm_losses")


@dataclass
class Summaries:
    """Means, intervals and paired comparisons of one study, long-form.

    Attributes
    ----------
    metrics : dict of str to spec
        The registry (each spec has ``unit`` and ``better``).
    windows : tuple of int
    methods : tuple of str
    reference : str or None
        The method every other is compared with (None: not run, no paired rows).
    settings : dict
        The bootstrap's settings.
    groups : dict
        ``pairs`` (pairs per group), ``ab_tercile_edges_deg``, ``end_self_collision``.
    summary : dict of (int, str, str, str) to dict
        (window, group, method, metric) -> ``{mean, lo, hi, n}``.
    paired : dict of (int, str, str, str) to dict
        (window, X, group, metric) -> ``{mean_diff, lo, hi, n, wins, ties, losses}``.
    calibration : dict of (int, str, str) to float or None
        (window, clip, metric) -> the real windows' mean.
    clip_windows : dict of (int, str) to int
        (window, clip) -> how many real windows.
    """

    metrics: dict
    windows: tuple
    methods: tuple
    reference: str | None
    settings: dict
    groups: dict
    summary: dict
    paired: dict
    calibration: dict
    clip_windows: dict

    def _check(self, metric: str) -> None:
        if metric not in self.metrics:
            raise KeyError(f"metric {metric!r} is not in the registry "
                           f"({', '.join(self.metrics)})")

    def interval(self, window: int, method: str, metric: str, group: str = "all") -> dict:
        """``{mean, lo, hi, n}`` of a method (or :data:`REAL`) on one metric."""
        self._check(metric)
        return self.summary[(int(window), group, method, metric)]

    def comparison(self, window: int, other: str, metric: str, group: str = "all") -> dict:
        """``{mean_diff, lo, hi, n, wins, ties, losses}`` of reference - ``other``."""
        self._check(metric)
        return self.paired[(int(window), other, group, metric)]

    def compared(self, window: int) -> list[str]:
        """The methods compared with the reference at a window (none without one)."""
        if self.reference is None or int(window) not in self.windows:
            return []
        return [m for m in self.methods if m != self.reference]

    def clips(self, window: int) -> list[str]:
        """The test clips with real windows at a window length, sorted."""
        return sorted(c for w, c in self.clip_windows if w == int(window))

    def clip_mean(self, window: int, clip: str, metric: str):
        """The real windows' mean of one clip (None if it has no such figure)."""
        self._check(metric)
        return self.calibration[(int(window), clip, metric)]

    def summary_rows(self) -> list[tuple]:
        """Long-form rows of :data:`SUMMARY_COLUMNS`."""
        return [(w, g, m, k, self.metrics[k].unit, self.metrics[k].better, iv["mean"],
                 iv["lo"], iv["hi"], iv["n"]) for (w, g, m, k), iv in self.summary.items()]

    def paired_rows(self) -> list[tuple]:
        """Long-form rows of :data:`PAIRED_COLUMNS`."""
        return [(w, x, g, k, self.metrics[k].unit, self.metrics[k].better, c["mean_diff"],
                 c["lo"], c["hi"], c["n"], c["wins"], c["ties"], c["losses"])
                for (w, x, g, k), c in self.paired.items()]

    def as_json(self) -> dict:
        """JSON-ready: every table as a list of rows that name their fields."""
        return {
            "bootstrap": self.settings,
            "groups": self.groups,
            "reference": self.reference,
            "summary": [{"window": w, "group": g, "method": m, "metric": k, **iv}
                        for (w, g, m, k), iv in self.summary.items()],
            "paired": [{"window": w, "other": x, "group": g, "metric": k, **c}
                       for (w, x, g, k), c in self.paired.items()],
            "calibration_by_clip": [
                {"window": w, "clip": c, "n": self.clip_windows[(w, c)], "metric": k,
                 "mean": mean} for (w, c, k), mean in self.calibration.items()],
        }


def _end_counts(pairs: list[dict]) -> dict:
    """Pairs whose end postures A / B / either are themselves in self-collision."""
    ends = np.array([p.get("end_self_collision") or [False, False] for p in pairs],
                    dtype=bool).reshape(-1, 2)
    return {"A": int(ends[:, 0].sum()), "B": int(ends[:, 1].sum()),
            "either": int(ends.any(axis=1).sum())}


def _finite(values: np.ndarray) -> np.ndarray:
    return values[np.isfinite(values)]


def summarise(records: Records, metrics: Mapping, pairs: list[dict],
              real: Mapping[int, list[dict]], methods: Sequence[str],
              windows: Sequence[int], seed: int, reference: str = "upm") -> Summaries:
    """Every interval and comparison of a study.

    Parameters
    ----------
    records : eval.records.Records
        The per-unit table: ``pair`` rows of every method, ``real`` rows.
    metrics : dict of str to spec
        Its registry (specs with ``unit`` and ``better``), in table order.
    pairs : list of dict
        The pairs, sorted by id (``id``, ``ab_distance_deg``, ``seen``, ``flat_floor``,
        ``end_self_collision``).
    real : dict of int to list of dict
        Per window length, the real windows (``id``, ``clip``, ``flat_floor``).
    methods : sequence of str
    windows : sequence of int
    seed : int
    reference : str
        The method compared with every other (no comparisons if it was not run).

    Returns
    -------
    Summaries
    """
    groups, edges = pair_groups(pairs)
    ids = [p["id"] for p in pairs]
    methods = tuple(methods)
    reference = reference if reference in methods else None
    summary, paired, calibration, clip_windows = {}, {}, {}, {}
    for frames in windows:
        reals = real.get(frames, [])
        for group in SUMMARY_GROUPS:
            chosen = [i for i, keep in zip(ids, groups[group], strict=True) if keep]
            real_ids = [r["id"] for r in reals if group == "all" or r["flat_floor"]]
            for method in (*methods, REAL):
                kind, mine = (REAL, real_ids) if method == REAL else ("pair", chosen)
                for metric in metrics:
                    values = records.values(kind, frames, method, metric, mine)
                    summary[(frames, group, method, metric)] = bootstrap_mean(
                        _finite(values), seed).as_dict()
        for clip in sorted({r["clip"] for r in reals}):
            mine = [r["id"] for r in reals if r["clip"] == clip]
            clip_windows[(frames, clip)] = len(mine)
            for metric in metrics:
                values = _finite(records.values(REAL, frames, REAL, metric, mine))
                calibration[(frames, clip, metric)] = (round6(values.mean()) if values.size
                                                       else None)
        if reference is None:
            continue
        for other in (m for m in methods if m != reference):
            for group in GROUPS:
                chosen = [i for i, keep in zip(ids, groups[group], strict=True) if keep]
                for metric, spec in metrics.items():
                    a = records.values("pair", frames, reference, metric, chosen)
                    b = records.values("pair", frames, other, metric, chosen)
                    both = np.isfinite(a) & np.isfinite(b)
                    paired[(frames, other, group, metric)] = compare(
                        a[both], b[both], spec.better, seed).as_dict()
    return Summaries(
        metrics=dict(metrics), windows=tuple(int(w) for w in windows), methods=methods,
        reference=reference,
        settings={"resamples": RESAMPLES, "confidence": CONFIDENCE, "interval": "percentile",
                  "unit": "pair (or real window)", "seed": seed,
                  "tie": "equal values as stored (6 decimals)",
                  "missing": "a NaN figure (none for that unit) is left out; n counts the "
                             "units that have it"},
        groups={"pairs": {g: int(mask.sum()) for g, mask in groups.items()},
                "ab_tercile_edges_deg": edges, "end_self_collision": _end_counts(pairs)},
        summary=summary, paired=paired, calibration=calibration, clip_windows=clip_windows)
