"""The humanoid's performer of the ``performed`` transition method
(:mod:`upm.transitions.performed`): the transition followed in the offline effort from the
clip's own state a little before the window to a little after it, and the window's frames
as the body did them, back on the subject's joint angles. :func:`install` puts it into
the method's slot (the command line and the study call it)."""

from __future__ import annotations

import numpy as np

from controller.config import DEFAULT

#: The humanoid of each skeleton seen (by identity; the skeleton is kept with it).
_MODELS: dict[int, tuple[object, object]] = {}


def install() -> None:
    """Install :func:`perform_transition` as ``performed``'s performer."""
    from upm.transitions.performed import install_performer

    install_performer(perform_transition)


def humanoid_of(skeleton):
    """The humanoid of an ASF skeleton (built once per skeleton)."""
    import mujoco

    from humanoid_xml import build_mjcf

    key = id(skeleton)
    if key not in _MODELS or _MODELS[key][0] is not skeleton:
        _MODELS[key] = (skeleton, mujoco.MjModel.from_xml_string(build_mjcf(skeleton)))
    return _MODELS[key][1]


def perform_transition(transition, context_s: float | None = None, config=None):
    """What the free-root humanoid did in a transition's window.

    Parameters
    ----------
    transition : upm.transitions.Transition
        The asked transition (its motion and window).
    context_s : float or None
        Seconds of the motion simulated before and after the window (None: the
        configuration's ``window_runs.lead_s`` and ``tail_s``).
    config : controller.config.ControllerConfig or None
        The offline effort's configuration (None: the defaults).

    Returns
    -------
    upm.transitions.performed.PerformedWindow
        The joint angles and root of the whole run (from ``first``, the context before
        the window, to the context after it), and ``figures``: ``joint_error_deg`` (RMS
        over the window's frames and hinges, against the asked window), ``body_error_mm``
        (mean), ``fell`` (1/0: anywhere in the run), ``fell_in_window``, ``left_window``
        (1: fell before the window's end, or the search's chosen path was in trouble in a
        segment that overlaps the window), ``torque_saturation_share`` (the window's
        frames), ``root_drift_m`` (at the window's end), ``join_step_start_deg`` and
        ``join_step_end_deg`` (RMS over the DOFs of the step from the clip into the run, at
        its start from the clip's own state, and from the run's end back to the clip),
        ``context_before_s``, ``context_after_s``, ``rollouts``, ``wall_s``.
    """
    from controller.offline import perform
    from controller.offline.samcon import segment_bounds
    from controller.qpos import from_qpos, to_qpos
    from upm.ops.angles import angle_diff_deg
    from upm.transitions.performed import PerformedWindow

    config = DEFAULT if config is None else config
    motion = transition.motion
    model = humanoid_of(motion.skeleton)
    fps = motion.fps
    n = motion.n_frames
    w0, w1, _ = transition.window.indices(n)
    lead = config.window_runs.lead_s if context_s is None else context_s
    tail = config.window_runs.tail_s if context_s is None else context_s
    a = max(0, w0 - round(lead * fps))
    b = min(n, w1 + round(tail * fps))
    asked = to_qpos(model, motion)
    result = perform(model, asked[a:b], fps, config.updated(
        {"offline": {"warm_start": config.offline.performed_warm_start,
                     "upper_sigma_share": config.offline.performed_upper_sigma_share}}))
    inside = slice(w0 - a, w1 - a)
    qpos = result.qpos
    finite = np.all(np.isfinite(qpos), axis=1)
    qpos = np.where(finite[:, None], qpos, asked[a:b])  # a diverged run: the asked frames
    done = from_qpos(model, qpos, motion.skeleton, fps)
    root = done.root.copy()
    previous = motion.root[a - 1, 3:] if a > 0 else root[0, 3:]
    for t in range(root.shape[0]):  # the root's angles continue from the clip's
        root[t, 3:] = previous + angle_diff_deg(root[t, 3:], previous)
        previous = root[t, 3:]
    posture = done.posture_deg
    declared = motion.skeleton.declared
    fall = result.tracking.fall_frame
    bounds = np.asarray(segment_bounds(b - a, fps, config.offline.segment_s))
    overlap = (bounds[1:] > w0 - a) & (bounds[:-1] < w1 - a)
    trouble = bool(np.any(result.outcome.segment_cost[overlap] > config.offline.trouble_cost))
    fell_in_window = fall is not None and fall < w1 - a
    share = result.tracking.saturation_share(inside)

    def step(x, y):
        return float(np.sqrt(np.mean(angle_diff_deg(x[declared], y[declared]) ** 2)))

    figures = {
        "joint_error_deg": float(np.sqrt(np.nanmean(result.error_deg[inside] ** 2))),
        "body_error_mm": float(np.nanmean(result.body_error_mm[inside])),
        "fell": float(result.fell),
        "fell_in_window": float(fell_in_window),
        "left_window": float(fell_in_window or trouble),
        "torque_saturation_share": float("nan") if share is None else share,
        "root_drift_m": float(result.root_drift_m[inside][-1]),
        "join_step_start_deg": step(posture[0], motion.posture_deg[a - 1]) if a > 0 else 0.0,
        "join_step_end_deg": step(posture[-1], motion.posture_deg[b]) if b < n else 0.0,
        "context_before_s": (w0 - a) / fps,
        "context_after_s": (b - w1) / fps,
        "rollouts": float(result.samples),
        "wall_s": float(result.wall_s),
        "diverged_frames": float(np.count_nonzero(~finite)),
    }
    return PerformedWindow(posture_deg=posture, root=root, figures=figures, first=a)
