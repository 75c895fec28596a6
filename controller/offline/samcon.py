"""The offline effort's search (after SAMCON: Liu et al. 2010): can this body perform
this motion without any external force?

The body is the free-root humanoid with its position servos (the servo tracking of
:mod:`controller.tracking`: no root actuator, ``xfrc_applied`` zero). The motion is cut
into segments of ``offline.segment_s``. For each segment, ``offline.samples`` corrections
of the servo targets are drawn (Gaussian, ``sigma_deg`` per servo, the upper body's
``upper_sigma_share`` of it, :func:`servo_sigma_rad`; temporally coherent with the
parent's correction by ``coherence``; the first sample of each parent only decays the
parent's correction), spread evenly over the ``keep`` best states the search
holds at the segment's start, rolled out in MuJoCo (``mujoco.rollout`` on
``offline.threads`` threads: the results do not depend on it) and scored by
:func:`controller.offline.cost.state_cost` over the segment's frames (plus
``fall_cost`` for a fall, :mod:`controller.falls`); the ``lookahead_top`` cheapest are
rolled on ``lookahead_s`` past the segment and charged their tail's cost (a state already
tipping over is not kept for a segment close to the reference), and the ``keep`` best are
kept, those out of trouble at the segment's end and their tail's end first
(``upright_first``, :func:`rank`). The plan's own path (no correction: with the warm
start, the real-time controller's run, :mod:`controller.offline.warm`) can be kept
whatever it ranks, while it has not fallen. Where every sample is in trouble (cost above
``trouble_cost``, fallen, or fallen in its tail), the search goes back 1, then 2, ... up
to ``backtracks`` segments and samples again, within ``budget`` (see
:class:`controller.config.OfflineConfig`). Where every kept state has fallen, the search
stops and the rest runs on the servos alone. Deterministic for a seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controller.config import DEFAULT, ControllerConfig


def upper_body_servos(model) -> np.ndarray:
    """Which servos move the upper body: their joint's body is neither on the chain from
    the pelvis to a foot (``lfoot``, ``rfoot``) nor below a foot.

    Returns
    -------
    numpy.ndarray
        Bool, shape ``(nu,)``: the arms, the trunk, the neck and the head True; the hips,
        knees, ankles and toes False.
    """
    import mujoco

    legs = set()
    for name in ("lfoot", "rfoot"):
        foot = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        if foot < 0:
            raise ValueError(f"the model has no {name} body (not a humanoid_xml model?)")
        body = foot
        while body > 0:  # the foot and the bodies above it, up to the world
            legs.add(body)
            body = int(model.body_parentid[body])
        legs.update(b for b in range(model.nbody) if _below(model, b, foot))
    bodies = model.jnt_bodyid[model.actuator_trnid[:, 0]]
    return np.array([int(b) not in legs for b in bodies], dtype=bool)


def _below(model, body: int, ancestor: int) -> bool:
    while body > 0:
        body = int(model.body_parentid[body])
        if body == ancestor:
            return True
    return False


def servo_sigma_rad(model, sigma_deg: float, upper_share: float) -> np.ndarray:
    """Standard deviation of each servo's sampled correction, rad, shape ``(nu,)``:
    ``sigma_deg`` in the legs, ``upper_share * sigma_deg`` in the upper body
    (:func:`upper_body_servos`)."""
    share = np.where(upper_body_servos(model), upper_share, 1.0)
    return math.radians(sigma_deg) * share


@dataclass(frozen=True, eq=False)
class _Node:
    """A state the search reached at the end of a segment."""

    parent: _Node | None
    state: np.ndarray  # (nstate,) full physics state at the segment's end
    delta: np.ndarray  # (nu,) the correction at the segment's end, rad
    ctrl: np.ndarray  # (steps, nu) the segment's servo targets
    cost: float
    fell: bool
    on_plan: bool = False  # every correction so far zero: the plan's own path


@dataclass(frozen=True)
class SearchOutcome:
    """What the search chose.

    Attributes
    ----------
    ctrl : ndarray, shape ((T-1) * substeps, nu)
        The servo targets of every physics step.
    rollouts : int
        Rollouts simulated (of one segment each; the servos-alone rest not counted).
    steps : int
        Physics steps simulated in all.
    passes : float
        Steps simulated over one pass: ``samples`` times the motion's steps, plus every
        segment's lookahead tails (at most the budget).
    backtracks : int
        Times the search went back.
    segments : int
    searched_segments : int
        Segments searched before every kept state had fallen (all of them if none).
    segment_cost : ndarray, shape (segments,)
        The chosen path's cost per segment (NaN past the search).
    """

    ctrl: np.ndarray
    rollouts: int
    steps: int
    passes: float
    backtracks: int
    segments: int
    searched_segments: int
    segment_cost: np.ndarray


def segment_bounds(n_frames: int, fps: float, segment_s: float) -> list[int]:
    """Frame boundaries of the segments: 0, F, 2F, ..., T-1 (F = segment_s in frames,
    at least 1; the last segment may be shorter)."""
    step = max(1, round(segment_s * fps))
    bounds = list(range(0, n_frames - 1, step)) + [n_frames - 1]
    return bounds


def search(model, plan, config: ControllerConfig = DEFAULT, progress: bool = False,
           keep_plan_path: bool = False) -> SearchOutcome:
    """The search over the servo targets of a free-root tracking plan.

    Parameters
    ----------
    model : mujoco.MjModel
        The humanoid (for the features; the plan's copy is simulated).
    plan : controller.tracking.plan.TrackingPlan
        A ``"free"`` plan (:func:`controller.tracking.plan.plan_tracking`).
    config : controller.config.ControllerConfig
        Its ``offline`` section and ``falls``.
    progress : bool
        A progress bar (segments) on a terminal.
    keep_plan_path : bool
        Keep the plan's own path (no correction) among the kept states while it has not
        fallen, however it ranks (the warm start's: the real-time controller's run,
        :mod:`controller.offline.warm`), so that the search can always fall back on it.
    """
    from controller.body import body_figures
    from controller.offline.cost import FeatureMaker
    from controller.offline.rollouts import Roller
    from upm.core.progress import progress as progress_bar

    off = config.offline
    sim, substeps = plan.model, plan.substeps
    n_frames = plan.reference_qpos.shape[0]
    bounds = segment_bounds(n_frames, plan.fps, off.segment_s)
    n_seg = len(bounds) - 1
    features = FeatureMaker(sim)
    ref = features.reference(plan.reference_qpos, plan.fps)
    figures = body_figures(model)
    rng = np.random.default_rng(off.seed)
    sigma = servo_sigma_rad(sim, off.sigma_deg, off.upper_sigma_share)
    fresh = math.sqrt(max(0.0, 1.0 - off.coherence ** 2))
    nu = sim.nu
    # a pass: every segment's samples, and its lookahead's tails
    tail_steps = (off.lookahead_top * max(1, round(off.lookahead_s * plan.fps)) * substeps
                  if off.lookahead_s > 0 else 0)
    one_pass = off.samples * plan.steps + n_seg * tail_steps
    limit_steps = off.budget * one_pass
    with Roller(sim, off.threads) as roller:
        start = _Node(None, roller.state_of(plan.start_qpos, plan.start_qvel),
                      np.zeros(nu), np.empty((0, nu)), 0.0, False, True)
        kept: list[list[_Node]] = [[start]] + [[] for _ in range(n_seg)]
        fails = [0] * n_seg
        rollouts = steps = backtracks = 0
        j = 0
        searched = n_seg
        bar = progress_bar(total=n_seg, desc="offline search", unit="segment",
                           disable=None if progress else True)
        while j < n_seg:
            parents = kept[j]
            a, b = bounds[j] * substeps, bounds[j + 1] * substeps
            owner = np.arange(off.samples) % len(parents)
            noise = rng.standard_normal((off.samples, nu)) * sigma
            noise[:len(parents)] = 0.0  # the first of each parent: its correction decayed
            before = np.stack([parents[i].delta for i in owner])
            delta = off.coherence * before + fresh * noise
            w = (np.arange(1, b - a + 1) / (b - a))[None, :, None]
            ctrl = plan.ctrl[None, a:b] + (1 - w) * before[:, None] + w * delta[:, None]
            states = roller.run(np.stack([parents[i].state for i in owner]), ctrl)
            rollouts += off.samples
            steps += off.samples * (b - a)
            frames = np.arange(bounds[j] + 1, bounds[j + 1] + 1)
            at = (frames - bounds[j]) * substeps - 1  # the step that ends each frame
            cost, fell, down = _score(roller.qpos(states[:, at]), roller.qvel(states[:, at]),
                                      frames, ref, features, figures, config)
            trouble = (cost > off.trouble_cost) | fell
            ahead = np.zeros(off.samples)
            if off.lookahead_s > 0:
                ahead, tail_fell, tail_down, tail_steps = _lookahead(
                    roller, plan, states[:, -1], delta, cost, bounds[j + 1],
                    lambda q, v, f: _score(q, v, f, ref, features, figures, config), off)
                steps += tail_steps
                trouble |= tail_fell
                down |= tail_down
            order = rank(cost, ahead, down, off.upright_first)[:off.keep]
            on_plan = [i for i in range(len(parents)) if parents[i].on_plan]
            if keep_plan_path and on_plan and not fell[on_plan[0]] \
                    and on_plan[0] not in order:
                order = np.append(order[:off.keep - 1], on_plan[0])
            if trouble.all() and fails[j] < off.backtracks:
                back = min(fails[j] + 1, j)
                again = (b - bounds[j - back] * substeps) + (plan.steps - b)
                redo = back + 1 + (n_seg - j - 1)  # segments again and still ahead
                if steps + off.samples * again + tail_steps * redo <= limit_steps:
                    fails[j] += 1
                    backtracks += 1
                    bar.update(-back)
                    j -= back
                    continue
            kept[j + 1] = [_Node(parents[owner[i]], states[i, -1].copy(), delta[i],
                                 ctrl[i], float(cost[i]), bool(fell[i]),
                                 i < len(parents) and parents[owner[i]].on_plan)
                           for i in order]
            bar.update(1)
            j += 1
            if all(node.fell for node in kept[j]):
                searched = j
                break
        bar.close()
    path = []
    node = kept[searched][0]
    while node.parent is not None:
        path.append(node)
        node = node.parent
    path.reverse()
    chosen = plan.ctrl.copy()
    seg_cost = np.full(n_seg, np.nan)
    for k, node in enumerate(path):
        chosen[bounds[k] * substeps:bounds[k + 1] * substeps] = node.ctrl
        seg_cost[k] = node.cost
    return SearchOutcome(ctrl=chosen, rollouts=rollouts, steps=steps,
                         passes=steps / one_pass if one_pass else 0.0, backtracks=backtracks,
                         segments=n_seg, searched_segments=searched, segment_cost=seg_cost)


def rank(cost, ahead, down, upright_first: bool = True) -> np.ndarray:
    """The samples best first: by segment cost plus lookahead ``cost + ahead``, then by
    segment cost, then by index; with ``upright_first``, every sample out of trouble
    (``down`` False) before every sample in it.

    Parameters
    ----------
    cost, ahead : ndarray, shape (N,)
    down : ndarray of bool, shape (N,)
    upright_first : bool

    Returns
    -------
    ndarray of int, shape (N,)
    """
    keys = (np.arange(cost.shape[0]), cost, cost + ahead)
    if upright_first:
        keys += (np.asarray(down, dtype=bool),)
    return np.lexsort(keys)


def _lookahead(roller, plan, end_states, delta, cost, end_frame, score, off):
    """The cost the lookahead adds to each sample, shape (N,): the
    ``off.lookahead_top`` samples cheapest over their segment are rolled on for
    ``off.lookahead_s`` from their ``end_states`` (N, nstate) at frame ``end_frame`` with
    their correction ``delta`` (N, nu) held (past the motion's end, its last targets and
    its last frame as the reference), and get ``lookahead_weight`` times the tail's mean
    cost plus ``fall_cost`` where the tail fell; the others get infinity (never kept
    before one that was looked ahead). Also whether each tail fell and whether its last
    frame is in trouble (N, each; the others: True), and the physics steps simulated."""
    n = cost.shape[0]
    substeps, n_frames = plan.substeps, plan.reference_qpos.shape[0]
    tail = max(1, round(off.lookahead_s * plan.fps))
    top = np.lexsort((np.arange(n), cost))[:off.lookahead_top]
    top = top[np.isfinite(cost[top])]
    ahead = np.full(n, np.inf)
    fell = np.ones(n, dtype=bool)
    down = np.ones(n, dtype=bool)
    if top.size == 0:
        return ahead, fell, down, 0
    rows = np.arange(end_frame * substeps, (end_frame + tail) * substeps)
    rows = np.minimum(rows, plan.ctrl.shape[0] - 1)
    ctrl = plan.ctrl[None, rows] + delta[top][:, None]
    states = roller.run(end_states[top], ctrl)
    at = np.arange(1, tail + 1) * substeps - 1
    frames = np.minimum(end_frame + np.arange(1, tail + 1), n_frames - 1)
    total, tail_fell, tail_down = score(roller.qpos(states[:, at]), roller.qvel(states[:, at]),
                                        frames)
    mean = total - off.fall_cost * tail_fell
    ahead[top] = off.lookahead_weight * mean + off.fall_cost * tail_fell
    fell[top] = tail_fell
    down[top] = tail_down
    return ahead, fell, down, top.size * rows.size


def _score(qpos, qvel, frames, ref, features, figures, config):
    """Each sample's cost (mean over its frames, ``fall_cost`` added where it fell),
    whether it fell, and whether its last frame is in trouble by the real-time search's
    test (:func:`controller.balance.search.trouble_rule`; fallen or not finite count as
    in trouble): ``qpos`` (N, F, nq), ``qvel`` (N, F, nv) at the reference's ``frames``
    (F,); three arrays of shape (N,)."""
    from controller.balance.search import in_trouble
    from controller.falls import fallen
    from controller.offline.cost import Features, state_cost

    n, f, nq = qpos.shape
    flat = qpos.reshape(n * f, nq)
    velocity = qvel.reshape(n * f, qvel.shape[-1])
    finite = np.all(np.isfinite(flat), axis=1) & np.all(np.isfinite(velocity), axis=1)
    sim = features(np.where(finite[:, None], flat, 0.0),
                   np.where(finite[:, None], velocity, 0.0))
    idx = np.tile(frames, n)
    ref_at = Features(*(getattr(ref, name)[idx] for name in Features.__dataclass_fields__))
    cost = state_cost(sim, ref_at, config.offline.weights).reshape(n, f)
    down = fallen(sim.root_height_m, sim.head_height_m, ref_at.root_height_m,
                  ref_at.head_height_m, figures, config.falls).reshape(n, f)
    down |= ~finite.reshape(n, f)
    fell = down.any(axis=1)
    total = cost.mean(axis=1) + config.offline.fall_cost * fell
    total[~finite.reshape(n, f).all(axis=1)] = np.inf
    last = np.arange(n) * f + f - 1
    down = in_trouble(sim.root_height_m[last], sim.head_height_m[last], sim.root_quat[last],
                      ref_at.root_height_m[last], ref_at.head_height_m[last],
                      ref_at.root_quat[last], config.search)
    return total, fell, down | fell | ~finite.reshape(n, f).all(axis=1)
