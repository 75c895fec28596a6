"""Key-posture sources that learn nothing: the study's two ablations of the map.

- :class:`ClassNearest` (``classnn``): per joint class, the key sub-posture is the
  nearest *training* sub-posture to the alpha-point C of A->B — the paper's section 3.1
  with the map's neurons replaced by every training sample. If UPM beats it, the map's
  training is what helps; if not, the class split and the real samples do the work.
- :class:`NearestPosture` (``snap``): the whole-body nearest training posture to C (no
  class split): a real posture of the training data, whole.

Distances are on the circle: the squared Euclidean distance of per-DOF differences
wrapped to [-180, 180) (the paper's d_j), found exactly with a periodic k-d tree
(``scipy.spatial.cKDTree`` with ``boxsize=360``). Both follow the key-posture protocol of
the maps: ``key_posture(a_deg, b_deg, alpha=0.5)``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from upm.core.errors import UsageError
from upm.motion.skeleton import CLASS_SLICES, POSTURE_SIZE
from upm.ops.angles import interpolate_deg, wrap_deg


def check_key_inputs(a_deg, b_deg, alpha):
    """Validate the arguments of ``key_posture``.

    Returns
    -------
    a, b : ndarray, shape (N, 63)
    alpha : ndarray, shape (N,)
    single : bool
        Whether A and B were single postures (63,).

    Raises
    ------
    UsageError
        For postures of the wrong length or shape, non-finite values, or alpha outside
        [0, 1] or NaN.
    """
    a = np.asarray(a_deg, dtype=float)
    b = np.asarray(b_deg, dtype=float)
    if a.shape != b.shape or a.ndim not in (1, 2) or a.shape[-1] != POSTURE_SIZE:
        raise UsageError(f"postures A and B must both have shape ({POSTURE_SIZE},) or "
                         f"(N, {POSTURE_SIZE}), not {a.shape} and {b.shape}")
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise UsageError("postures A and B must be finite (no NaN or infinity)")
    single = a.ndim == 1
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    alpha = np.asarray(alpha, dtype=float)
    if alpha.ndim > 1 or (alpha.ndim == 1 and alpha.shape[0] not in (1, a.shape[0])):
        raise UsageError(f"alpha must be a number or one per posture pair, not shape "
                         f"{alpha.shape}")
    if np.isnan(alpha).any() or (alpha < 0).any() or (alpha > 1).any():
        raise UsageError(f"alpha must be in [0, 1] (0 is A, 1 is B), not {alpha}")
    return a, b, np.broadcast_to(alpha, (a.shape[0],)), single


def _check_training(postures_deg) -> np.ndarray:
    p = np.asarray(postures_deg, dtype=float)
    if p.ndim != 2 or p.shape[1] != POSTURE_SIZE or p.shape[0] == 0:
        raise UsageError(f"training postures must have shape (N, {POSTURE_SIZE}) with N >= 1, "
                         f"not {p.shape}")
    if not np.isfinite(p).all():
        raise UsageError("training postures must be finite (no NaN or infinity)")
    return wrap_deg(p)


class _PeriodicTree:
    """Exact nearest neighbours under wrapped angle distances.

    A periodic k-d tree (``boxsize=360``) over angles shifted per DOF so that the box's
    seam falls in the widest empty arc of the data: distances on the circle do not
    change, but few points lie near the seam, so queries rarely look across it (with the
    seam at 0, DOFs that swing around 0 make the query ~50x slower).
    """

    def __init__(self, values_deg: np.ndarray):
        self.seam_deg = _widest_gap_middle(values_deg)
        self.tree = cKDTree(self._to_box(values_deg), boxsize=360.0)

    def _to_box(self, angles_deg: np.ndarray) -> np.ndarray:
        boxed = np.mod(angles_deg - self.seam_deg, 360.0)
        return np.where(boxed >= 360.0, 0.0, boxed)

    def query(self, angles_deg: np.ndarray) -> np.ndarray:
        """Index of the nearest data row of each query row, (M,)."""
        return self.tree.query(self._to_box(angles_deg))[1]


def _widest_gap_middle(values_deg: np.ndarray) -> np.ndarray:
    """Per column, the middle of the widest arc of the circle holding no value, (D,)."""
    v = np.sort(np.mod(values_deg, 360.0), axis=0)
    gaps = np.diff(np.concatenate([v, v[:1] + 360.0]), axis=0)
    widest = np.argmax(gaps, axis=0)
    columns = np.arange(v.shape[1])
    return v[widest, columns] + 0.5 * gaps[widest, columns]


def _tree(values_deg: np.ndarray) -> _PeriodicTree:
    return _PeriodicTree(values_deg)


class ClassNearest:
    """``classnn``: per class, the nearest training sub-posture to the alpha-point.

    Parameters
    ----------
    postures_deg : array_like, shape (N, 63)
        Training postures (e.g. every frame of the training clips).
    """

    kind = "classnn"

    def __init__(self, postures_deg):
        self.postures_deg = _check_training(postures_deg)
        self._trees = {name: _tree(self.postures_deg[:, s]) for name, s in CLASS_SLICES.items()}

    @classmethod
    def fit(cls, postures_deg) -> ClassNearest:
        return cls(postures_deg)

    def __len__(self) -> int:
        return self.postures_deg.shape[0]

    def key_posture(self, a_deg, b_deg, alpha=0.5) -> np.ndarray:
        """The key posture for A, B and ratio alpha (0 is A, 1 is B).

        Parameters
        ----------
        a_deg, b_deg : array_like, shape (63,) or (N, 63)
        alpha : float or array_like, shape (N,)

        Returns
        -------
        ndarray, shape (63,) or (N, 63)
            Each class sub-vector is one training sample's, wrapped to [-180, 180).
        """
        a, b, alpha, single = check_key_inputs(a_deg, b_deg, alpha)
        c = interpolate_deg(a, b, alpha[:, None])
        key = np.empty_like(c)
        for name, s in CLASS_SLICES.items():
            index = self._trees[name].query(c[:, s])
            key[:, s] = self.postures_deg[index, s]
        return key[0] if single else key


class NearestPosture:
    """``snap``: the whole-body nearest training posture to the alpha-point.

    Parameters
    ----------
    postures_deg : array_like, shape (N, 63)
    """

    kind = "snap"

    def __init__(self, postures_deg):
        self.postures_deg = _check_training(postures_deg)
        self._tree = _tree(self.postures_deg)

    @classmethod
    def fit(cls, postures_deg) -> NearestPosture:
        return cls(postures_deg)

    def __len__(self) -> int:
        return self.postures_deg.shape[0]

    def key_posture(self, a_deg, b_deg, alpha=0.5) -> np.ndarray:
        """The training posture nearest to the alpha-point of A->B, (63,) or (N, 63)."""
        a, b, alpha, single = check_key_inputs(a_deg, b_deg, alpha)
        c = interpolate_deg(a, b, alpha[:, None])
        index = self._tree.query(c)
        key = self.postures_deg[index]
        return key[0] if single else key


def training_postures(catalog, split: str = "train", step: int = 1) -> np.ndarray:
    """The postures of a catalogue's clips of one split, every ``step``-th frame.

    Parameters
    ----------
    catalog : upm.motion.catalog.Catalog
    split : str
        ``"train"`` (the clips.csv training split), ``"test"``, or ``""`` for all clips.
    step : int

    Returns
    -------
    ndarray, shape (N, 63)
        Wrapped to [-180, 180) (the sources compare wrapped differences anyway).
    """
    from upm.maps.class_maps import postures_of_clips

    names = catalog.names(split or None)
    if not names:
        raise UsageError(f"no clips of split {split!r} under {catalog.root}")
    return postures_of_clips(catalog, names, step)[0]
