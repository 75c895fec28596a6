"""The Uniform Posture Map (Lee & Chung 2001, section 2.3): one growing map per class.

Per joint class (body, global, medium, detail) a map of neurons is trained on the class
sub-vectors of real postures (:func:`upm.maps.upm_training.train_upm_class`): a sample
farther than ``R`` from every neuron becomes a neuron; otherwise the winner and its
neighbours -- the neurons within the current neighbourhood radius of the winner, by
wrapped distance in weight space -- move toward it by ``eta * wrap(x - W)``; ``eta`` and
the neighbourhood shrink linearly over the passes, down to a closing pass at ``eta = 0``
that only adds neurons. No neuron is ever placed by a grid: neurons are born at real
postures and only move toward real postures within their reach, which is why the map
has no neurons in the holes of a non-convex set of postures (the paper's claim against
the Kohonen SOM, :mod:`upm.maps.som`).

Defaults, so that ``upm train`` needs no tuning:

- ``R`` per class (:func:`default_radius_deg`): the 90th percentile of the distance from
  each training sample to the nearest of a seeded random sketch of
  ``m = 5 N^0.54321`` samples (the SOM Toolbox's rule for the size of a map, which the
  SOM here also uses). A sketch of ``m`` real postures then covers 90 % of the samples
  within ``R``; the map ends with about ``m`` neurons per class, whatever the units or
  spread of the class.
- neighbourhood radius: ``R`` (the neurons whose cells touch the winner's), shrinking
  to 0 with ``eta``; ``eta`` from 0.1; 5 passes plus the closing pass.

Every parameter can be overridden. Training is deterministic for a seed.
"""

from __future__ import annotations

import time

import numpy as np

from upm.core.errors import DataFileError, UsageError
from upm.maps.class_maps import ClassMaps
from upm.maps.map_size import default_radius_deg
from upm.maps.upm_training import train_upm_classes
from upm.motion.skeleton import CLASS_NAMES, CLASS_SLICES

__all__ = ["UniformPostureMap", "default_radius_deg"]

def _per_class(value, name: str, allow_zero: bool = False) -> dict:
    """A float, a per-class dict, or None -> a dict over every class (None kept)."""
    if value is None or isinstance(value, (int, float)):
        per_class = {c: value for c in CLASS_NAMES}
    elif isinstance(value, dict):
        unknown = set(value) - set(CLASS_NAMES)
        if unknown:
            raise UsageError(f"{name}: unknown class {sorted(unknown)[0]!r} "
                             f"(classes: {', '.join(CLASS_NAMES)})")
        per_class = {c: value.get(c) for c in CLASS_NAMES}
    else:
        raise UsageError(f"{name} must be a number or a dict of class -> number, "
                         f"not {value!r}")
    out = {}
    for c, v in per_class.items():
        if v is None:
            out[c] = None
            continue
        try:
            v = float(v)
        except (TypeError, ValueError):
            raise UsageError(f"{name}[{c}] must be a number, not {v!r}") from None
        if not (v >= 0.0 if allow_zero else v > 0.0) or not np.isfinite(v):
            raise UsageError(f"{name}[{c}] must be {'>= 0' if allow_zero else '> 0'} and "
                             f"finite, not {v}")
        out[c] = v
    return out


class UniformPostureMap(ClassMaps):
    """The UPM: four growing class maps and the key-posture query.

    Parameters
    ----------
    radius_deg : float or dict of class -> float, optional
        ``R`` (the largest distance at which a sample joins an existing neuron);
        default per class: :func:`default_radius_deg`.
    neighbourhood_deg : float or dict, optional
        Initial neighbourhood radius; default per class: that class's ``R``.
    learning_rate : float
        ``eta`` of the first pass, in (0, 1).
    passes : int
        Passes with ``eta > 0`` (a closing pass at ``eta = 0`` follows).
    batch_size : int
        Samples per vectorised step; 1 is the paper's sequential algorithm exactly.
    seed : int
        Seeds the default ``R`` sketch and the per-pass shuffle.
    shuffle : bool
        A new seeded sample order each pass (else the given order).
    progress : bool
        A progress bar over the classes on stderr (when it is a terminal).
    workers : int, optional
        Processes training the four classes at once (default: the usable CPUs; 1 trains
        them in order). The neurons do not depend on it.

    Examples
    --------
    >>> upm = UniformPostureMap().fit(postures_deg, clip_names=names)  # doctest: +SKIP
    >>> key = upm.key_posture(a_deg, b_deg, alpha=0.5)                  # doctest: +SKIP
    """

    kind = "upm"

    def __init__(self, radius_deg=None, neighbourhood_deg=None, learning_rate: float = 0.1,
                 passes: int = 5, batch_size: int = 512, seed: int = 0, shuffle: bool = True,
                 progress: bool = False, workers: int | None = None):
        super().__init__()
        if not 0.0 < learning_rate < 1.0:
            raise UsageError(f"learning_rate must be in (0, 1), not {learning_rate}")
        if int(passes) < 1:
            raise UsageError(f"passes must be at least 1, not {passes}")
        if int(batch_size) < 1:
            raise UsageError(f"batch_size must be at least 1, not {batch_size}")
        self._radius = _per_class(radius_deg, "radius_deg")
        self._neighbourhood = _per_class(neighbourhood_deg, "neighbourhood_deg",
                                         allow_zero=True)
        self.params = {
            "learning_rate": float(learning_rate), "passes": int(passes),
            "batch_size": int(batch_size), "seed": int(seed), "shuffle": bool(shuffle),
            "radius_deg": dict(self._radius), "neighbourhood_deg": dict(self._neighbourhood),
        }
        self.show_progress = progress
        self.workers = workers

    @property
    def radius_deg(self) -> dict[str, float]:
        """``R`` per class (after training: the values used)."""
        return dict(self.params["radius_deg"])

    @property
    def neighbourhood_deg(self) -> dict[str, float]:
        """Initial neighbourhood radius per class (after training: the values used)."""
        return dict(self.params["neighbourhood_deg"])

    def fit(self, postures_deg, clip_names=None) -> UniformPostureMap:
        """Train the four class maps on postures ``(N, 63)`` (degrees, any range).

        ``clip_names`` (the clips the postures came from) is kept as provenance.
        Returns ``self``.
        """
        x = self._training_postures(postures_deg)
        p = self.params
        start_s = time.perf_counter()
        neurons, class_stats, errors = {}, {}, {}
        # The classes are independent: trained in parallel (default R, training and
        # quantisation error in each worker), identical neurons.
        jobs = {c: (x[:, CLASS_SLICES[c]], self._radius[c], self._neighbourhood[c], {
            "learning_rate": p["learning_rate"], "passes": p["passes"],
            "batch_size": p["batch_size"], "seed": p["seed"], "shuffle": p["shuffle"]})
            for c in CLASS_NAMES}
        results = train_upm_classes(jobs, workers=self.workers,
                                    desc="UPM classes" if self.show_progress else None)
        for c in CLASS_NAMES:
            result = results[c]
            neurons[c] = result.neurons_deg
            errors[c] = result.quantisation_error_deg
            class_stats[c] = {"radius_deg": result.radius_deg,
                              "neighbourhood_deg": result.neighbourhood_deg,
                              "births_per_pass": list(result.births_per_pass),
                              "train_seconds": result.seconds,
                              "train_cpu_seconds": result.cpu_seconds}
        p["radius_deg"] = {c: results[c].radius_deg for c in CLASS_NAMES}
        p["neighbourhood_deg"] = {c: results[c].neighbourhood_deg for c in CLASS_NAMES}
        self._set_trained(neurons, x, clip_names, time.perf_counter() - start_s, class_stats,
                          errors)
        return self

    def _restore_extra(self, arrays, path) -> None:
        try:
            self._radius = _per_class(self.params.get("radius_deg"), "radius_deg")
            self._neighbourhood = _per_class(self.params.get("neighbourhood_deg"),
                                             "neighbourhood_deg", allow_zero=True)
        except UsageError as exc:
            raise DataFileError(path, f"corrupt parameters: {exc}") from None
