"""The training's hinted winner search, compiled (numba): one pass over graph lists.

For each sample with a hint, :class:`upm.maps.growing_map.MapSearch` looks for its nearest
neuron among the hint's neighbours in the snapshot graph whose snapshot distance is within
the sample's reach. In numpy that expands every (sample, candidate) pair, wraps and sums
their differences, and takes a minimum per sample; here each sample's list is scanned in
place, and a candidate is dropped as soon as its partial sum passes the best so far.

Ties go to the first candidate of the list, i.e. the lowest neuron index, as the numpy
search did (a minimum per sample's run of pairs, first position among equals). The
distances are summed here DOF by DOF, which may round differently from numpy's sum: the
caller measures the winners again, with numpy.

Imported only when a map is trained.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from upm.maps.torus_kernels import wrap_difference


@njit(cache=True, nogil=True)
def nearest_in_lists(x, weights, hint, reach, indptr, indices, dist, best):
    """Per row ``i`` of ``x`` (M, D), the neuron of ``hint[i]``'s list whose snapshot
    distance ``dist`` is at most ``reach[i]`` and whose current ``weights`` (K, D) are
    nearest to ``x[i]`` (wrapped); written to ``best[i]``. Both in [-180, 180)."""
    width = x.shape[1]
    for i in range(x.shape[0]):
        best_sq = 1e300
        pick = -1
        for e in range(indptr[hint[i]], indptr[hint[i] + 1]):
            if dist[e] > reach[i]:
                continue
            n = indices[e]
            total = 0.0
            for d in range(width):
                v = wrap_difference(x[i, d] - weights[n, d])
                total += v * v
                if total > best_sq:
                    break
            if total < best_sq:
                best_sq = total
                pick = n
        best[i] = pick


@njit(cache=True, nogil=True)
def pair_distances(weights, first, second, out):
    """Wrapped distance of neurons ``first[p]`` and ``second[p]`` of ``weights`` (K, D)
    (in [-180, 180)) for each pair ``p``, into ``out``: the graph's edge lengths."""
    width = weights.shape[1]
    for p in range(first.shape[0]):
        a, b = first[p], second[p]
        total = 0.0
        for d in range(width):
            v = wrap_difference(weights[a, d] - weights[b, d])
            total += v * v
        out[p] = np.sqrt(total)
