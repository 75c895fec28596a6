"""The balance controller's backtracking search over its modes (after SAMCON).

Where the character gets into trouble (pelvis or head well below the reference's, or
tilted), the search (:class:`Search`) runs the last segments again in other modes (the
configuration's :attr:`controller.config.ControllerConfig.modes`) from their saved states,
and records each trouble it worked on (:class:`SearchTrouble`). Its constants are the
configuration's ``search`` section (:class:`controller.config.sections.SearchConfig`),
named here ``search.key``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from controller.config import DEFAULT, ControllerConfig


class SearchTrouble(NamedTuple):
    """One trouble the search worked on (:class:`Search`): where the character first got
    into it, why, what the search spent on it, and how it ended.

    Attributes
    ----------
    frame : int
        The frame the first attempt got into trouble at.
    time_s : float
        Its time from the run's start.
    cause : tuple of str
        What the search's test found there (:func:`trouble_rule`): any of ``"pelvis
        low"``, ``"head low"``, ``"tilted"``, or ``"simulation failed"``.
    retries : int
        Segments the search ran again for it (the replay of its best attempt included).
    rerun_s : float
        Simulated seconds those retries ran again (from each restart to the frame the
        attempt before it got into trouble at).
    outcome : str
        ``"got past"`` (an attempt went on beyond the segment in trouble), ``"budget
        spent"`` or ``"no mode within reach"`` (the search gave up and the run went on
        from the attempt that got furthest).
    restarts_by_mode, rerun_s_by_mode : tuple, one entry per mode each
        ``retries`` and ``rerun_s`` by the mode each restart ran its first segment in
        (the segment it changed).
    last_mode : int or None
        The mode the last restart ran its first segment in: for a trouble the search got
        past, the change that got past it (None: no restart).
    """

    frame: int
    time_s: float
    cause: tuple
    retries: int
    rerun_s: float
    outcome: str
    restarts_by_mode: tuple = ()
    rerun_s_by_mode: tuple = ()
    last_mode: int | None = None


class Search:
    """Backtracking over the controller's modes, segment by segment.

    The run is cut into segments of ``search.segment_s``; each runs in one mode, the first
    by default. When the character gets into trouble (pelvis ``search.trouble_drop_m``
    below the reference's, or its up axis tilted below ``search.trouble_up`` and
    ``search.trouble_tilt_margin_deg`` beyond the reference's, or the head
    ``search.trouble_head_drop_m`` below the reference's, or the simulation fails), the
    segment is run again from its saved start state in the next mode; the segments after
    a changed one keep its mode for ``search.sticky_s``. The search first *sweeps* back: for
    one trouble (until an attempt gets into trouble further on) it changes one segment at a
    time, each in the next of ``search.sweep_modes`` after its mode, then the one before it
    (up to ``search.max_backtrack`` back from the trouble's own segment, even when a changed attempt
    gets into trouble earlier), the later ones back on the modes they had before; a sweep
    that finds nothing goes back to the choices before it and tries the combinations in
    every mode, nearest first: when a segment has no modes left, the one before it, and the
    segments after it start again (the search before the sweep, which spent most of its
    budget re-running the nearest segments' combinations: over seeds 0-20 of issue 10's
    rows the sweep made 12 falls of 231 against 25, 5 against 11 on seeds 11-20, not looked
    at when it was chosen, with 60 % fewer segments run again). When the search has spent
    ``search.budget`` times the reference's physics steps, or has tried every mode
    within reach, the attempt that got furthest is run again and the run goes on from it
    (a fall is a fall). SAMCON (Liu et al. 2010) searches the same way, with sampled target
    offsets instead of a few discrete modes.
    """

    def __init__(self, sim, n_frames: int, fps: float, substeps: int, ref_heights_m,
                 watched: tuple[int, int], ref_up_z=None,
                 config: ControllerConfig = DEFAULT):
        """``ref_heights_m``: the reference's pelvis and head heights, (T,) each;
        ``watched``: the pelvis body and the head site; ``ref_up_z``: the vertical
        component of the reference's pelvis up axis, (T,) (:func:`up_axis_z`; None:
        upright throughout); ``config``: its ``search`` section and ``modes`` (the budget
        ``search.budget`` in multiples of the reference's physics steps; 0: no search)."""
        settings = config.search
        self.settings = settings
        self.n_modes = len(config.modes)
        self.sim, self.n_frames = sim, n_frames
        self.every = segment_frames(fps, settings.segment_s)
        self.sticky = int(round(settings.sticky_s / settings.segment_s))
        self.ref_pelvis, self.ref_head = ref_heights_m
        self.up_limit = tilt_limits(np.ones(n_frames) if ref_up_z is None else ref_up_z,
                                    settings)
        self.pelvis_body, self.head_site = watched
        self.budget_steps = settings.budget * (n_frames - 1) * substeps
        self.choice: dict[int, int] = {}
        self.saved: dict[int, object] = {}
        self.quiet_until = 0
        self.retries = 0
        self.restart = 1
        self.best: tuple[int, dict] | None = None
        self.trouble: _Trouble | None = None
        self.fps = float(fps)
        self._records: list[dict] = []  # SearchTrouble's fields, the last one open

    def _segment(self, t: int) -> int:
        return (t - 1) // self.every

    def enter(self, data, t: int) -> None:
        """Save the state at the start of a segment (before frame ``t``'s steps), if the
        segment is entered for the first time since the run was last restarted before it."""
        import mujoco

        if (t - 1) % self.every == 0:
            i = self._segment(t)
            if i not in self.saved:
                copy_ = mujoco.MjData(self.sim)
                mujoco.mj_copyData(copy_, self.sim, data)
                self.saved[i] = copy_

    def _mode_of(self, i: int, choice: dict | None = None) -> int:
        """Segment ``i``'s mode: its own choice, else that of the latest segment before
        it with one, within ``search.sticky_s``, else the default."""
        choice = self.choice if choice is None else choice
        for j in range(i, max(-1, i - self.sticky - 1), -1):
            if j in choice:
                return choice[j]
        return 0

    def mode(self, t: int) -> int:
        """The index in the modes of frame ``t``'s segment."""
        return self._mode_of(self._segment(t))

    def modes(self) -> np.ndarray:
        """The mode of every segment, int array (segments,)."""
        n = self._segment(self.n_frames - 1) + 1
        return np.array([self._mode_of(i) for i in range(n)], dtype=int)

    def in_trouble(self, data, t: int) -> bool:
        """Whether the search acts on trouble at frame ``t`` (it is not resting)."""
        return t > self.quiet_until and self.troubled(data, t)

    def troubled(self, data, t: int) -> bool:
        """Whether the character is in trouble at frame ``t`` (quiet or not)."""
        return bool(self.causes(data, t))

    def causes(self, data, t: int) -> tuple:
        """What puts the character in trouble at frame ``t``: any of ``"pelvis low"``,
        ``"head low"``, ``"tilted"`` (empty: not in trouble)."""
        settings = self.settings
        low = self.ref_pelvis[t] - data.xpos[self.pelvis_body, 2] > settings.trouble_drop_m
        bent = (self.ref_head[t] - data.site_xpos[self.head_site, 2]
                > settings.trouble_head_drop_m)
        tilted = data.xmat[self.pelvis_body, 8] < self.up_limit[t]
        return tuple(name for name, on in (("pelvis low", low), ("head low", bent),
                                           ("tilted", tilted)) if on)

    def troubles(self) -> tuple:
        """Every trouble the search worked on, :class:`SearchTrouble` each (the last one
        got past if the search did not give up on it)."""
        return tuple(SearchTrouble(**{"outcome": "got past", **r,
                                      "restarts_by_mode": tuple(r["restarts_by_mode"]),
                                      "rerun_s_by_mode": tuple(r["rerun_s_by_mode"])})
                     for r in self._records)

    def retry(self, data, t: int, steps: int, failed: bool = False) -> int | None:
        """Restore the state for the next attempt; returns the frame to run from, or
        None (go on as it is). ``failed``: the simulation failed at frame ``t``.

        When the budget is spent or no mode is left within reach, the attempt that got
        furthest before its trouble is run again, if it is not this one, and the search
        rests until past that point.
        """
        if self.best is None or t > self.best[0]:
            self.best = (t, dict(self.choice))
        spent = steps >= self.budget_steps
        i = self._segment(t)
        if self.trouble is None or i > self.trouble.segment:  # a new trouble
            if self._records and "outcome" not in self._records[-1]:
                self._records[-1]["outcome"] = "got past"
            cause = ("simulation failed",) if failed else self.causes(data, t)
            self._records.append(dict(frame=int(t), time_s=t / self.fps, cause=cause,
                                      retries=0, rerun_s=0.0,
                                      restarts_by_mode=[0] * self.n_modes,
                                      rerun_s_by_mode=[0.0] * self.n_modes, last_mode=None))
            if not spent:
                self.trouble = _Trouble(i, i, dict(self.choice))
        back, mode = self._back(t)
        if not spent and back is None and self.trouble is not None and self.trouble.sweeping:
            # the sweep found nothing: the choices before it again, then the combinations
            self.trouble.sweeping = False
            before = self.trouble.choice_before
            differ = [j for j in range(i + 1) if self._mode_of(j) != self._mode_of(j, before)]
            if differ and differ[0] in self.saved:
                return self._restart(data, differ[0], before, t)
            back, mode = self._back(t)
        if spent or back is None:
            return self._give_up(data, t, spent)
        if self.trouble is not None:
            self.trouble.changed = back
        choice = dict(self.choice)
        choice[back] = mode
        return self._restart(data, back, {j: m for j, m in choice.items() if j <= back}, t)

    def _back(self, t: int) -> tuple[int | None, int | None]:
        """The segment a retry at frame ``t`` goes back to and the mode it runs in next
        (the next of ``search.sweep_modes`` while sweeping, else the next mode),
        or ``(None, None)`` (no mode left within reach)."""
        i = self._segment(t)
        back = reach_from = i
        order = range(1, self.n_modes)
        if self.trouble is not None and self.trouble.sweeping and i <= self.trouble.segment:
            # sweeping: nothing after the last changed, and within reach of the trouble's
            # own segment, not of the earlier one its changes got into trouble at (which
            # chased the sweep up to 10 s back, where the combinations found the way)
            back = min(i, self.trouble.changed)
            reach_from = self.trouble.segment
            order = self.settings.sweep_modes
        mode = None
        while back >= 0 and reach_from - back <= self.settings.max_backtrack:
            mode = _next_mode(order, self._mode_of(back))
            if mode is not None:
                break
            back -= 1
        if mode is None or back not in self.saved:  # no mode left within reach
            return None, None
        return back, mode

    def _give_up(self, data, t: int, spent: bool) -> int | None:
        best_t, best_choice = self.best
        self.best = None
        self.trouble = None
        self._records[-1]["outcome"] = "budget spent" if spent else "no mode within reach"
        self.quiet_until = self.n_frames if spent else max(t, best_t) + self.every
        if best_t <= t:
            return None
        differ = [j for j in range(self._segment(best_t) + 1)
                  if self._mode_of(j) != self._mode_of(j, best_choice)]
        first = differ[0] if differ else self._segment(t)
        if first not in self.saved:
            return None
        return self._restart(data, first, best_choice, t, quiet=self.quiet_until)

    def _restart(self, data, segment: int, choice: dict, t: int, quiet: int = 0) -> int:
        """Run again from ``segment``'s saved start with ``choice``, the attempt before
        having got to frame ``t``; returns the frame to run from."""
        import mujoco

        record = self._records[-1]
        rerun_s = (t - segment * self.every) / self.fps
        mode = self._mode_of(segment, choice)
        record["retries"] += 1
        record["rerun_s"] += rerun_s
        record["restarts_by_mode"][mode] += 1
        record["rerun_s_by_mode"][mode] += rerun_s
        record["last_mode"] = mode
        self.choice = choice
        for j in [j for j in self.saved if j > segment]:
            del self.saved[j]
        mujoco.mj_copyData(data, self.sim, self.saved[segment])
        self.quiet_until = quiet
        self.retries += 1
        self.restart = segment * self.every + 1
        return self.restart


def segment_frames(fps: float, segment_s: float = DEFAULT.search.segment_s) -> int:
    """Frames per segment of ``segment_s`` (``search.segment_s``) at ``fps``: frame
    ``t``'s steps (from frame ``t - 1`` to ``t``) belong to segment
    ``(t - 1) // segment_frames(fps, segment_s)``."""
    return max(1, int(round(segment_s * fps)))


def frame_modes(segment_modes, n_frames: int, fps: float,
                segment_s: float = DEFAULT.search.segment_s) -> np.ndarray:
    """The mode each frame was run in (the steps that led to it; frame 0: the first
    segment's), int array (n_frames,), from :meth:`Search.modes` ``(segments,)`` (segments
    of ``segment_s``)."""
    segment_modes = np.asarray(segment_modes, dtype=int)
    if not segment_modes.size:
        return np.zeros(n_frames, dtype=int)
    frames = np.arange(n_frames)
    index = np.maximum(frames - 1, 0) // segment_frames(fps, segment_s)
    return segment_modes[np.minimum(index, segment_modes.size - 1)]


def _next_mode(modes, current: int) -> int | None:
    """The first of ``modes`` (ascending) after mode ``current``, or None (none left)."""
    return next((m for m in modes if m > current), None)


@dataclass(eq=False)
class _Trouble:
    """The trouble the search is working on: the furthest segment an attempt got into
    trouble in, the latest segment changed for it, the choices (segment to mode) before,
    and whether the search is still sweeping back (:class:`Search`)."""

    segment: int
    changed: int
    choice_before: dict
    sweeping: bool = True


def up_axis_z(quat) -> np.ndarray:
    """The vertical component of a body's up axis (its rotation matrix's last element).

    Parameters
    ----------
    quat : array_like, shape (..., 4)
        Orientations, (w, x, y, z), not necessarily of unit norm.

    Returns
    -------
    ndarray, shape (...)
        1 upright, 0 lying, -1 upside down.
    """
    w, x, y, z = np.moveaxis(np.asarray(quat, dtype=float), -1, 0)
    return (w * w - x * x - y * y + z * z) / (w * w + x * x + y * y + z * z)


def tilt_limits(ref_up_z, search=DEFAULT.search) -> np.ndarray:
    """The least up-axis component (``xmat[8]``) of the pelvis out of trouble, per frame:
    ``search.trouble_up``, or lower where the reference tilts to within
    ``search.trouble_tilt_margin_deg`` of it (-1: no tilt is trouble).

    Parameters
    ----------
    ref_up_z : array_like, shape (T,)
        The reference's pelvis up-axis component (:func:`up_axis_z`).
    search : controller.config.sections.SearchConfig

    Returns
    -------
    ndarray, shape (T,)
    """
    ref_tilt = np.arccos(np.clip(np.asarray(ref_up_z, dtype=float), -1.0, 1.0))
    margin = math.radians(search.trouble_tilt_margin_deg)
    beyond = np.cos(np.minimum(np.pi, ref_tilt + margin))
    return np.minimum(search.trouble_up, beyond)


def in_trouble(pelvis_m, head_m, pelvis_quat, ref_pelvis_m, ref_head_m, ref_pelvis_quat,
               search=DEFAULT.search) -> np.ndarray:
    """The search's test for trouble (:func:`trouble_rule`, as :meth:`Search.causes`) on
    many states at once.

    Parameters
    ----------
    pelvis_m, head_m : array_like, shape (N,)
        The pelvis's and the head's heights.
    pelvis_quat : array_like, shape (N, 4)
        The pelvis's orientation (w, x, y, z).
    ref_pelvis_m, ref_head_m, ref_pelvis_quat : array_like, shapes (N,), (N,), (N, 4)
        The reference's, at the same frames.
    search : controller.config.sections.SearchConfig

    Returns
    -------
    ndarray of bool, shape (N,)
        False where a height is NaN and the pelvis upright.
    """
    with np.errstate(invalid="ignore"):
        low = np.asarray(ref_pelvis_m) - np.asarray(pelvis_m) > search.trouble_drop_m
        bent = np.asarray(ref_head_m) - np.asarray(head_m) > search.trouble_head_drop_m
    tilted = up_axis_z(pelvis_quat) < tilt_limits(up_axis_z(ref_pelvis_quat), search)
    return low | bent | tilted


def trouble_rule(search=DEFAULT.search) -> str:
    """The search's test for trouble (:meth:`Search.troubled`) in words (``search``:
    :class:`controller.config.sections.SearchConfig`)."""
    tilt_deg = math.degrees(math.acos(search.trouble_up))
    return (f"in trouble: the pelvis more than {100 * search.trouble_drop_m:.0f} cm below "
            f"the reference's, or the head more than {100 * search.trouble_head_drop_m:.0f} "
            f"cm below the reference's, or the pelvis's up axis more than {tilt_deg:.0f} deg "
            f"from vertical and {search.trouble_tilt_margin_deg:.0f} deg beyond the "
            "reference's tilt")
