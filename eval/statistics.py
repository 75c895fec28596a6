"""Statistics of the study: bootstrap intervals of means, paired comparisons of UPM with
every other method, and the same split by how far apart the end postures are, by whether
the clips' subjects were seen in training and by whether the floor is flat.

- **Interval**: the 95 % percentile bootstrap interval of the mean, from
  :data:`RESAMPLES` resamples of the pairs (or real windows) with replacement. The
  resamples come from a generator seeded with the study's seed and the sample size, so
  every method and metric with the same pairs is resampled alike (paired) and the numbers
  are reproducible.
- **Paired comparison** UPM - X: per pair the difference of the two methods' values; its
  mean and bootstrap interval, and how many pairs UPM wins, ties and loses. *Win* is the
  better side of the metric (higher valid share, lower everything else); a *tie* is an
  equal value as stored (6 decimals) — e.g. both windows fully valid, or both adding no
  limit excess.
- **Groups** (:func:`pair_groups`): ``all``; ``ab_near`` / ``ab_middle`` / ``ab_far``
  (terciles of the A-B distance, deg RMS over the declared DOFs); ``seen`` (both clips'
  subjects have clips in the train split) / ``unseen``; ``flat_floor`` (both clips
  flat-floor, :mod:`eval.realdata`) / ``uneven_floor``.

:mod:`eval.summaries` applies them to a study's long-form table.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Bootstrap resamples per interval.
RESAMPLES = 2000
#: Coverage of the intervals.
CONFIDENCE = 0.95
_BOOTSTRAP_STREAM = 3
#: The groups of pairs every comparison is also made on.
GROUPS = ("all", "ab_near", "ab_middle", "ab_far", "seen", "unseen", "flat_floor",
          "uneven_floor")


@dataclass(frozen=True)
class Interval:
    """A mean and its bootstrap interval.

    Attributes
    ----------
    mean, lo, hi : float
        NaN when ``n`` is 0.
    n : int
    """

    mean: float
    lo: float
    hi: float
    n: int

    def as_dict(self) -> dict:
        return {"mean": round6(self.mean), "lo": round6(self.lo), "hi": round6(self.hi),
                "n": self.n}


def round6(x: float):
    """``x`` rounded to 6 decimals, None when it is not finite (JSON has no NaN)."""
    return None if not np.isfinite(x) else round(float(x), 6)


def resample_indices(n: int, seed: int, resamples: int = RESAMPLES) -> np.ndarray:
    """Bootstrap resamples of ``n`` items, (resamples, n) indices; the same for the same
    ``n`` and ``seed``."""
    rng = np.random.default_rng([seed, _BOOTSTRAP_STREAM, n])
    return rng.integers(0, n, size=(resamples, n))


def bootstrap_mean(values, seed: int, resamples: int = RESAMPLES,
                   confidence: float = CONFIDENCE) -> Interval:
    """The mean of ``values`` (N,) and its percentile bootstrap interval."""
    v = np.asarray(values, dtype=float)
    n = v.size
    if n == 0:
        return Interval(np.nan, np.nan, np.nan, 0)
    means = v[resample_indices(n, seed, resamples)].mean(axis=1)
    tail = 100.0 * (1.0 - confidence) / 2.0
    lo, hi = np.percentile(means, [tail, 100.0 - tail])
    return Interval(float(v.mean()), float(lo), float(hi), n)


@dataclass(frozen=True)
class Comparison:
    """UPM - X on one metric over some pairs.

    Attributes
    ----------
    difference : Interval
        Mean of the per-pair differences and its interval.
    wins, ties, losses : int
        Pairs where UPM is better, equal, worse.
    """

    difference: Interval
    wins: int
    ties: int
    losses: int

    def as_dict(self) -> dict:
        d = self.difference.as_dict()
        return {"mean_diff": d["mean"], "lo": d["lo"], "hi": d["hi"], "n": d["n"],
                "wins": self.wins, "ties": self.ties, "losses": self.losses}


def compare(upm_values, other_values, better: str, seed: int) -> Comparison:
    """UPM - X per pair (arrays (N,) in the same pair order)."""
    a = np.asarray(upm_values, dtype=float)
    b = np.asarray(other_values, dtype=float)
    diff = a - b
    sign = 1.0 if better == "higher" else -1.0
    equal = a == b
    wins = int(np.sum(~equal & (sign * diff > 0)))
    losses = int(np.sum(~equal & (sign * diff < 0)))
    return Comparison(bootstrap_mean(diff, seed), wins, int(equal.sum()), losses)


def tercile_edges(values) -> np.ndarray:
    """The 1/3 and 2/3 quantiles of ``values`` (N,): the tercile cut points, (2,)."""
    return np.quantile(np.asarray(values, dtype=float), [1.0 / 3.0, 2.0 / 3.0])


def pair_groups(pairs: list[dict]) -> tuple[dict[str, np.ndarray], list[float]]:
    """Which pairs fall in each group of :data:`GROUPS`.

    Parameters
    ----------
    pairs : list of dict
        Pair records (``ab_distance_deg``, ``seen``, ``flat_floor``).

    Returns
    -------
    groups : dict of str to ndarray of bool, shape (N,)
    edges : list of float
        The A-B distance tercile cut points, degrees.
    """
    ab = np.array([p["ab_distance_deg"] for p in pairs], dtype=float)
    seen = np.array([p["seen"] for p in pairs], dtype=bool)
    flat = np.array([p["flat_floor"] for p in pairs], dtype=bool)
    edges = tercile_edges(ab) if ab.size else np.array([np.nan, np.nan])
    tercile = np.searchsorted(edges, ab, side="right")
    groups = {"all": np.ones(ab.size, dtype=bool), "ab_near": tercile == 0,
              "ab_middle": tercile == 1, "ab_far": tercile == 2, "seen": seen,
              "unseen": ~seen, "flat_floor": flat, "uneven_floor": ~flat}
    return groups, [round6(e) for e in edges]


