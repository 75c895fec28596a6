"""Shared material for the transition tests: real clip pairs and synthetic ones
(tests/synthetic.py), key-posture sources fitted once per process, and the continuity
checks of the window's edges."""

from __future__ import annotations

import functools

import numpy as np

from upm.motion.catalog import Catalog
from upm.ops.angles import angle_diff_deg

#: Real pairs (clip 1, frame A, clip 2, frame B): a walk into a run, a walk into a dance
#: of another subject, a 60 fps salsa into a walk (resampled), a karate kata whose root
#: Euler angles pass 1000 degrees into a 60 fps jump (two subjects, resampled), a swordplay
#: into a punch.
PAIRS = (
    ("02_01", 200, "02_03", 20),
    ("05_01", 300, "16_15", 100),
    ("60_10", 400, "35_01", 50),
    ("135_06", 1500, "141_04", 150),
    ("02_07", 900, "02_05", 700),
)

#: Synthetic pairs of the ``synthetic_catalog`` fixture, the same layout: a walk into a
#: run of the shorter subject, a run into a turning walk of the same subject, a turning
#: walk into a 60 fps walk of the other subject (resampled).
SYNTHETIC_PAIRS = (
    ("81_01", 120, "82_02", 20),
    ("81_02", 100, "81_03", 30),
    ("81_03", 150, "82_01", 10),
)

#: Frames of each clip around the join (enough context for every method).
CLIP_FRAMES = 40


@functools.lru_cache(maxsize=2)
def catalog_of(data_dir) -> Catalog:
    return Catalog(data_dir)


@functools.lru_cache(maxsize=2)
def sources(data_dir) -> dict:
    """Key-posture source per key method, each built by its registered builder: classnn
    and snap fitted on the train split (every 2nd frame: enough, and half the fitting
    time); the UPM and SOM of the study (trained on the train split once, then cached:
    upm.maps.map_cache); feasible: the UPM with the humanoid's checks."""
    from upm.transitions import METHODS, KeySourceContext, build_key_source

    context = KeySourceContext(catalog=catalog_of(data_dir), train_maps=True, train_step=2)
    return {name: build_key_source(name, context) for name, method in METHODS.items()
            if method.needs_key_source}


def pair(data_dir, index: int, frames: int = CLIP_FRAMES):
    """Clip 1 ending at A and clip 2 starting at B of ``PAIRS[index]``."""
    return _pair(catalog_of(data_dir), PAIRS[index], frames)


def synthetic_pair(catalog, index: int, frames: int = CLIP_FRAMES):
    """Clip 1 ending at A and clip 2 starting at B of ``SYNTHETIC_PAIRS[index]``, from the
    synthetic folder's ``catalog``."""
    return _pair(catalog, SYNTHETIC_PAIRS[index], frames)


def _pair(catalog, spec, frames):
    name1, a, name2, b = spec
    before = catalog.load(name1).frames(a + 1 - frames, a + 1)
    after = catalog.load(name2).frames(b, b + frames)
    return before, after


# --- continuity at a window edge ----------------------------------------------------------
#
# At an edge, the real frame R (A, or B) meets the new frame next to it. With frames taken
# outward from the window, s0 = step across the join, s-1 / s1 = the steps on either side;
# d(k) = the change of step (discrete acceleration) centred on frame k, R at 0.
#
# C0 (no jump): |s0| <= max(|s-1|, |s1|) + max |d| over the frames *not touching* the join
#   (-2, -1 on the clip side, 2, 3 on the window side) + 0.05 deg. A smooth curve's step
#   can differ from its neighbours' by no more than the accelerations around it; a jump
#   adds its whole size to s0. The 0.05 deg absorbs slerp's uneven Euler speed (measured
#   up to 0.02 deg on 25 random real pairs).
# C1 (no velocity jump): |d(0)| <= 2 max(|d(-1)|, |d(1)|) + 0.1 deg/frame^2: the
#   acceleration at the join is not an outlier among its neighbours. 0.1 deg/frame^2 is
#   about the median |d| of the CMU clips (0.02-0.3: mocap noise); a linear blend's velocity
#   jump shows here as 5-15 deg/frame^2 on real pairs.


def _edge_frames(motion, real_index: int, direction: int, dofs) -> np.ndarray:
    """Frames R-4d .. R+5d (d = direction: +1 from A into the window, -1 from B back into
    it), unwrapped: shape (10, n)."""
    index = real_index + direction * np.arange(-4, 6)
    seg = motion.posture_deg[index][:, dofs]
    return seg[0] + np.cumsum(np.vstack([np.zeros(seg.shape[1]),
                                         angle_diff_deg(seg[1:], seg[:-1])]), axis=0)


def edge_excess(motion, real_index: int, direction: int, dofs) -> tuple[float, float]:
    """(C0 excess, C1 excess) at one edge, max over DOFs: > 0 means the check fails."""
    x = _edge_frames(motion, real_index, direction, dofs)
    s = np.diff(x, axis=0)  # s[k]: from frame k-4 to k-3 (relative to R): join step s[4]
    d = np.diff(s, axis=0)  # d[k]: centred on frame k-3: join acceleration d[3]
    far = np.max(np.abs(d[[1, 2, 5, 6]]), axis=0)
    c0 = np.abs(s[4]) - np.maximum(np.abs(s[3]), np.abs(s[5])) - far - 0.05
    c1 = np.abs(d[3]) - 2.0 * np.maximum(np.abs(d[2]), np.abs(d[4])) - 0.1
    return float(c0.max()), float(c1.max())


def window_edges(transition, skip=None):
    """((C0, C1) excess at A, (C0, C1) excess at B) over the declared DOFs.

    ``skip``: optional bool array (2, 63) of DOFs left out at A and at B (feasible's
    limit turns: :func:`upm.transitions.feasible.limit_turns`)."""
    declared = transition.motion.skeleton.declared
    skip = np.zeros((2, declared.size), dtype=bool) if skip is None else np.asarray(skip)
    at_a = edge_excess(transition.motion, transition.a_index, +1,
                       np.flatnonzero(declared & ~skip[0]))
    at_b = edge_excess(transition.motion, transition.b_index, -1,
                       np.flatnonzero(declared & ~skip[1]))
    return at_a, at_b


def feasible_limit_turns(before, after, frames=20, alpha=0.5):
    """The DOFs of a feasible transition whose join turns at a limit, (2, 63) bool."""
    from upm.transitions import make_problem
    from upm.transitions.feasible import allowed_range, limit_turns, long_way_turns

    problem = make_problem(before, after, frames, alpha)
    turns = long_way_turns(problem)
    if turns.any():
        import dataclasses

        problem = dataclasses.replace(problem, after_deg=problem.after_deg + 360.0 * turns)
    lower, upper, constrained, _ = allowed_range(problem)
    return limit_turns(problem, lower, upper, constrained)
