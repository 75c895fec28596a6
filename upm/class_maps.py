"""What every posture map shares: four class maps, the key-posture query, save and load.

A posture map (the Uniform Posture Map of :mod:`upm.posture_map`, or the classic Kohonen
SOM of :mod:`upm.som`) holds one set of neurons per joint class (body, global, medium,
detail; :data:`upm.skeleton.CLASS_SLICES`), each a ``(K_c, D_c)`` array of degrees in
``[-180, 180)``. The undeclared DOFs of the CMU skeleton (constant zeros) are kept: they
cost nothing in any distance and keep every neuron a full sub-vector of the posture.

**Key posture** (paper section 3.1) of postures A, B at ratio ``alpha``: per class,
``C = A + alpha * wrap(B - A)`` per DOF (the short way round; **alpha = 0 is A, alpha =
1 is B** -- the paper's code weights the other way round), then the neuron nearest to C
by wrapped distance; the four neurons joined. Nearest-neuron search is exact: the key
posture and :meth:`ClassMaps.nearest_neurons` search the four classes in one compiled
call (:mod:`upm.torus_tree`), the other queries with :mod:`upm.angular_search`.

**File** (``.npz``, read with ``allow_pickle=False``): ``format``, ``format_version``,
``kind`` ("upm" or "som"), the layout (``class_names``, ``class_slices``, ``dof_names``),
``neurons_<class>`` arrays, kind-specific arrays, and ``meta_json`` (parameters, per-class
statistics, training provenance: the clip names).
"""

from __future__ import annotations

import json
import os
import tokenize
import zipfile
import zlib
from typing import ClassVar

import numpy as np

from upm.angles import wrap_deg
from upm.angular_search import AngularIndex
from upm.errors import DataFileError, UsageError
from upm.skeleton import CLASS_NAMES, CLASS_SLICES, POSTURE_DOF_NAMES, POSTURE_SIZE

FILE_FORMAT = "upm-controller/posture-map"
FORMAT_VERSION = 1
#: Map kinds by the ``kind`` field of a file: module and class.
MAP_KINDS: dict[str, tuple[str, str]] = {
    "upm": ("upm.posture_map", "UniformPostureMap"),
    "som": ("upm.som", "KohonenSOM"),
}


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
    from upm.progress import progress

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
        """The four classes' neurons in one exact search (:class:`upm.torus_tree.TorusForest`,
        built on first use)."""
        from upm.torus_tree import TorusForest

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
        from upm.fileio import atomic_open

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
        arrays = _read_npz(path)
        kind = _text(arrays, "kind", path)
        if kind != cls.kind:
            raise DataFileError(path, f"holds a {kind!r} map, not a {cls.kind!r} map "
                                      f"(use upm.posture_map.load_map to read either)")
        return cls._from_arrays(arrays, path)

    @classmethod
    def _from_arrays(cls, arrays: dict, path):
        self = cls()
        self._restore(arrays, path)
        return self

    def _restore(self, arrays: dict, path) -> None:
        names = _text_list(arrays, "class_names", path)
        slices = np.asarray(arrays["class_slices"])
        dofs = _text_list(arrays, "dof_names", path)
        expected = np.array([[CLASS_SLICES[c].start, CLASS_SLICES[c].stop] for c in CLASS_NAMES])
        if (names != CLASS_NAMES or slices.shape != expected.shape
                or not np.array_equal(slices, expected) or dofs != POSTURE_DOF_NAMES):
            raise DataFileError(path, "its joint/class layout differs from this program's "
                                      "21-joint, 4-class posture")
        try:
            meta = json.loads(_text(arrays, "meta_json", path))
            self.params = dict(meta["params"])
            self.stats = dict(meta["stats"])
            self.provenance = dict(meta["provenance"])
        except (ValueError, KeyError, TypeError):
            raise DataFileError(path, "corrupt metadata (meta_json)") from None
        _check_meta(self.stats, self.provenance, path)
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


#: Bounds on a map archive, checked from the zip directory before anything is
#: decompressed (a zip bomb is refused unread). A 2,000-neuron map is under 2 MB.
MAX_MEMBERS = 64
MAX_UNCOMPRESSED_BYTES = 1 << 30
MAX_COMPRESSION_RATIO = 200
#: What reading a damaged archive member can raise (zip, zlib, the .npy header).
_ARCHIVE_ERRORS = (OSError, ValueError, EOFError, KeyError, TypeError, SyntaxError,
                   RuntimeError, NotImplementedError, OverflowError, zipfile.BadZipFile,
                   zlib.error, tokenize.TokenError)


def _read_npz(path) -> dict:
    """Every array of a posture-map file, checked for format and version.

    The archive is read member by member with ``allow_pickle=False`` (an object array
    is refused, never unpickled), after its directory is checked against
    :data:`MAX_MEMBERS`, :data:`MAX_UNCOMPRESSED_BYTES` and
    :data:`MAX_COMPRESSION_RATIO`.
    """
    try:
        with open(path, "rb") as handle:
            magic = handle.read(4)
    except FileNotFoundError:
        raise DataFileError(path, "no such file") from None
    except OSError as exc:
        raise DataFileError(path, f"cannot read: {exc.strerror}") from None
    if magic != b"PK\x03\x04":  # every .npz is a zip archive
        raise DataFileError(path, "not a posture map: not an .npz (zip) archive "
                                  "(write one with 'upm train --out MAP.npz')")
    try:
        with zipfile.ZipFile(path) as archive:
            members = archive.infolist()
            _check_members(path, members)
            arrays = {}
            for info in members:
                with archive.open(info) as member:
                    arrays[info.filename[:-len(".npy")]] = np.lib.format.read_array(
                        member, allow_pickle=False)
    except DataFileError:
        raise
    except _ARCHIVE_ERRORS as exc:
        reason = " ".join(str(exc).split())[:200] or type(exc).__name__
        if "allow_pickle" in reason:
            reason = "it holds a Python object array, which is never unpickled"
        raise DataFileError(path, f"not a readable posture map (.npz): {reason}") from None
    if "format" not in arrays:
        raise DataFileError(path, "not a posture map file (no 'format' field)")
    if _text(arrays, "format", path) != FILE_FORMAT:
        raise DataFileError(path, f"not a posture map file (format "
                                  f"{_text(arrays, 'format', path)!r})")
    version = arrays.get("format_version")
    if version is None or version.shape != () or version.dtype.kind not in "iu":
        raise DataFileError(path, "no valid format_version")
    if int(version) != FORMAT_VERSION:
        raise DataFileError(path, f"format version {int(version)} is not supported (this "
                                  f"program reads version {FORMAT_VERSION}); train the map again")
    for key in ("kind", "class_names", "class_slices", "dof_names", "meta_json"):
        if key not in arrays:
            raise DataFileError(path, f"missing field {key}")
    return arrays


def _check_members(path, members) -> None:
    if len(members) > MAX_MEMBERS:
        raise DataFileError(path, f"not a posture map: {len(members)} archive members "
                                  f"(at most {MAX_MEMBERS})")
    total = 0
    for info in members:
        if not info.filename.endswith(".npy") or info.filename.count("/"):
            raise DataFileError(path, f"not a posture map: archive member {info.filename!r} "
                                      "is not an .npy array")
        total += info.file_size
        ratio = info.file_size / max(info.compress_size, 1)
        if total > MAX_UNCOMPRESSED_BYTES or ratio > MAX_COMPRESSION_RATIO:
            raise DataFileError(path, f"archive member {info.filename!r} would decompress to "
                                      f"{info.file_size} bytes (ratio {ratio:.0f}): refused "
                                      "unread as a possible zip bomb")


def _text_list(arrays: dict, key: str, path) -> tuple[str, ...]:
    value = arrays[key]
    if value.ndim != 1 or value.dtype.kind != "U":
        raise DataFileError(path, f"field {key} must be a list of names, not {value.dtype} "
                                  f"{value.shape}")
    return tuple(str(x) for x in value)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value)


def _check_meta(stats: dict, provenance: dict, path) -> None:
    """Refuse metadata the summaries (``upm train``, ``upm map-info``) cannot print."""
    def bad(what: str):
        return DataFileError(path, f"corrupt metadata (meta_json): {what}")

    if set(stats) != set(CLASS_NAMES):
        raise bad(f"stats must cover the classes {', '.join(CLASS_NAMES)}")
    for c, s in stats.items():
        if not isinstance(s, dict):
            raise bad(f"stats of {c} is not a record")
        for key in ("neurons", "quantisation_error_mean_deg", "quantisation_error_max_deg"):
            if not _is_number(s.get(key)):
                raise bad(f"stats of {c} lacks a number {key}")
        if s.get("radius_deg") is not None and not _is_number(s["radius_deg"]):
            raise bad(f"stats of {c}: radius_deg is not a number")
        grid = s.get("grid")
        if grid is not None and not (isinstance(grid, list) and len(grid) == 2
                                     and all(isinstance(v, int) for v in grid)):
            raise bad(f"stats of {c}: grid is not [rows, cols]")
    names = provenance.get("clip_names", [])
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise bad("provenance clip_names is not a list of names")
    for key in ("n_samples", "train_seconds"):
        if provenance.get(key) is not None and not _is_number(provenance[key]):
            raise bad(f"provenance {key} is not a number")


def _text(arrays: dict, key: str, path) -> str:
    value = arrays.get(key)
    if value is None or value.shape != () or value.dtype.kind != "U":
        raise DataFileError(path, f"field {key} must be a text value")
    return str(value)


def load_map(path: str | os.PathLike):
    """Read a saved posture map of either kind (``"upm"`` or ``"som"``)."""
    import importlib

    arrays = _read_npz(path)
    kind = _text(arrays, "kind", path)
    if kind not in MAP_KINDS:
        raise DataFileError(path, f"unknown map kind {kind!r} (known: {', '.join(MAP_KINDS)})")
    module, name = MAP_KINDS[kind]
    return getattr(importlib.import_module(module), name)._from_arrays(arrays, path)
