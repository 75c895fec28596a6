"""The compiled search of :mod:`upm.maps.torus_tree` (numba, cached on disk).

Imported only when a forest is first queried, so that commands that never search a map
do not pay for importing numba. Arrays are as :class:`upm.maps.torus_tree.TorusForest` lays
them out; no Python object reaches this module.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Margin on leaf bounds, relative and absolute (degrees squared): the gap ``q + 360 - hi``
#: and the wrapped difference ``(q - hi) + 360`` of a neuron on the box's edge round
#: differently.
_MARGIN = 1e-9
_MARGIN_ABS = 1e-9


@njit(cache=True, nogil=True, inline="always")
def _wrap(x):
    """``upm.ops.angles.wrap_deg`` for one value (same operations, same rounding)."""
    w = (x + 180.0) % 360.0 - 180.0
    if w >= 180.0:
        w -= 360.0
    return w


@njit(cache=True, nogil=True, inline="always")
def wrap_difference(x):
    """A difference of two angles in [-180, 180) brought into [-180, 180) (one turn at
    most: an add or a subtract, no modulo)."""
    if x >= 180.0:
        x -= 360.0
    elif x < -180.0:
        x += 360.0
    return x


@njit(cache=True, nogil=True, inline="always")
def _gap_sq(x, low, high):
    """Squared wrapped distance from angle ``x`` to the nearest angle of ``[low, high]``."""
    if x < low:
        g = min(low - x, x + 360.0 - high)
    elif x > high:
        g = min(x - high, low + 360.0 - x)
    else:
        g = 0.0
    return g * g


@njit(cache=True, nogil=True, inline="always")
def _search(q, first, active, leaf0, n_leaves, box_base, box_lo, box_hi, leaf_start,
            leaf_offset, leaf_weights, order, bounds, acc):
    """Nearest neuron of one block to ``q[first:first + active]`` (search column order):
    (point, squared distance over the searched DOFs); the point indexes the forest's
    tree-ordered neurons.

    Every leaf's box bound at once (DOF-major, SIMD), then the leaves in order of bound
    until the bound passes the best distance found; a leaf's neurons DOF-major too, each
    DOF for all of them at once, until every partial sum is past the best.
    """
    for leaf in range(n_leaves):
        bounds[leaf] = 0.0
    for d in range(active):
        x = q[first + d]
        row = box_base + d * n_leaves
        for leaf in range(n_leaves):
            bounds[leaf] += _gap_sq(x, box_lo[row + leaf], box_hi[row + leaf])
    best = np.inf
    best_point = -1
    nearest_leaf = 0
    for leaf in range(1, n_leaves):
        if bounds[leaf] < bounds[nearest_leaf]:
            nearest_leaf = leaf
    for r in range(n_leaves):
        # the leaf of least bound first, then the others in order (leaf 0 in its place)
        leaf = nearest_leaf if r == 0 else (0 if r == nearest_leaf else r)
        if bounds[leaf] > best * (1.0 + _MARGIN) + _MARGIN_ABS:
            continue
        start = leaf_start[leaf0 + leaf]
        n = leaf_start[leaf0 + leaf + 1] - start
        row = leaf_offset[leaf0 + leaf]
        for j in range(n):
            acc[j] = 0.0
        done = True
        for d in range(active):
            x_q = q[first + d]
            least = np.inf
            for j in range(n):
                x = wrap_difference(x_q - leaf_weights[row + j])
                acc[j] += x * x
                least = min(least, acc[j])
            row += n
            if least > best:
                done = False
                break
        if done:
            for j in range(n):
                p = start + j
                if acc[j] < best:
                    best = acc[j]
                    best_point = p
                elif acc[j] == best and order[p] < order[best_point]:  # a tie: lower index
                    best_point = p
    return best_point, best


@njit(cache=True, nogil=True)
def nearest(points, blocks, cols, weights, order, box_lo, box_hi, leaf_start, leaf_offset,
            leaf_weights, index, dist_sq, out):
    """Per point and block, the nearest neuron: its row in the block, the squared wrapped
    distance over all the block's DOFs, and its values copied into ``out``."""
    bounds = np.empty(max(1, blocks[:, 4].max()))
    acc = np.empty(max(1, np.diff(leaf_start).max()))
    q = np.empty(points.shape[1])
    for i in range(points.shape[0]):
        for c in range(q.shape[0]):
            q[c] = points[i, cols[c]]
        for k in range(blocks.shape[0]):
            first, active, width = blocks[k, 0], blocks[k, 1], blocks[k, 2]
            p, s = _search(q, first, active, blocks[k, 3], blocks[k, 4], blocks[k, 5],
                           box_lo, box_hi, leaf_start, leaf_offset, leaf_weights, order,
                           bounds, acc)
            offset = blocks[k, 6] + (p - blocks[k, 7]) * width
            for d in range(active, width):  # the DOFs every neuron of the block shares
                x = wrap_difference(q[first + d] - weights[offset + d])
                s += x * x
            index[i, k] = order[p]
            dist_sq[i, k] = s
            for d in range(width):
                out[i, cols[first + d]] = weights[offset + d]


@njit(cache=True, nogil=True)
def key_postures(a, b, alpha, blocks, cols, weights, order, box_lo, box_hi, leaf_start,
                 leaf_offset, leaf_weights, out):
    """Per row, the neurons nearest to ``wrap(a + alpha * wrap(b - a))`` (the operations
    of ``upm.ops.angles.interpolate_deg`` then ``wrap_deg``, in the same order)."""
    bounds = np.empty(max(1, blocks[:, 4].max()))
    acc = np.empty(max(1, np.diff(leaf_start).max()))
    q = np.empty(a.shape[1])
    for i in range(a.shape[0]):
        t = alpha[i]
        for c in range(q.shape[0]):
            e = cols[c]
            q[c] = _wrap(a[i, e] + t * _wrap(b[i, e] - a[i, e]))
        for k in range(blocks.shape[0]):
            first, active, width = blocks[k, 0], blocks[k, 1], blocks[k, 2]
            p, _ = _search(q, first, active, blocks[k, 3], blocks[k, 4], blocks[k, 5],
                           box_lo, box_hi, leaf_start, leaf_offset, leaf_weights, order,
                           bounds, acc)
            offset = blocks[k, 6] + (p - blocks[k, 7]) * width
            for d in range(width):
                out[i, cols[first + d]] = weights[offset + d]
