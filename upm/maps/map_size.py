"""How big a posture map is by default: the SOM Toolbox's map size and the UPM's data-driven
radius ``R`` (see :mod:`upm.maps.posture_map`), shared by the UPM, its training and the SOM."""

from __future__ import annotations

import numpy as np

from upm.maps.torus_tree import nearest_neuron

#: Quantile of sample-to-sketch distances taken as the default R.
RADIUS_QUANTILE = 0.9


def sketch_size(n_samples: int) -> int:
    """The SOM Toolbox's map size for ``n_samples`` samples: ``5 N^0.54321``."""
    return int(min(n_samples, max(1, round(5.0 * n_samples ** 0.54321))))


def default_radius_deg(samples_deg, seed: int = 0) -> float:
    """The data-driven default ``R`` of one class (see the module docstring).

    Parameters
    ----------
    samples_deg : array_like, shape (N, D)
    seed : int

    Returns
    -------
    float
        Degrees (wrapped distance); at least 1e-6.
    """
    x = np.asarray(samples_deg, dtype=float)
    rng = np.random.default_rng(seed)
    sketch = x[rng.choice(len(x), sketch_size(len(x)), replace=False)]
    _, dist_sq = nearest_neuron(x, sketch)
    return max(float(np.sqrt(np.quantile(dist_sq, RADIUS_QUANTILE))), 1e-6)
