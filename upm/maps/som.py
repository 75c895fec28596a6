"""The classic fixed-grid Kohonen self-organising map: the paper's foil.

One map per joint class, trained on the same class sub-vectors as the UPM and queried
with the same key-posture rule (:class:`upm.maps.class_maps.ClassMaps`), so that the two
differ only in how the neurons were placed.

Per class, a rectangular ``rows x cols`` grid of neurons is trained with Kohonen's
*batch map* (Kohonen 2001, ch. 3.14; the SOM Toolbox's default): every epoch, each
sample's winner is its nearest neuron (exact, wrapped distance), and every neuron
becomes the Gaussian-weighted mean, over the grid neighbourhood of the winners, of the
samples -- for angles, the weighted **circular mean** (``atan2`` of the weighted sums of
sines and cosines), so wrap-around is handled exactly. The neighbourhood width ``sigma``
shrinks exponentially from ``max(rows, cols) / 4`` to 1 grid unit.

Defaults follow the SOM Toolbox: ``5 N^0.54321`` neurons, the grid's side ratio the
square root of the ratio of the two largest principal variances, and a linear
initialisation along the two principal axes of the wrapped deviations from the circular
mean. Libraries such as MiniSom subtract angles without wrapping, hence this module.

Neurons tied to their grid neighbours are pulled across any gap in the data: on a
non-convex set (an annulus, a bent elbow) some end where no sample is -- the paper's
objection to the SOM, measured by :func:`upm.maps.class_maps.off_data_share`.
"""

from __future__ import annotations

import time

import numpy as np

from upm.core.errors import DataFileError, UsageError
from upm.maps.angular_search import AngularIndex
from upm.maps.class_maps import ClassMaps
from upm.maps.map_size import sketch_size
from upm.motion.skeleton import CLASS_NAMES, CLASS_SLICES
from upm.ops.angles import angle_diff_deg, wrap_deg


def circular_mean_deg(x_deg, axis: int = 0) -> np.ndarray:
    """Per-DOF circular mean (degrees, in [-180, 180))."""
    rad = np.deg2rad(np.asarray(x_deg, dtype=float))
    return wrap_deg(np.rad2deg(np.arctan2(np.sin(rad).mean(axis), np.cos(rad).mean(axis))))


def _principal_axes(x_deg):
    """Circular mean, and the two largest principal variances and axes of the wrapped
    deviations from it."""
    mean = circular_mean_deg(x_deg)
    dev = angle_diff_deg(x_deg, mean)
    cov = np.atleast_2d(np.cov(dev, rowvar=False)) if len(dev) > 1 else np.zeros(
        (dev.shape[1], dev.shape[1]))
    values, vectors = np.linalg.eigh(cov)
    order = np.argsort(values)[::-1][:2]
    values = np.maximum(values[order], 0.0)
    vectors = vectors[:, order]
    if len(values) < 2:  # a 1-D class: the second axis is empty
        values = np.append(values, 0.0)
        vectors = np.column_stack([vectors, np.zeros(len(vectors))])
    return mean, values, vectors


def default_grid(samples_deg) -> tuple[int, int]:
    """The SOM Toolbox's grid for these samples: ``5 N^0.54321`` neurons, sides in the
    ratio of the two largest principal standard deviations."""
    x = np.asarray(samples_deg, dtype=float)
    units = max(2, sketch_size(len(x)))
    _, values, _ = _principal_axes(x)
    ratio = np.sqrt(values[0] / values[1]) if values[1] > 0 else float(units)
    rows = max(1, int(round(np.sqrt(units / ratio))))
    cols = max(1, int(round(units / rows)))
    return rows, cols


def grid_coordinates(rows: int, cols: int) -> np.ndarray:
    """Grid position of each neuron, row-major, shape (rows * cols, 2)."""
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    return np.column_stack([r.ravel(), c.ravel()]).astype(float)


def train_som_class(samples_deg, grid: tuple[int, int], epochs: int = 10,
                    sigma_start: float | None = None, sigma_end: float = 1.0,
                    init: str = "pca", seed: int = 0, desc: str | None = None,
                    ) -> np.ndarray:
    """Train one class map of the batch SOM (see the module docstring).

    Parameters
    ----------
    samples_deg : array_like, shape (N, D)
    grid : (rows, cols)
    epochs : int
    sigma_start : float, optional
        Initial neighbourhood width in grid units; default ``max(rows, cols) / 4``.
    sigma_end : float
        Final width.
    init : {"pca", "random"}
        Linear along the two principal axes, or seeded random samples.
    seed : int
    desc : str, optional
        Label of a progress bar.

    Returns
    -------
    ndarray, shape (rows * cols, D)
        Neurons in degrees, in [-180, 180), row-major over the grid.
    """
    from upm.core.progress import progress

    x = wrap_deg(np.asarray(samples_deg, dtype=float))
    rows, cols = int(grid[0]), int(grid[1])
    if rows < 1 or cols < 1:
        raise UsageError(f"a SOM grid needs at least 1 x 1 neurons, not {rows} x {cols}")
    coords = grid_coordinates(rows, cols)
    if init == "pca":
        mean, values, vectors = _principal_axes(x)
        # Spread the grid over +-2 standard deviations along each principal axis.
        u = np.linspace(-1.0, 1.0, rows) if rows > 1 else np.zeros(1)
        v = np.linspace(-1.0, 1.0, cols) if cols > 1 else np.zeros(1)
        uu, vv = np.meshgrid(u, v, indexing="ij")
        spread = 2.0 * np.sqrt(values)
        weights = wrap_deg(mean + uu.ravel()[:, None] * spread[0] * vectors[:, 0]
                           + vv.ravel()[:, None] * spread[1] * vectors[:, 1])
    elif init == "random":
        rng = np.random.default_rng(seed)
        weights = x[rng.choice(len(x), rows * cols, replace=len(x) < rows * cols)].copy()
    else:
        raise UsageError(f"unknown SOM init {init!r} (known: pca, random)")
    sigma0 = float(sigma_start) if sigma_start else max(rows, cols) / 4.0
    sigma0 = max(sigma0, sigma_end)
    grid_sq = ((coords[:, None, :] - coords[None, :, :]) ** 2).sum(-1)
    rad = np.deg2rad(x)
    cos_x, sin_x = np.cos(rad), np.sin(rad)
    for e in progress(range(epochs), desc=desc, unit="epoch", disable=None if desc else True):
        sigma = sigma0 * (sigma_end / sigma0) ** (e / max(1, epochs - 1))
        winner, _ = AngularIndex(weights).nearest(x)
        # Per-winner sums of the unit vectors, then the grid-neighbourhood mix of them.
        sum_cos = np.zeros_like(weights)
        sum_sin = np.zeros_like(weights)
        np.add.at(sum_cos, winner, cos_x)
        np.add.at(sum_sin, winner, sin_x)
        count = np.bincount(winner, minlength=len(weights)).astype(float)
        h = np.exp(-grid_sq / (2.0 * sigma * sigma))
        mass = h @ count
        mix_cos, mix_sin = h @ sum_cos, h @ sum_sin
        alive = mass > 1e-12 * max(1.0, mass.max())
        new = np.rad2deg(np.arctan2(mix_sin, mix_cos))
        weights = np.where(alive[:, None], wrap_deg(new), weights)
    return weights


class KohonenSOM(ClassMaps):
    """The classic fixed-grid Kohonen SOM, one per class, with the UPM's key-posture query.

    Parameters
    ----------
    grid : (rows, cols) or dict of class -> (rows, cols), optional
        Default per class: :func:`default_grid` (SOM Toolbox rule).
    epochs : int
        Batch-map epochs.
    sigma_start, sigma_end : float
        Neighbourhood width in grid units (default start ``max(rows, cols) / 4``, end 1).
    init : {"pca", "random"}
    seed : int
    progress : bool
        A progress bar per class.
    """

    kind = "som"

    def __init__(self, grid=None, epochs: int = 10, sigma_start: float | None = None,
                 sigma_end: float = 1.0, init: str = "pca", seed: int = 0,
                 progress: bool = False):
        super().__init__()
        if int(epochs) < 1:
            raise UsageError(f"epochs must be at least 1, not {epochs}")
        if init not in ("pca", "random"):
            raise UsageError(f"unknown SOM init {init!r} (known: pca, random)")
        self._grid = self._grid_per_class(grid)
        self.params = {"grid": {c: (list(g) if g else None) for c, g in self._grid.items()},
                       "epochs": int(epochs), "sigma_start": sigma_start,
                       "sigma_end": float(sigma_end), "init": init, "seed": int(seed)}
        self.show_progress = progress
        self.grids: dict[str, tuple[int, int]] = {}

    @staticmethod
    def _grid_per_class(grid) -> dict:
        if grid is None:
            return {c: None for c in CLASS_NAMES}
        if isinstance(grid, dict):
            unknown = set(grid) - set(CLASS_NAMES)
            if unknown:
                raise UsageError(f"grid: unknown class {sorted(unknown)[0]!r}")
            return {c: (tuple(int(v) for v in grid[c]) if grid.get(c) else None)
                    for c in CLASS_NAMES}
        try:
            rows, cols = (int(v) for v in grid)
        except (TypeError, ValueError):
            raise UsageError(f"grid must be (rows, cols), not {grid!r}") from None
        if rows < 1 or cols < 1:
            raise UsageError(f"grid must have at least 1 x 1 neurons, not {rows} x {cols}")
        return {c: (rows, cols) for c in CLASS_NAMES}

    def fit(self, postures_deg, clip_names=None) -> KohonenSOM:
        """Train the four class SOMs on postures ``(N, 63)``; returns ``self``."""
        x = self._training_postures(postures_deg)
        p = self.params
        start_s = time.perf_counter()
        neurons, class_stats = {}, {}
        for c in CLASS_NAMES:
            sub = x[:, CLASS_SLICES[c]]
            grid = self._grid[c] or default_grid(sub)
            t0 = time.perf_counter()
            neurons[c] = train_som_class(
                sub, grid, epochs=p["epochs"], sigma_start=p["sigma_start"],
                sigma_end=p["sigma_end"], init=p["init"], seed=p["seed"],
                desc=f"SOM {c}" if self.show_progress else None)
            self.grids[c] = (int(grid[0]), int(grid[1]))
            class_stats[c] = {"grid": list(self.grids[c]),
                              "train_seconds": time.perf_counter() - t0}
        p["grid"] = {c: list(g) for c, g in self.grids.items()}
        self._set_trained(neurons, x, clip_names, time.perf_counter() - start_s, class_stats)
        return self

    def _extra_arrays(self) -> dict[str, np.ndarray]:
        return {f"grid_{c}": np.array(self.grids[c], dtype=np.int64) for c in CLASS_NAMES}

    def _restore_extra(self, arrays, path) -> None:
        self.grids = {}
        for c in CLASS_NAMES:
            g = arrays.get(f"grid_{c}")
            if g is None or g.shape != (2,) or g.dtype.kind not in "iu":
                raise DataFileError(path, f"missing or bad grid_{c} (rows, cols)")
            rows, cols = int(g[0]), int(g[1])
            if rows * cols != len(self.neurons[c]):
                raise DataFileError(path, f"grid_{c} is {rows} x {cols} but the class has "
                                          f"{len(self.neurons[c])} neurons")
            self.grids[c] = (rows, cols)
        self._grid = dict(self.grids)
