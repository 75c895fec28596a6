"""The growing map of :mod:`upm.maps.upm_training` and its exact nearest-neuron search.

:class:`GrowingMap` holds the neuron weights (an array that grows by doubling);
:class:`MapSearch` finds each sample's winner and neighbourhood against a
:class:`Snapshot` of the map (a KD-tree and a neighbour graph), with the drift bounds and
hints that the training module's docstring derives (section **Search**).
"""

from __future__ import annotations

import numpy as np

from upm.maps.angular_search import (
    AngularIndex,
    diff_of_wrapped,
    pairwise_sq_deg,
    rowwise_sq_deg,
)
from upm.ops.angles import wrap_deg


class GrowingMap:
    """Neuron weights (wrapped degrees) in an array that grows by doubling."""

    def __init__(self, first_deg: np.ndarray):
        self.weights = np.zeros((64, first_deg.shape[0]))
        self.size = 0
        self.append(first_deg[None, :])

    @property
    def current(self) -> np.ndarray:
        return self.weights[:self.size]

    def append(self, rows_deg: np.ndarray) -> None:
        need = self.size + len(rows_deg)
        if need > len(self.weights):
            grown = np.zeros((max(need, 2 * len(self.weights)), self.weights.shape[1]))
            grown[:self.size] = self.weights[:self.size]
            self.weights = grown
        self.weights[self.size:need] = wrap_deg(rows_deg)
        self.size = need

    def move(self, rows: np.ndarray, delta_deg: np.ndarray) -> None:
        self.weights[rows] = wrap_deg(self.weights[rows] + delta_deg)


class Snapshot:
    """The map at one moment: a KD-tree index and a neighbour graph of its neurons.

    ``graph`` is CSR (``indptr``, ``indices``, ``dist``): for each neuron, every neuron
    within ``radius`` of it at snapshot time (itself included) and their distances.
    """

    def __init__(self, weights: np.ndarray, radius: float):
        from upm.maps.graph_search import pair_distances

        self.weights0 = weights.copy()
        self.size = len(weights)
        self.radius = radius
        self.index = AngularIndex(self.weights0)
        # Chord <= wrapped distance: the chord pairs are a superset; keep the exact ones.
        pairs = self.index.tree.query_pairs(radius, output_type="ndarray")
        first, second = np.ascontiguousarray(pairs[:, 0]), np.ascontiguousarray(pairs[:, 1])
        pair_dist = np.empty(len(pairs))
        pair_distances(self.weights0, first, second, pair_dist)
        # Summed DOF by DOF (not as numpy sums): a margin keeps every pair within radius.
        keep = pair_dist <= radius * (1.0 + 1e-12)
        pairs, pair_dist = pairs[keep], pair_dist[keep]
        selves = np.arange(self.size)
        ci = np.concatenate([pairs[:, 0], pairs[:, 1], selves])
        ni = np.concatenate([pairs[:, 1], pairs[:, 0], selves])
        dist = np.concatenate([pair_dist, pair_dist, np.zeros(self.size)])
        # By centre, then neuron: one key per (unique) pair, so any sort gives this order.
        order = np.argsort(ci * self.size + ni)
        ci, ni, dist = ci[order], ni[order], dist[order]
        self.indptr = np.searchsorted(ci, np.arange(self.size + 1))
        self.indices = ni
        self.dist = dist
        self._forest = None

    def nearest_then(self, x: np.ndarray) -> np.ndarray:
        """Each row's nearest neuron at the snapshot positions (compiled search; built
        on first use)."""
        from upm.maps.torus_tree import TorusForest

        if self._forest is None:
            self._forest = TorusForest([self.weights0], [slice(0, self.weights0.shape[1])])
        return self._forest.nearest(x)[0][:, 0]


class MapSearch:
    """Exact winner and neighbourhood search over a growing, moving map.

    Neurons that moved more than ``max_drift`` since the snapshot ("loose") and those
    born since are the *extras*, searched by brute force; the bounds of the tree and the
    graph carry the largest move of the others (``drift``).
    """

    def __init__(self, growing: GrowingMap, radius_deg: float):
        self.growing = growing
        self.graph_radius = 2.0 * radius_deg
        self.max_drift = 0.25 * radius_deg
        self.snap = Snapshot(growing.current, self.graph_radius)
        self.drift = 0.0
        self.extras = np.zeros(0, dtype=np.intp)
        self.anchored = np.ones(1, dtype=bool)
        self.rebuilds = 1

    def refresh(self) -> None:
        """Measure each neuron's move since the snapshot; rebuild it when too many
        neurons have come loose or been born."""
        g, s = self.growing, self.snap
        moved = diff_of_wrapped(g.weights[:s.size], s.weights0)
        disp = np.sqrt(np.einsum("kd,kd->k", moved, moved))
        loose = np.flatnonzero(disp > self.max_drift)
        if len(loose) + g.size - s.size > max(16, s.size // 32):
            self.snap = s = Snapshot(g.current, self.graph_radius)
            disp, loose = np.zeros(s.size), np.zeros(0, dtype=np.intp)
            self.rebuilds += 1
        self.anchored = disp <= self.max_drift
        self.drift = float(disp[self.anchored].max(initial=0.0))
        self.extras = np.concatenate([loose, np.arange(s.size, g.size)])
        s.index.refresh(g.weights[:s.size], slack=self.drift)

    def _graph_pairs(self, rows, centres, reach):
        """(row, neuron) pairs from the graph lists of anchored ``centres`` whose
        snapshot distance is within ``reach`` (per row)."""
        s = self.snap
        counts = s.indptr[centres + 1] - s.indptr[centres]
        row = np.repeat(rows, counts)
        slot = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        edge = np.repeat(s.indptr[centres], counts) + slot
        keep = s.dist[edge] <= np.repeat(np.broadcast_to(reach, centres.shape), counts)
        return row[keep], s.indices[edge[keep]]

    def nearest(self, x: np.ndarray, hint: np.ndarray):
        """Exact nearest neuron of each row of ``x``; ``hint`` a neuron index or -1."""
        s, w = self.snap, self.growing.weights
        best = np.full(len(x), -1)
        best_sq = np.full(len(x), np.inf)
        self._via_graph(x, np.arange(len(x)), hint, best, best_sq)
        cold = np.flatnonzero(best < 0)
        if len(cold):
            # A hint for the others: their nearest neuron as it stood at the snapshot.
            self._via_graph(x, cold, s.nearest_then(x[cold]), best, best_sq)
            cold = cold[best[cold] < 0]
        if len(cold):
            best[cold], best_sq[cold] = s.index.nearest(x[cold])
        if len(self.extras):
            sq = pairwise_sq_deg(x, w[self.extras])
            j = np.argmin(sq, axis=1)
            j_sq = sq[np.arange(len(x)), j]
            closer = j_sq < best_sq
            best[closer] = self.extras[j[closer]]
            best_sq[closer] = j_sq[closer]
        return best, best_sq

    def _via_graph(self, x, rows, hint, best, best_sq) -> None:
        """Fill ``best``, ``best_sq`` at the ``rows`` whose hint (a neuron index or -1,
        one per row) is anchored and near enough that the graph holds every neuron that
        may be nearer; leave the others at -1."""
        from upm.maps.graph_search import nearest_in_lists

        s, w = self.snap, self.growing.weights
        ok = (hint >= 0) & (hint < s.size)
        ok[ok] = self.anchored[hint[ok]]
        hinted, h = rows[ok], hint[ok]
        if not len(hinted):
            return
        reach = 2.0 * np.sqrt(rowwise_sq_deg(x[hinted], w[h])) + 2.0 * self.drift
        ok = reach <= s.radius
        hinted, h, reach = hinted[ok], h[ok], reach[ok]
        found = np.empty(len(hinted), dtype=np.intp)
        xs = x[hinted]
        nearest_in_lists(xs, w, h, reach, s.indptr, s.indices, s.dist, found)
        best[hinted] = found
        best_sq[hinted] = rowwise_sq_deg(xs, w[found])  # numpy's rounding, as before

    def neighbourhoods(self, centres: np.ndarray, radius: float):
        """(centre position, neuron) pairs within ``radius`` of neurons ``centres``,
        sorted by centre position, without repeats."""
        s, w = self.snap, self.growing.weights
        reach = radius + 2.0 * self.drift
        in_graph = np.zeros(len(centres), dtype=bool)
        snapped = centres < s.size
        in_graph[snapped] = self.anchored[centres[snapped]] & (reach <= s.radius)
        gi = np.flatnonzero(in_graph)
        ci, ni = self._graph_pairs(gi, centres[gi], reach)
        parts_c, parts_n = [ci], [ni]
        other = np.flatnonzero(~in_graph)
        if len(other):
            oc, on = s.index.within(w[centres[other]], radius)
            parts_c.append(other[oc])
            parts_n.append(on)
        if len(self.extras):
            ce, ne = np.nonzero(pairwise_sq_deg(w[centres], w[self.extras]) <= radius * radius)
            parts_c.append(ce)
            parts_n.append(self.extras[ne])
        ci, ni = np.concatenate(parts_c), np.concatenate(parts_n)
        keep = rowwise_sq_deg(w[centres[ci]], w[ni]) <= radius * radius
        pairs = np.unique(np.stack([ci[keep], ni[keep]], axis=1), axis=0)
        return pairs[:, 0], pairs[:, 1]
