"""Training one class map of the Uniform Posture Map (paper section 2.3).

On the sub-vectors ``x`` (degrees) of one joint class:

1. the first sample becomes the first neuron;
2. a sample farther than ``R`` from every neuron becomes a new neuron (no neuron moves);
3. otherwise its winner is the nearest neuron (wrapped squared distance), and
4. the winner and its neighbours move toward it: ``W += eta * wrap(x - W)``;
5. after each pass ``eta`` and the neighbourhood radius shrink linearly; the pass at
   which ``eta`` reaches 0 moves nothing but still adds a neuron for every sample left
   beyond ``R`` -- so every training sample ends within ``R`` of a neuron.

**Neighbours** (the paper fixes no grid): the neurons within the current neighbourhood
radius ``r`` of the winner, by wrapped distance in weight space (the winner itself
included). ``r`` starts at ``neighbourhood_deg`` and shrinks with ``eta``, linearly to 0.

**Batches**: samples are taken ``batch_size`` at a time. Growth is resolved sample by
sample in order (a sample within ``R`` of a neuron born earlier in the same batch is not
a new neuron, and may have it as winner). Winners and neighbourhoods are found against
the map as it stood at the batch's start, and each neuron's moves within the batch are
composed in sample order -- ``W_n = W_0 + sum_m eta (1 - eta)^(n - m) wrap(x_m - W_0)``,
exactly the sequential result for the same winners. With ``batch_size=1`` this *is* the
sequential algorithm of the paper; larger batches only let a later sample of the batch
see its winner not yet moved by earlier ones (a move of at most ``eta * R`` each).

**Search** (exact, see :mod:`upm.maps.angular_search`): a snapshot of the map holds a KD-tree
on the circle embedding and a neighbour graph (every pair of neurons within
``graph_radius`` of each other). Neurons move after the snapshot by at most ``drift``
(measured every batch); the bounds below allow for it, and the snapshot is rebuilt when
the drift or the neurons born since grow too large. A sample's winner in the previous
pass is a *hint*: if it lies at ``U`` from the sample, any nearer neuron lies within
``2 U`` of the hint (triangle inequality), so within ``2 U + 2 drift`` of it in the
snapshot -- in its graph list when that is below ``graph_radius`` (scanned by a compiled
loop, :mod:`upm.maps.graph_search`). A sample without a usable hint takes as hint its nearest
neuron at the snapshot positions (the compiled search of :mod:`upm.maps.torus_tree`, built
on the snapshot when first needed); the few still out of the graph's reach go to the
KD-tree. Neighbourhoods (radius ``r``) come from the graph likewise. Every path is exact
and measures the winner's distance with numpy, so the neurons are those of the numpy
search before it, bit for bit (tested against a checksum).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from upm.maps.angular_search import (
    diff_of_wrapped,
    pairwise_sq_deg,
)
from upm.maps.growing_map import GrowingMap, MapSearch
from upm.ops.angles import wrap_deg


@dataclass(frozen=True)
class ClassTrainingResult:
    """One trained class map.

    Attributes
    ----------
    neurons_deg : ndarray, shape (K, D)
        Neuron weights in degrees, wrapped to ``[-180, 180)``.
    births_per_pass : tuple of int
        Neurons added during each pass (the first includes the first neuron).
    seconds : float
        Wall-clock training time.
    radius_deg, neighbourhood_deg : float
        ``R`` and the initial neighbourhood used (:func:`train_upm_classes` fills them in).
    quantisation_error_deg : (float, float) or None
        Mean and largest wrapped distance from the training samples to their nearest
        neuron (:func:`train_upm_classes` fills it in).
    cpu_seconds : float
        CPU time of the process for the whole job of :func:`train_upm_classes` (default
        R, training, quantisation error; NaN until it fills it in): on a loaded machine
        the figure to compare, where wall-clock time depends on the other work.
    """

    neurons_deg: np.ndarray
    births_per_pass: tuple[int, ...]
    seconds: float
    radius_deg: float = float("nan")
    neighbourhood_deg: float = float("nan")
    quantisation_error_deg: tuple[float, float] | None = None
    cpu_seconds: float = float("nan")


def _resolve_growth(x, far, r_sq):
    """Which far samples become neurons, in batch order (the leader rule).

    Parameters
    ----------
    x : ndarray, shape (B, D)
    far : ndarray of int, shape (F,)
        Batch positions (ascending) of samples farther than R from every old neuron.
    r_sq : float

    Returns
    -------
    ndarray of int
        Batch positions of the samples that become neurons, ascending.
    """
    if len(far) <= 1:
        return far
    near = pairwise_sq_deg(x[far], x[far]) <= r_sq
    created = np.zeros(len(far), dtype=bool)
    for i in range(len(far)):
        created[i] = not near[i, :i][created[:i]].any()
    return far[created]


def _batch_step(growing: GrowingMap, search: MapSearch, x: np.ndarray, hint: np.ndarray,
                r_sq: float, neighbourhood_deg: float, eta: float):
    """Process one batch of samples.

    Returns
    -------
    winner : ndarray of int, shape (B,)
        Each sample's winner (for a sample that became a neuron: that neuron).
    born : int
        Neurons added.
    """
    search.refresh()
    old_k = growing.size
    winner, win_sq = search.nearest(x, hint)
    born = _resolve_growth(x, np.flatnonzero(win_sq > r_sq), r_sq)
    if len(born):
        # A neuron born at batch position p exists for the samples after p only.
        to_new = pairwise_sq_deg(x, x[born])
        to_new[np.arange(len(x))[:, None] <= born[None, :]] = np.inf
        nearest_new = np.argmin(to_new, axis=1)
        closer = to_new[np.arange(len(x)), nearest_new] < win_sq
        winner = np.where(closer, old_k + nearest_new, winner)
        winner[born] = old_k + np.arange(len(born))
        growing.append(x[born])
        search.refresh()  # the newborns join the searched neurons
    if eta <= 0.0:
        return winner, len(born)
    movers = np.ones(len(x), dtype=bool)
    movers[born] = False
    movers = np.flatnonzero(movers)
    if len(movers) == 0:
        return winner, len(born)
    birth_pos = np.full(growing.size, -1)
    birth_pos[old_k:] = born
    # Neighbourhoods of the distinct winners, at the batch-start positions.
    centres, which = np.unique(winner[movers], return_inverse=True)
    c_of_pair, n_of_pair = search.neighbourhoods(centres, neighbourhood_deg)
    starts = np.searchsorted(c_of_pair, np.arange(len(centres) + 1))
    counts = np.diff(starts)[which]
    # Expand to (sample, neuron) pairs: each mover moves its winner's neighbourhood.
    pair_sample = np.repeat(movers, counts)
    slot = np.arange(len(pair_sample)) - np.repeat(np.cumsum(counts) - counts, counts)
    pair_neuron = n_of_pair[np.repeat(starts[which], counts) + slot]
    alive = birth_pos[pair_neuron] < pair_sample
    pair_sample, pair_neuron = pair_sample[alive], pair_neuron[alive]
    # Compose each neuron's moves in sample order: weight eta (1 - eta)^(later moves).
    order = np.lexsort((pair_sample, pair_neuron))
    pair_sample, pair_neuron = pair_sample[order], pair_neuron[order]
    neurons, first, n_moves = np.unique(pair_neuron, return_index=True, return_counts=True)
    rank = np.arange(len(pair_neuron)) - np.repeat(first, n_moves)
    later = np.repeat(n_moves, n_moves) - 1 - rank
    weight = eta * (1.0 - eta) ** later
    diff = diff_of_wrapped(x[pair_sample], growing.weights[pair_neuron]) * weight[:, None]
    growing.move(neurons, np.add.reduceat(diff, first, axis=0))
    return winner, len(born)


def train_upm_class(samples_deg, radius_deg: float, neighbourhood_deg: float,
                    learning_rate: float = 0.1, passes: int = 5, batch_size: int = 512,
                    seed: int = 0, shuffle: bool = True, desc: str | None = None,
                    ) -> ClassTrainingResult:
    """Train one class map of the UPM.

    Parameters
    ----------
    samples_deg : array_like, shape (N, D)
        Training sub-vectors in degrees (wrapped internally).
    radius_deg : float
        ``R``: a sample farther than this from every neuron becomes a neuron.
    neighbourhood_deg : float
        Initial neighbourhood radius (shrinks linearly to 0 with ``eta``); 0 moves the
        winner only. Neighbourhoods up to about ``2 R`` come from the neighbour graph,
        larger ones from the KD-tree (both exact).
    learning_rate : float
        ``eta`` of the first pass, in ``(0, 1)``; it falls linearly to 0 over ``passes``.
    passes : int
        Passes with ``eta > 0``; one closing pass at ``eta = 0`` follows.
    batch_size : int
        Samples per vectorised step (1 = the paper's sequential algorithm exactly).
    seed : int
        Seeds the per-pass shuffle of the sample order.
    shuffle : bool
        Visit the samples in a new seeded random order each pass (else in the given order).
    desc : str, optional
        Label of a progress bar (on stderr when it is a terminal).

    Returns
    -------
    ClassTrainingResult
    """
    from upm.core.progress import progress

    x_all = wrap_deg(np.asarray(samples_deg, dtype=float))
    n = len(x_all)
    start_s = time.perf_counter()
    rng = np.random.default_rng(seed)
    orders = [rng.permutation(n) if shuffle else np.arange(n) for _ in range(passes + 1)]
    growing = GrowingMap(x_all[orders[0][0]])
    search = MapSearch(growing, float(radius_deg))
    r_sq = float(radius_deg) ** 2
    hint = np.full(n, -1)
    hint[orders[0][0]] = 0
    births = []
    with progress(total=(passes + 1) * n, desc=desc, unit="sample",
                  disable=None if desc else True) as bar:
        for p in range(passes + 1):
            fraction_left = 1.0 - p / passes if passes > 0 else 0.0
            eta = learning_rate * fraction_left
            radius_nb = neighbourhood_deg * fraction_left
            added = 1 if p == 0 else 0
            order = orders[p][1:] if p == 0 else orders[p]
            for s in range(0, len(order), batch_size):
                rows = order[s:s + batch_size]
                hint[rows], born = _batch_step(growing, search, x_all[rows], hint[rows],
                                               r_sq, radius_nb, eta)
                added += born
                bar.update(len(rows))
            births.append(added)
    return ClassTrainingResult(
        neurons_deg=growing.current.copy(),
        births_per_pass=tuple(births),
        seconds=time.perf_counter() - start_s,
    )


#: Classes in order of training time on the CMU train split, slowest first: submitted in
#: this order, two workers finish the four classes together (detail + medium, global +
#: body) instead of one running two slow ones. Unknown names go last; the neurons do not
#: depend on it.
SLOWEST_FIRST = ("detail", "global", "body", "medium")


def _train_one(job: tuple) -> ClassTrainingResult:
    """One class, everything that needs only its samples: the default ``R`` (when
    ``radius`` is None), the training, and the quantisation error of its samples."""
    from dataclasses import replace

    from upm.maps.map_size import default_radius_deg
    from upm.maps.torus_tree import nearest_neuron

    start_cpu_s = time.process_time()
    samples, radius, neighbourhood, kwargs = job
    if radius is None:
        radius = default_radius_deg(samples, seed=kwargs.get("seed", 0))
    if neighbourhood is None:
        neighbourhood = radius
    result = train_upm_class(samples, radius, neighbourhood, **kwargs)
    _, dist_sq = nearest_neuron(samples, result.neurons_deg)
    distance = np.sqrt(dist_sq)
    return replace(result, radius_deg=float(radius), neighbourhood_deg=float(neighbourhood),
                   quantisation_error_deg=(float(distance.mean()), float(distance.max())),
                   cpu_seconds=time.process_time() - start_cpu_s)


def train_upm_classes(jobs: dict[str, tuple], workers: int | None = None,
                      desc: str | None = None) -> dict[str, ClassTrainingResult]:
    """Train several class maps at once, one process per class (at most ``workers``).

    The classes are independent and each is seeded, so the neurons are identical to
    training them one after the other.

    Parameters
    ----------
    jobs : dict of str to tuple
        Per class, ``(samples_deg, radius_deg, neighbourhood_deg, kwargs)``: the
        arguments of :func:`train_upm_class` (``kwargs`` without ``desc``); a radius of
        None is the default (:func:`upm.maps.map_size.default_radius_deg`), a
        neighbourhood of None the radius. Each worker also measures its class's
        quantisation error, so nothing is left to do one class at a time.
    workers : int, optional
        Processes; default the usable CPUs. 1 trains in this process, in order.
    desc : str, optional
        Label of a progress bar over the classes.

    Returns
    -------
    dict of str to ClassTrainingResult
    """
    import os

    from upm.core.progress import progress

    if workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
    import multiprocessing

    workers = max(1, min(int(workers), len(jobs)))
    if "fork" not in multiprocessing.get_all_start_methods():
        workers = 1  # no fork (Windows): in order, same neurons
    names = list(jobs)
    with progress(total=len(names), desc=desc, unit="class",
                  disable=None if desc else True) as bar:
        if workers == 1:
            results = {}
            for name in names:
                results[name] = _train_one(jobs[name])
                bar.update(1)
            return results
        from concurrent.futures import ProcessPoolExecutor

        # fork: the workers need no imports and share the samples copy-on-write.
        context = multiprocessing.get_context("fork")
        with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
            rank = {name: i for i, name in enumerate(SLOWEST_FIRST)}
            futures = {name: pool.submit(_train_one, jobs[name])
                       for name in sorted(names, key=lambda n: rank.get(n, len(rank)))}
            results = {}
            for name in names:
                results[name] = futures[name].result()
                bar.update(1)
        return results
