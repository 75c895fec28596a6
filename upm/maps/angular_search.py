"""Exact nearest-neighbour and radius search under the wrapped angular distance.

The distance between two angle vectors (degrees) is the Euclidean norm of their per-DOF
differences wrapped to ``[-180, 180)`` (:func:`upm.ops.angles.angular_distance_sq`). Each
angle is embedded on a circle of radius ``180/pi``: ``e(theta) = (180/pi) (cos theta,
sin theta)``. The chord between two angles ``delta`` apart is ``(360/pi) sin(|delta|/2)``:
never more than ``|delta|`` (and never less than ``(2/pi) |delta|``), so the Euclidean
distance of embeddings is a lower bound of the wrapped distance, tight for small angles.

A KD-tree (``scipy.spatial.cKDTree``) on the embeddings gives the ``k`` chord-nearest
neurons; they are refined on exact wrapped distances, and the answer is *proved* exact
when the ``(k+1)``-th chord distance exceeds the best exact distance found (every other
neuron is then farther, since chord <= wrapped). Rows where the proof fails are searched
again by brute force. Radius queries use the same bound: the chord ball holds every
neuron of the wrapped ball, and candidates are checked exactly.

The tree may be *stale* (built on earlier positions of neurons that have moved since by
at most ``slack`` in the embedding, as during training): the bounds then carry the
slack, and neurons added after the build are searched by brute force.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from upm.ops.angles import wrap_deg

#: Radius of the embedding circle, so that chord distances are in degrees for small angles.
EMBED_SCALE_DEG = 180.0 / np.pi
#: Relative float margin on chord bounds (the embedding's rounding error is far below).
_MARGIN = 1e-9


def embed_deg(angles_deg) -> np.ndarray:
    """Embed angle vectors on circles: ``(..., D)`` degrees -> ``(..., 2 D)``.

    The first ``D`` columns are ``(180/pi) cos``, the last ``D`` ``(180/pi) sin``; the
    Euclidean distance of two embeddings is the chord distance, ``<=`` the wrapped one.
    """
    rad = np.deg2rad(np.asarray(angles_deg, dtype=float))
    return EMBED_SCALE_DEG * np.concatenate([np.cos(rad), np.sin(rad)], axis=-1)


def diff_of_wrapped(a, b):
    """``a - b`` wrapped to [-180, 180) for ``a``, ``b`` already in [-180, 180) (the
    difference is then in (-360, 360): one correction each way, cheaper than ``mod``)."""
    d = np.subtract(a, b)
    np.subtract(d, 360.0, out=d, where=d >= 180.0)
    np.add(d, 360.0, out=d, where=d < -180.0)
    return d


def pairwise_sq_deg(a_deg, b_deg) -> np.ndarray:
    """Wrapped squared distances by brute force, ``(M, D)`` x ``(K, D)`` -> ``(M, K)``."""
    a = wrap_deg(a_deg)
    b = wrap_deg(b_deg)
    d = diff_of_wrapped(a[:, None, :], b[None, :, :])
    return np.einsum("mkd,mkd->mk", d, d)


def rowwise_sq_deg(a, b):
    """Wrapped squared distances row by row (broadcasting), for inputs in [-180, 180)."""
    d = diff_of_wrapped(a, b)
    return np.einsum("...d,...d->...", d, d)


def _brute_nearest(points, weights, chunk=1 << 21):
    index = np.empty(len(points), dtype=np.intp)
    dist_sq = np.empty(len(points))
    step = max(1, chunk // max(1, len(weights) * weights.shape[1]))
    for s in range(0, len(points), step):
        d = diff_of_wrapped(points[s:s + step, None, :], weights[None, :, :])
        sq = np.einsum("mkd,mkd->mk", d, d)
        index[s:s + step] = np.argmin(sq, axis=1)
        dist_sq[s:s + step] = sq[np.arange(len(sq)), index[s:s + step]]
    return index, dist_sq


class AngularIndex:
    """Neurons (angle vectors) to search exactly under the wrapped distance.

    Parameters
    ----------
    neurons_deg : array_like, shape (K, D)
        Degrees in [-180, 180) (others are wrapped, in a copy). An array already in range
        is referenced, not copied: a caller that moves neurons in place (training) calls
        :meth:`refresh` after, or :meth:`rebuild`.
    candidates : int
        How many chord-nearest neurons are refined exactly before the exactness proof.
    """

    def __init__(self, neurons_deg, candidates: int = 8):
        weights = np.asarray(neurons_deg, dtype=float)
        if weights.ndim != 2 or len(weights) == 0:
            raise ValueError("an AngularIndex needs a non-empty (K, D) array")
        if not np.all((weights >= -180.0) & (weights < 180.0)):
            weights = wrap_deg(weights)
        self.candidates = int(candidates)
        self.unproved = 0  # rows searched by brute force because the proof failed
        self.rebuild(weights)

    def rebuild(self, weights_deg) -> None:
        """Build the tree afresh on the current ``weights_deg`` (shape (K, D))."""
        self.weights = weights_deg
        self._snapshot = embed_deg(weights_deg)
        self.tree = cKDTree(self._snapshot)
        self.n_tree = len(weights_deg)
        self.slack = 0.0

    def __len__(self) -> int:
        return len(self.weights)

    def refresh(self, weights_deg, slack: float) -> None:
        """Point the index at ``weights_deg`` -- the same neurons in [-180, 180), moved
        since the build by at most ``slack`` (wrapped distance, an upper bound of the
        chord moved), maybe with more appended at the end (searched by brute force) --
        without rebuilding the tree."""
        self.weights = weights_deg
        self.slack = float(slack)

    def nearest(self, points_deg) -> tuple[np.ndarray, np.ndarray]:
        """The nearest neuron of each point.

        Parameters
        ----------
        points_deg : array_like, shape (M, D)

        Returns
        -------
        index : ndarray of int, shape (M,)
        dist_sq : ndarray, shape (M,)
            Squared wrapped distance to that neuron (degrees squared).
        """
        points = wrap_deg(np.asarray(points_deg, dtype=float).reshape(-1, self.weights.shape[1]))
        k = min(self.candidates, self.n_tree)
        if k == self.n_tree:
            return _brute_nearest(points, self.weights)
        chord, cand = self.tree.query(embed_deg(points), k=k + 1)
        cand_sq = rowwise_sq_deg(points[:, None, :], self.weights[cand[:, :k]])
        pick = np.argmin(cand_sq, axis=1)
        rows = np.arange(len(points))
        best = cand[rows, pick]
        best_sq = cand_sq[rows, pick]
        # Every tree neuron outside the k is at least chord[:, k] - slack away now.
        bound = np.maximum(chord[:, k] - self.slack, 0.0)
        scale = np.sqrt(self.weights.shape[1]) * EMBED_SCALE_DEG
        unproved = np.flatnonzero(bound * bound <= best_sq + _MARGIN * scale**2)
        if len(unproved):
            # Search those rows again over every tree neuron that may beat the best.
            self.unproved += len(unproved)
            ci, ni = self._ball_pairs(points[unproved], np.sqrt(best_sq[unproved]))
            sq = rowwise_sq_deg(points[unproved][ci], self.weights[ni])
            order = np.lexsort((sq, ci))
            first = np.searchsorted(ci[order], np.arange(len(unproved)))
            best[unproved] = ni[order][first]
            best_sq[unproved] = sq[order][first]
        if len(self.weights) > self.n_tree:
            extra, extra_sq = _brute_nearest(points, self.weights[self.n_tree:])
            closer = extra_sq < best_sq
            best[closer] = extra[closer] + self.n_tree
            best_sq[closer] = extra_sq[closer]
        return best, best_sq

    def within(self, centres_deg, radius_deg: float) -> tuple[np.ndarray, np.ndarray]:
        """Every (centre, neuron) pair at most ``radius_deg`` apart (wrapped distance).

        Parameters
        ----------
        centres_deg : array_like, shape (M, D)
        radius_deg : float

        Returns
        -------
        centre_index, neuron_index : ndarray of int, shape (P,)
            The pairs, sorted by centre then neuron.
        """
        centres = wrap_deg(np.asarray(centres_deg, dtype=float).reshape(-1, self.weights.shape[1]))
        r = float(radius_deg)
        ci, ni = self._ball_pairs(centres, np.full(len(centres), r))
        if len(self.weights) > self.n_tree:
            ce, ne = np.nonzero(pairwise_sq_deg(centres, self.weights[self.n_tree:]) <= r * r)
            ci = np.concatenate([ci, ce])
            ni = np.concatenate([ni, ne + self.n_tree])
        keep = rowwise_sq_deg(centres[ci], self.weights[ni]) <= r * r
        ci, ni = ci[keep], ni[keep]
        order = np.lexsort((ni, ci))
        return ci[order], ni[order]

    def _ball_pairs(self, points, radius_deg):
        """(point, tree neuron) pairs whose chord distance may be within ``radius_deg``
        (per point) given the slack: a superset of the wrapped ball."""
        scale = np.sqrt(self.weights.shape[1]) * EMBED_SCALE_DEG
        lists = self.tree.query_ball_point(embed_deg(points),
                                            radius_deg + self.slack + _MARGIN * scale)
        counts = np.fromiter((len(x) for x in lists), dtype=np.intp, count=len(lists))
        ci = np.repeat(np.arange(len(points)), counts)
        ni = (np.concatenate([np.asarray(x, dtype=np.intp) for x in lists])
              if counts.sum() else np.zeros(0, dtype=np.intp))
        return ci, ni
