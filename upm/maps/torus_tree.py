"""Exact key postures in one compiled call: the neurons in boxes on the torus of angles.

The key-posture query (:meth:`upm.maps.class_maps.ClassMaps.key_posture`) is four exact
nearest-neuron searches under the wrapped angular distance, one per joint class. Four
``cKDTree`` calls with their Python around them cost more than the whole query may
(issue 13: 50 us single, 15 us per pair batched), so here the four searches -- and the
interpolation of A and B before them -- run in one numba-compiled call
(:mod:`upm.maps.torus_kernels`).

Each class's neurons are cut into leaves of at most :data:`LEAF_SIZE` by a KD-tree on
the angles themselves (no embedding: split at the median of the DOF of widest spread).
For a leaf's box of angles ``[lo, hi]`` (``-180 <= lo <= hi < 180``) the wrapped distance
from a query angle ``q`` below it to any angle in it is at least ``min(lo - q, q + 360 -
hi)`` (above it: ``min(q - hi, lo + 360 - q)``), so the sum of the squared gaps over the
DOFs bounds every neuron of the leaf from below. A query computes every leaf's bound at
once, scans the leaf of least bound, then every other leaf whose bound does not exceed
the best distance found: the search is exact. A leaf is scanned DOF by DOF for all its
neurons at once, with the same wrapped differences as
:func:`upm.maps.angular_search.diff_of_wrapped`, until every partial sum is past the best. DOFs
are searched in order of decreasing spread (so that sums pass the best early), and DOFs
on which every neuron of a class has the same value (the CMU skeleton's undeclared DOFs)
are left out of the search: they add the same amount to every neuron's distance.

Measured (``upm bench``, the trained UPM, about 1,300 neurons per class): leaves of 24 to
32 neurons are fastest; walking the KD-tree itself (with bounds updated one split at a
time) was about 1.5x slower than this flat scan of leaf bounds, and sorting the leaves by
bound cost more than it saved.

Ties (neurons at exactly the same wrapped distance: maps hold duplicate neurons) go to
the lowest index. :class:`upm.maps.angular_search.AngularIndex` breaks them by the chord
distance of its embedding, which for neurons differing by 1e-14 degrees is rounding, so
the two may return such twins of each other (tested: within 1e-12 degrees).
"""

from __future__ import annotations

import numpy as np

#: Neurons per leaf (measured on the trained UPM, about 1,300 neurons per class).
LEAF_SIZE = 32


def _leaves(weights: np.ndarray, leaf_size: int) -> tuple[np.ndarray, list[int]]:
    """KD-tree leaves of ``weights`` (K, A): split at the median of the widest DOF until
    at most ``leaf_size`` neurons remain.

    Returns
    -------
    order : (K,) int, the neurons leaf by leaf
    starts : list of int, where each leaf starts in ``order`` (and K at the end)
    """
    k, width = weights.shape
    order = np.arange(k)
    starts = []
    pending = [(0, k)]
    while pending:
        s, e = pending.pop()
        if e - s <= leaf_size or width == 0:
            starts.append(s)
            continue
        block = weights[order[s:e]]
        d = int(np.argmax(np.ptp(block, axis=0)))
        order[s:e] = order[s:e][np.argsort(block[:, d], kind="stable")]
        mid = (s + e) // 2
        pending.append((mid, e))
        pending.append((s, mid))
    return order, sorted(starts) + [k]


class TorusForest:
    """Exact nearest neurons of several blocks of columns at once, e.g. the four joint
    classes of a posture.

    Parameters
    ----------
    blocks : sequence of array_like, shape (K_i, D_i)
        The neurons of each block, degrees in [-180, 180) (others are wrapped).
    columns : sequence of slice
        Where each block's D_i columns sit in a query vector: consecutive slices from 0.
    leaf_size : int
    """

    def __init__(self, blocks, columns, leaf_size: int = LEAF_SIZE):
        from upm.ops.angles import wrap_deg

        columns = list(columns)
        if [c.start for c in columns] != [0] + [c.stop for c in columns[:-1]]:
            raise ValueError("the blocks' columns must be consecutive slices from 0")
        self.width = columns[-1].stop
        #: The search's column order: internal column c is the query's column cols[c].
        self.cols = np.empty(self.width, dtype=np.int64)
        weights, orders, rows, box_lo, box_hi = [], [], [], [], []
        leaf_start, leaf_weights = [], []
        n_leaves = point_base = flat_base = box_base = 0
        for w, col in zip(blocks, columns, strict=True):
            w = np.asarray(w, dtype=float)
            width = col.stop - col.start
            if w.ndim != 2 or len(w) == 0 or w.shape[1] != width:
                raise ValueError(f"a block of neurons must be (K, {width}), not {w.shape}")
            if not np.all((w >= -180.0) & (w < 180.0)):
                w = wrap_deg(w)
            spread = np.ptp(w, axis=0)
            dofs = np.argsort(-spread, kind="stable")  # widest first, constant ones last
            active = int(np.count_nonzero(spread > 0.0))
            self.cols[col] = col.start + dofs
            order, starts = _leaves(w[:, dofs[:active]], leaf_size)
            w = w[order][:, dofs]
            weights.append(w.ravel())
            orders.append(order)
            lo = np.empty((active, len(starts) - 1))
            hi = np.empty_like(lo)
            for leaf, (s, e) in enumerate(zip(starts[:-1], starts[1:], strict=True)):
                searched = w[s:e, :active]
                lo[:, leaf], hi[:, leaf] = searched.min(axis=0), searched.max(axis=0)
                leaf_start.append(point_base + s)
                leaf_weights.append(searched.T.ravel())
            box_lo.append(lo.ravel())
            box_hi.append(hi.ravel())
            rows.append((col.start, active, width, n_leaves, len(starts) - 1, box_base,
                         flat_base, point_base))
            n_leaves += len(starts) - 1
            box_base += lo.size
            point_base += len(w)
            flat_base += w.size
        leaf_start.append(point_base)
        self.n_blocks = len(rows)
        #: Per block: first column, searched DOFs, all DOFs, first leaf, leaves, first
        #: box value, first weight value, first neuron.
        self.blocks = np.array(rows, dtype=np.int64)
        #: Every block's neurons leaf by leaf, row-major in search column order, in one
        #: flat array; each one's row in its block.
        self.weights = np.ascontiguousarray(np.concatenate(weights))
        self.order = np.concatenate(orders).astype(np.int64)
        #: Per block, each leaf's tight box on the searched DOFs, DOF-major.
        self.box_lo = np.ascontiguousarray(np.concatenate(box_lo + [np.zeros(1)]))
        self.box_hi = np.ascontiguousarray(np.concatenate(box_hi + [np.zeros(1)]))
        #: Each leaf's first neuron (and the total at the end); its searched values
        #: DOF-major from leaf_offset on in leaf_weights.
        self.leaf_start = np.array(leaf_start, dtype=np.int64)
        sizes = [len(x) for x in leaf_weights]
        self.leaf_offset = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
        self.leaf_weights = np.ascontiguousarray(np.concatenate(leaf_weights + [np.zeros(1)]))

    def _arrays(self):
        return (self.blocks, self.cols, self.weights, self.order, self.box_lo, self.box_hi,
                self.leaf_start, self.leaf_offset, self.leaf_weights)

    def nearest(self, points_deg) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The nearest neuron of each block for each point.

        Parameters
        ----------
        points_deg : array_like, shape (M, width)
            Degrees in [-180, 180).

        Returns
        -------
        index : ndarray of int, shape (M, n_blocks)
            Per block, the nearest neuron's row in that block.
        dist_sq : ndarray, shape (M, n_blocks)
            Its squared wrapped distance (degrees squared).
        neurons : ndarray, shape (M, width)
            Each block's columns replaced by its nearest neuron.
        """
        p = np.ascontiguousarray(points_deg, dtype=float).reshape(-1, self.width)
        index = np.empty((len(p), self.n_blocks), dtype=np.int64)
        dist_sq = np.empty((len(p), self.n_blocks))
        out = np.empty_like(p)
        _kernels().nearest(p, *self._arrays(), index, dist_sq, out)
        return index, dist_sq, out

    def key_postures(self, a_deg, b_deg, alpha) -> np.ndarray:
        """Per block, the neuron nearest to ``wrap(A + alpha * wrap(B - A))``.

        Parameters
        ----------
        a_deg, b_deg : ndarray, shape (M, width)
            Finite degrees, any range.
        alpha : ndarray, shape (M,)

        Returns
        -------
        ndarray, shape (M, width)
            Degrees in [-180, 180); each block's columns exactly a neuron.
        """
        out = np.empty(a_deg.shape)
        _kernels().key_postures(a_deg, b_deg, alpha, *self._arrays(), out)
        return out


def _kernels():
    """The compiled kernels: numba is imported, and the code compiled or read from
    numba's disk cache, on the first query only."""
    from upm.maps import torus_kernels

    return torus_kernels


def nearest_neuron(points_deg, neurons_deg) -> tuple[np.ndarray, np.ndarray]:
    """The nearest of one set of neurons to each point, by the compiled search.

    The same answer as :meth:`upm.maps.angular_search.AngularIndex.nearest`, bit for bit
    (the distance is computed again the same way, with numpy), at about a tenth of its
    time for many points and a thousand neurons or more.

    Parameters
    ----------
    points_deg : array_like, shape (M, D)
        Degrees (any range; wrapped).
    neurons_deg : array_like, shape (K, D)
        Degrees (any range; wrapped), ``K >= 1``.

    Returns
    -------
    index : ndarray of int, shape (M,)
    dist_sq : ndarray, shape (M,)
        Squared wrapped distance to that neuron (degrees squared).
    """
    from upm.maps.angular_search import rowwise_sq_deg
    from upm.ops.angles import wrap_deg

    neurons = wrap_deg(np.asarray(neurons_deg, dtype=float))
    points = wrap_deg(np.asarray(points_deg, dtype=float).reshape(-1, neurons.shape[1]))
    index = TorusForest([neurons], [slice(0, neurons.shape[1])]).nearest(points)[0][:, 0]
    # (M, 1, D) as AngularIndex computes it, so that the sums round the same way.
    dist_sq = rowwise_sq_deg(points[:, None, :], neurons[index][:, None, :])[:, 0]
    return index.astype(np.intp), dist_sq
