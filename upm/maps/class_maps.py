"""What every posture map shares: four class maps, the key-posture query, save and load.

A posture map (the Uniform Posture Map of :mod:`upm.maps.posture_map`, or the classic Kohonen
SOM of :mod:`upm.maps.som`) holds one set of neurons per joint class (body, global, medium,
detail; :data:`upm.motion.skeleton.CLASS_SLICES`), each a ``(K_c, D_c)`` array of degrees in
``[-180, 180)``. The undeclared DOFs of the CMU skeleton (constant zeros) are kept: they
cost nothing in any distance and keep every neuron a full sub-vector of the posture.

**Key posture** (paper section 3.1) of postures A, B at ratio ``alpha``: per class,
``C = A + alpha * wrap(B - A)`` per DOF (the short way round; **alpha = 0 is A, alpha =
1 is B** -- the paper's code weights the other way round), then the neuron nearest to C
by wrapped distance; the four neurons joined. Nearest-neuron search is exact: the key
posture and :meth:`ClassMaps.nearest_neurons` search the four classes in one compiled
call (:mod:`upm.maps.torus_tree`), the other queries with :mod:`upm.maps.angular_search`.

**File** (``.npz``, read with ``allow_pickle=False``): ``format``, ``format_version``,
``kind`` ("upm" or "som"), the layout (``class_names``, ``class_slices``, ``dof_names``),
``neurons_<class>`` arrays, kind-specific arrays, and ``meta_json`` (parameters, per-class
statistics, training provenance: the clip names).
"""

from __future__ import annotations

import json
import os
from typing import ClassVar

import numpy as np

from upm.core.errors import DataFileError, UsageError
from upm.maps.angular_search import AngularIndex
from upm.maps.npz_file import (
    FILE_FORMAT,
    FORMAT_VERSION,
    check_meta,
    read_map_arrays,
    text_field,
    text_list,
)
from upm.motion.skeleton import CLASS_NAMES, CLASS_SLICES, POSTURE_DOF_NAMES, POSTURE_SIZE
from upm.ops.angles import wrap_deg


def check_postures(postures_deg, what: str = "postures") -> np.ndarray:
    """Postures as a float array ``(..., 63)``; UsageError if the shape or a value is bad."""
    try:
        p = np.asarray(postures_deg, dtype=float)
    except (TypeError, ValueError):
        raise UsageError(f"{what}: not an array of numbers") from None
    if p.ndim == 0 or p.shape[-1] != POSTURE_SIZE:
        raise UsageError(f"{what}: a posture has {POSTURE_SIZE} values (21 joints x rx, ry, "
                         f"rz, degrees); got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise UsageError(f"{what}: NaN or infinite angle")
    return p


def check_alpha(alpha) -> np.ndarray:
    """The ratio(s) alpha as a float array; UsageError if NaN or outside [0, 1]."""
    if type(alpha) is float and 0.0 <= alpha <= 1.0:  # the common case, without numpy's
        return np.asarray(alpha)                      # per-call overhead (NaN fails here)
    try:
        a = np.asarray(alpha, dtype=float)
    except (TypeError, ValueError):
        raise UsageError(f"alpha must be a number in [0, 1], not {alpha!r}") from None
    if np.any(np.isnan(a)):
        raise UsageError("alpha is NaN: it must be a number in [0, 1]")
    if np.any((a < 0.0) | (a > 1.0)):
        bad = a[(a < 0.0) | (a > 1.0)].flat[0]
        raise UsageError(f"alpha must be in [0, 1] (0 is A, 1 is B), not {bad:g}")
    return a


def off_data_share(neurons_deg, samples_deg, tolerance_deg: float) -> float:
    """Share of neurons farther than ``tolerance_deg`` from every sample (wrapped).

    The paper's central measure: a neuron far from every real posture is a posture the
    map may propose that the body never took ("a neuron in the hole").

    Parameters
    ----------
    neurons_deg : array_like, shape (K, D)
    samples_deg : array_like, shape (N, D)
    tolerance_deg : float
    """
    _, dist_sq = AngularIndex(samples_deg).nearest(neurons_deg)
    return float(np.mean(dist_sq > float(tolerance_deg) ** 2))


def nearest_distance_deg(points_deg, neurons_deg) -> np.ndarray:
    """Wrapped distance from each point ``(N, D)`` to its nearest neuron ``(K, D)``."""
    _, dist_sq = AngularIndex(neurons_deg).nearest(points_deg)
    return np.sqrt(dist_sq)


def postures_of_clips(catalog, names, step: int = 1) -> tuple[np.ndarray, list[str]]:
    """Every ``step``-th frame of the named clips, wrapped: ``(N, 63)`` degrees, and the
    names.

    Clips are read at their catalogue rate; for a posture map the rate only changes how
    densely a motion is sampled, not which postures are in the data.
    """
    from upm.core.progress import progress

    names = list(names)
    if not names:
        raise UsageError("no training clips selected")
    frames = [catalog.load(n).posture_deg[::step]
              for n in progress(names, desc="reading clips", unit="clip")]
    return wrap_deg(np.concatenate(frames)), names


class ClassMaps:
    """Four class maps of neurons with the key-posture query; see the module docstring.

    Subclasses set :attr:`kind`, implement ``fit`` and may add arrays to the file through
    :meth:`_extra_arrays` / :meth:`_restore_extra`.

    Attributes
    ----------
    neurons : dict of str to ndarray
        Per class name, the neurons ``(K_c, D_c)`` in degrees, in ``[-180, 180)``.
    params : dict
        The training parameters (JSON-serialisable).
    stats : dict
        Per class name: ``neurons``, ``quantisation_error_mean_deg``,
        ``quantisation_error_max_deg`` (training samples to nearest neuron), and more.
    provenance : dict
        ``clip_names`` (list of str), ``n_samples``, ``train_seconds``.
    """

    kind: ClassVar[str] = ""

    def __init__(self):
        self.neurons: dict[str, np.ndarray] = {}
        self.params: dict = {}
        self.stats: dict = {}
        self.provenance: dict = {}
        self._indexes: dict[str, AngularIndex] = {}
        self._forest = None

    # -- queries -------------------------------------------------------------------
    @property
    def is_fitted(self) -> bool:
        return all(c in self.neurons for c in CLASS_NAMES)

    def _require_fitted(self) -> None:
        if not self.is_fitted:
            raise UsageError(f"this {type(self).__name__} is not trained: call fit() or load()")

    def index(self, class_name: str) -> AngularIndex:
        """The search index of one class's neurons (built on first use)."""
        self._require_fitted()
        if class_name not in self._indexes:
            self._indexes[class_name] = AngularIndex(self.neurons[class_name])
        return self._indexes[class_name]

    def forest(self):
        """The four classes' neurons in one exact search (:class:`upm.maps.torus_tree.TorusForest`,
        built on first use)."""
        from upm.maps.torus_tree import TorusForest

        self._require_fitted()
        if self._forest is None:
            self._forest = TorusForest([self.neurons[c] for c in CLASS_NAMES],
                                       [CLASS_SLICES[c] for c in CLASS_NAMES])
        return self._forest

    def n_neurons(self) -> dict[str, int]:
        """Neurons per class."""
        return {c: len(self.neurons[c]) for c in CLASS_NAMES if c in self.neurons}

    def nearest_neurons(self, postures_deg) -> np.ndarray:
        """Each class sub-vector of each posture replaced by its nearest neuron.

        Parameters
        ----------
        postures_deg : array_like, shape (..., 63)

        Returns
        -------
        ndarray, shape (..., 63)
            Degrees in [-180, 180); each class sub-vector is exactly a neuron.
        """
        self._require_fitted()
        p = check_postures(postures_deg)
        _, _, out = self.forest().nearest(wrap_deg(p.reshape(-1, POSTURE_SIZE)))
        return out.reshape(p.shape)

    def key_posture(self, a_deg, b_deg, alpha=0.5) -> np.ndarray:
        """The key (intermediate) posture of A and B at ratio ``alpha`` (paper 3.1).

        Parameters
        ----------
        a_deg, b_deg : array_like, shape (63,) or (N, 63)
            Postures in degrees (any range; differences are wrapped).
        alpha : float or array_like, shape (N,) or broadcastable
            0 is A, 1 is B. Broadcast with the postures' leading shape, so one pair with
            many alphas, many pairs with one alpha, or pairs and alphas one to one.

        Returns
        -------
        ndarray, shape (63,) or (N, 63)
            Degrees in [-180, 180); per class, the neuron nearest to the point at
            ``alpha`` on A->B the short way round.

        Raises
        ------
        UsageError
            A posture of the wrong length or with NaN, alpha NaN or outside [0, 1],
            shapes that do not broadcast, or an untrained map.
        """
        self._require_fitted()
        a = check_postures(a_deg, "posture A")
        b = check_postures(b_deg, "posture B")
        t = check_alpha(alpha)
        try:
            lead = np.broadcast_shapes(a.shape[:-1], b.shape[:-1], t.shape)
        except ValueError:
            raise UsageError(f"shapes do not broadcast: A {a.shape}, B {b.shape}, "
                             f"alpha {t.shape}") from None
        shape = lead + (POSTURE_SIZE,)
        if a.shape == b.shape == shape and t.ndim == 0:  # one pair or pairs, one alpha
            out = self.forest().key_postures(
                np.ascontiguousarray(a.reshape(-1, POSTURE_SIZE)),
                np.ascontiguousarray(b.reshape(-1, POSTURE_SIZE)),
                np.full(a.size // POSTURE_SIZE, float(t)))
            return out.reshape(shape)
        out = self.forest().key_postures(
            np.ascontiguousarray(np.broadcast_to(a, shape).reshape(-1, POSTURE_SIZE)),
            np.ascontiguousarray(np.broadcast_to(b, shape).reshape(-1, POSTURE_SIZE)),
            np.ascontiguousarray(np.broadcast_to(t, lead).reshape(-1)))
        return out.reshape(shape)

    def quantisation_error(self, postures_deg) -> dict[str, dict[str, float]]:
        """Per class, the mean and largest wrapped distance (degrees) from the given
        postures' sub-vectors to their nearest neuron."""
        self._require_fitted()
        p = check_postures(postures_deg).reshape(-1, POSTURE_SIZE)
        out = {}
        for c in CLASS_NAMES:
            _, sq = self.index(c).nearest(p[:, CLASS_SLICES[c]])
            d = np.sqrt(sq)
            out[c] = {"mean_deg": float(d.mean()), "max_deg": float(d.max())}
        return out

    # -- training helpers ------------------------------------------------------------
    def _set_trained(self, neurons: dict[str, np.ndarray], postures: np.ndarray,
                     clip_names, seconds: float, class_stats: dict,
                     errors: dict | None = None) -> None:
        """Keep trained neurons; ``errors`` (per class: mean and largest distance of the
        postures to the wrapped neurons) when the training measured them already."""
        self.neurons = {c: np.ascontiguousarray(wrap_deg(neurons[c])) for c in CLASS_NAMES}
        self._indexes, self._forest = {}, None
        if errors is None:
            error = self.quantisation_error(postures)
        else:
            error = {c: {"mean_deg": errors[c][0], "max_deg": errors[c][1]}
                     for c in CLASS_NAMES}
        self.stats = {
            c: {"neurons": len(self.neurons[c]),
                "quantisation_error_mean_deg": error[c]["mean_deg"],
                "quantisation_error_max_deg": error[c]["max_deg"],
                **class_stats.get(c, {})}
            for c in CLASS_NAMES
        }
        self.provenance = {
            "clip_names": [str(n) for n in clip_names] if clip_names is not None else [],
            "n_samples": int(len(postures)),
            "train_seconds": float(seconds),
        }

    @staticmethod
    def _training_postures(postures_deg) -> np.ndarray:
        p = check_postures(postures_deg, "training postures")
        if p.ndim != 2 or len(p) == 0:
            raise UsageError(f"training postures: expected shape (N, {POSTURE_SIZE}) with "
                             f"N >= 1, got {p.shape}")
        return wrap_deg(p)

    # -- file ----------------------------------------------------------------------
    def _extra_arrays(self) -> dict[str, np.ndarray]:
        return {}

    def _restore_extra(self, arrays, path) -> None:
        return None

    def save(self, path: str | os.PathLike) -> None:
        """Write the map to ``path`` (``.npz``), atomically."""
        from upm.core.fileio import atomic_open

        self._require_fitted()
        arrays = {
            "format": np.array(FILE_FORMAT),
            "format_version": np.array(FORMAT_VERSION, dtype=np.int64),
            "kind": np.array(self.kind),
            "class_names": np.array(CLASS_NAMES),
            "class_slices": np.array([[CLASS_SLICES[c].start, CLASS_SLICES[c].stop]
                                      for c in CLASS_NAMES], dtype=np.int64),
            "dof_names": np.array(POSTURE_DOF_NAMES),
            "meta_json": np.array(json.dumps({"params": self.params, "stats": self.stats,
                                              "provenance": self.provenance})),
        }
        for c in CLASS_NAMES:
            arrays[f"neurons_{c}"] = self.neurons[c]
        arrays.update(self._extra_arrays())
        with atomic_open(path, "wb") as handle:
            np.savez_compressed(handle, **arrays)

    @classmethod
    def load(cls, path: str | os.PathLike):
        """Read a map saved by :meth:`save` (DataFileError if the file is not one, or
        is of another kind, version or joint layout)."""
        arrays = read_map_arrays(path)
        kind = text_field(arrays, "kind", path)
        if kind != cls.kind:
            raise DataFileError(path, f"holds a {kind!r} map, not a {cls.kind!r} map "
                                      f"(use upm.maps.load_map to read either)")
        return cls._from_arrays(arrays, path)

    @classmethod
    def _from_arrays(cls, arrays: dict, path):
        self = cls()
        self._restore(arrays, path)
        return self

    def _restore(self, arrays: dict, path) -> None:
        names = text_list(arrays, "class_names", path)
        slices = np.asarray(arrays["class_slices"])
        dofs = text_list(arrays, "dof_names", path)
        expected = np.array([[CLASS_SLICES[c].start, CLASS_SLICES[c].stop] for c in CLASS_NAMES])
        if (names != CLASS_NAMES or slices.shape != expected.shape
                or not np.array_equal(slices, expected) or dofs != POSTURE_DOF_NAMES):
            raise DataFileError(path, "its joint/class layout differs from this program's "
                                      "21-joint, 4-class posture")
        try:
            meta = json.loads(text_field(arrays, "meta_json", path))
            self.params = dict(meta["params"])
            self.stats = dict(meta["stats"])
            self.provenance = dict(meta["provenance"])
        except (ValueError, KeyError, TypeError):
            raise DataFileError(path, "corrupt metadata (meta_json)") from None
        check_meta(self.stats, self.provenance, path)
        neurons = {}
        for c in CLASS_NAMES:
            key = f"neurons_{c}"
            if key not in arrays:
                raise DataFileError(path, f"missing array {key}")
            w = arrays[key]
            width = CLASS_SLICES[c].stop - CLASS_SLICES[c].start
            if (w.ndim != 2 or w.shape[1] != width or len(w) == 0
                    or not np.issubdtype(w.dtype, np.floating)):
                raise DataFileError(path, f"{key} must be a non-empty (K, {width}) float "
                                          f"array, not {w.dtype} {w.shape}")
            if not np.all(np.isfinite(w)):
                raise DataFileError(path, f"{key} holds NaN or infinite values")
            neurons[c] = np.ascontiguousarray(w, dtype=float)
        self.neurons = neurons
        self._indexes, self._forest = {}, None
        self._restore_extra(arrays, path)
