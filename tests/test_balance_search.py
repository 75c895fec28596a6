"""The balance controller's pieces that need no long simulation: marker dropouts filled
on the real clip 16_15 (and nothing touched on a clean clip), the reference put on the
floor, and the backtracking search's bookkeeping (which segment is run again in which
mode, within its reach and budget)."""

import math

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from controller import to_qpos
from controller.balance import search as balance_search
from controller.balance.control import torque_model
from controller.balance.follow import follow
from controller.balance.report import BalanceTracking
from controller.balance.run import replay
from controller.config import DEFAULT
from controller.dropouts import fill_dropouts
from controller.qpos import joint_layout

SEARCH, MODES = DEFAULT.search, DEFAULT.modes


def test_16_15_left_arm_dropout_filled(catalog):
    motion = catalog.load("16_15")
    from humanoid_xml import build_mjcf

    model = mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("16")))
    qpos = to_qpos(model, motion)
    filled, count = fill_dropouts(model, qpos)
    layout = joint_layout(model)
    arm = [a for n, a in zip(layout.names, layout.qpos_address, strict=True)
           if n.startswith("lhumerus.")]
    # the raw clip: the left arm at exactly zero for 2 frames, then 76 degrees away
    assert np.all(qpos[:2, arm] == 0.0)
    assert np.abs(np.rad2deg(qpos[2, arm])).max() > 70
    # filled: held at the first frame after the dropout; nothing else changes
    assert count >= 2
    np.testing.assert_allclose(filled[:3, arm], np.repeat(qpos[2:3, arm], 3, axis=0), atol=1e-12)
    others = np.ones(model.nq, dtype=bool)
    for n, a in zip(layout.names, layout.qpos_address, strict=True):
        if n.split(".")[0] in {"lhumerus", "lradius", "lwrist", "lhand", "lfingers",
                               "lthumb", "lclavicle"}:
            others[a] = False
    np.testing.assert_array_equal(filled[:, others], qpos[:, others])


def test_clean_clip_untouched(model02, walk):
    qpos = to_qpos(model02, walk)
    filled, count = fill_dropouts(model02, qpos)
    assert count == 0
    np.testing.assert_array_equal(filled, qpos)


@pytest.fixture
def search_with(model02):
    """A search of 20 segments at 120 fps with a configuration: ``(search, data,
    frames per segment)``."""

    def make(config=DEFAULT):
        sim = torque_model(model02)
        data = mujoco.MjData(sim)
        fps, every = 120.0, int(round(config.search.segment_s * 120.0))
        n_frames = 20 * every
        ref_pelvis, ref_head = np.full(n_frames, 1.0), np.full(n_frames, 1.6)
        head = mujoco.mj_name2id(sim, mujoco.mjtObj.mjOBJ_SITE, "head_end")
        s = balance_search.Search(sim, n_frames, fps, 5, (ref_pelvis, ref_head), (1, head),
                                  config=config)
        return s, data, every
    return make


@pytest.fixture
def search(search_with):
    return search_with()


def _run_to(search, data, t):
    for frame in range(search.restart, t + 1):
        data.time = frame  # marks the state each segment was saved in
        search.enter(data, frame)


def test_search_retries_then_backtracks(search):
    s, data, every = search
    sweep = SEARCH.sweep_modes
    t = 2 * every + 5  # in segment 2
    _run_to(s, data, t)
    # the segment in trouble runs again in each mode of the sweep, from its saved start
    for mode in sweep:
        assert s.retry(data, t, steps=0) == 2 * every + 1
        assert s.mode(t) == mode
        assert data.time == 2 * every + 1
        _run_to(s, data, t)
    # no modes left there: the segment before it; segment 2 starts over in its mode,
    # and the segments after keep it for search.sticky_s, then go back to the default
    assert s.retry(data, t, steps=0) == every + 1
    first = sweep[0]
    assert s.mode(every + 1) == first and s.mode(t) == first
    last_sticky = 1 + s.sticky
    assert s.modes()[:last_sticky + 2].tolist() == [0] + [first] * s.sticky + [first, 0]
    assert s.retries == len(sweep) + 1


def test_each_frame_reads_the_mode_its_segment_ran_in(search):
    """The per-frame modes the report splits errors by are the search's own: frame t's
    steps ran in mode ``Search.mode(t)``."""
    s, data, every = search
    t = 2 * every + 5
    _run_to(s, data, t)
    s.retry(data, t, steps=0)
    s.retry(data, t, steps=0)
    modes = balance_search.frame_modes(s.modes(), s.n_frames, s.fps)
    assert modes.shape == (s.n_frames,)
    assert modes[1:].tolist() == [s.mode(f) for f in range(1, s.n_frames)]
    assert modes[0] == modes[1] and set(modes.tolist()) == {0, SEARCH.sweep_modes[1]}
    assert balance_search.frame_modes([], 3, s.fps).tolist() == [0, 0, 0]


def test_trouble_is_a_low_pelvis_or_a_bent_over_body(search):
    """In trouble: the pelvis 12 cm below the reference's, or the head 25 cm below it
    with the pelvis up (bent over at the waist), or the pelvis tilted."""
    s, data, every = search
    sim = s.sim
    data.qpos[:] = sim.qpos0
    data.qpos[2] = 1.0
    mujoco.mj_kinematics(sim, data)
    pelvis, head = data.xpos[s.pelvis_body, 2], data.site_xpos[s.head_site, 2]
    t = every
    s.ref_pelvis[t], s.ref_head[t] = pelvis + 0.05, head + 0.1
    assert not s.in_trouble(data, t)
    s.ref_pelvis[t] = pelvis + 0.15
    assert s.in_trouble(data, t)
    s.ref_pelvis[t], s.ref_head[t] = pelvis + 0.05, head + 0.3
    assert s.in_trouble(data, t)
    # tilted 60 degrees about x, at the reference's heights
    s.ref_pelvis[t], s.ref_head[t] = pelvis, head
    data.qpos[3:7] = [np.cos(np.pi / 6), np.sin(np.pi / 6), 0.0, 0.0]
    mujoco.mj_kinematics(sim, data)
    s.ref_head[t] = data.site_xpos[s.head_site, 2]
    assert s.in_trouble(data, t)
    # ... unless the reference bends over as far: 60 degrees is trouble only where the
    # reference tilts less than 45 (02_10, washing, bends its pelvis 43 degrees over)
    for ref_tilt_deg, trouble in ((0.0, True), (40.0, True), (50.0, False), (60.0, False)):
        s.up_limit[t] = balance_search.tilt_limits([math.cos(math.radians(ref_tilt_deg))])[0]
        assert s.in_trouble(data, t) == trouble, ref_tilt_deg


def test_tilt_limit_follows_the_reference_only_where_it_bends_over():
    margin = SEARCH.trouble_tilt_margin_deg
    limit_deg = math.degrees(math.acos(SEARCH.trouble_up))
    ref_tilt_deg = np.linspace(0.0, 180.0, 721)
    limits = balance_search.tilt_limits(np.cos(np.radians(ref_tilt_deg)))
    # the fixed limit, exactly, wherever the reference is more than the margin inside it
    inside = ref_tilt_deg < limit_deg - margin - 1e-9
    assert np.all(limits[inside] == SEARCH.trouble_up)
    # beyond: the reference's tilt plus the margin; never past upside down
    np.testing.assert_allclose(np.degrees(np.arccos(limits[~inside])),
                               np.minimum(180.0, ref_tilt_deg[~inside] + margin), atol=1e-6)
    assert np.all(np.diff(limits) <= 0)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(
    lambda q: sum(v * v for v in q) > 1e-3))
def test_up_axis_z_is_mujocos_rotation_matrix_element(quat):
    unit = np.asarray(quat) / np.linalg.norm(quat)
    matrix = np.empty(9)
    mujoco.mju_quat2Mat(matrix, unit)
    assert balance_search.up_axis_z(quat) == pytest.approx(matrix[8], abs=1e-12)


def test_the_searchs_reference_tilt_is_the_pelvis_body_tilt(model02, catalog):
    """The search reads the reference's tilt off its root quaternion: the same as the
    pelvis body's ``xmat[8]`` after forward kinematics, on a real clip that bends over."""
    from controller.qpos import free_joint

    motion = catalog.load("02_10")
    qpos = to_qpos(model02, motion)[::40]
    joint = free_joint(model02)
    adr, body = model02.jnt_qposadr[joint], model02.jnt_bodyid[joint]
    data = mujoco.MjData(model02)
    expected = []
    for q in qpos:
        data.qpos[:] = q
        mujoco.mj_kinematics(model02, data)
        expected.append(data.xmat[body, 8])
    np.testing.assert_allclose(balance_search.up_axis_z(qpos[:, adr + 3:adr + 7]), expected,
                               atol=1e-12)
    # the clip bends the pelvis past the fixed limit: the limit follows it there
    assert min(expected) < SEARCH.trouble_up


def test_search_gives_up_out_of_reach_or_budget(search):
    s, data, every = search
    t = 2 * every + 5
    _run_to(s, data, t)
    assert s.retry(data, t, steps=int(s.budget_steps)) is None
    assert not s.in_trouble(data, t + 1)  # quiet from then on
    assert s.modes().tolist() == [0] * len(s.modes())


def test_search_records_each_trouble_and_how_it_ended(search):
    """Each trouble the search works on is recorded where the character first got into it,
    with its cause, the retries and the simulated time they ran again, and its outcome: got
    past (an attempt went on beyond its segment) or given up (budget spent)."""
    s, data, every = search
    sim = s.sim
    data.qpos[:] = sim.qpos0
    data.qpos[2] = 1.0
    mujoco.mj_kinematics(sim, data)
    s.ref_pelvis[:] = data.xpos[s.pelvis_body, 2] + 0.2  # the pelvis 20 cm low everywhere
    s.ref_head[:] = data.site_xpos[s.head_site, 2]
    t = 2 * every + 5
    _run_to(s, data, t)
    assert s.retry(data, t, steps=0) == 2 * every + 1
    _run_to(s, data, t - 2)  # the next attempt gets into trouble sooner
    assert s.retry(data, t - 2, steps=0) == 2 * every + 1
    (first,) = s.troubles()
    one, two = SEARCH.sweep_modes[:2]  # the sweep's first two modes
    restarts, rerun_s = np.zeros(len(MODES), int), np.zeros(len(MODES))
    restarts[[one, two]] = 1
    # segment 2 ran again in the first (from its start to frame t), then in the second
    rerun_s[one], rerun_s[two] = 5 / 120.0, 3 / 120.0
    assert first._replace(rerun_s=0.0, rerun_s_by_mode=()) == balance_search.SearchTrouble(
        frame=t, time_s=t / 120.0, cause=("pelvis low",), retries=2, rerun_s=0.0,
        outcome="got past",  # open: so far
        restarts_by_mode=tuple(restarts), rerun_s_by_mode=(), last_mode=two)
    assert first.rerun_s == pytest.approx((5 + 3) / 120.0)
    np.testing.assert_allclose(first.rerun_s_by_mode, rerun_s)
    later = 4 * every + 7  # an attempt got past segment 2, into trouble in segment 4
    _run_to(s, data, later)
    assert s.retry(data, later, steps=0, failed=True) == 4 * every + 1
    _run_to(s, data, later - 3)  # sooner again, with the budget spent: the best again
    assert s.retry(data, later - 3, steps=int(s.budget_steps)) == 4 * every + 1
    first, second = s.troubles()
    assert first.outcome == "got past" and first.retries == 2
    assert second.frame == later and second.cause == ("simulation failed",)
    assert second.outcome == "budget spent" and second.retries == 2
    assert second.rerun_s == pytest.approx((7 + 4) / 120.0)
    assert sum(r.retries for r in s.troubles()) == s.retries
    for trouble in s.troubles():
        assert sum(trouble.restarts_by_mode) == trouble.retries
        assert sum(trouble.rerun_s_by_mode) == pytest.approx(trouble.rerun_s)


def test_search_goes_back_as_far_as_its_reach(search):
    """With every mode tried in the segments in reach but the furthest, the search goes
    back to that one, search.max_backtrack segments before the trouble; with it spent
    too, nothing is left in reach and the run goes on as it is."""
    s, data, every = search
    last, reach = len(MODES) - 1, SEARCH.max_backtrack
    i = reach + 2  # the segment in trouble
    t = i * every + 5
    assert t < s.n_frames
    _run_to(s, data, t)
    s.choice = {j: last for j in range(i - reach + 1, i + 1)}
    assert s.retry(data, t, steps=0) == (i - reach) * every + 1
    assert s.mode((i - reach) * every + 1) == 1
    _run_to(s, data, t)
    s.choice = {j: last for j in range(i - reach, i + 1)}
    s.trouble = None  # a trouble of its own, with no sweep to end
    assert s.retry(data, t, steps=0) is None


def test_search_sweeps_back_one_segment_at_a_time(search):
    """For one trouble the search changes one segment at a time: when segment 2 has run
    in every mode of the sweep, segment 1 takes the next ones with segment 2 back on the
    mode it had (inherited), not every combination of the two."""
    s, data, every = search
    sweep = SEARCH.sweep_modes
    t = 2 * every + 5
    _run_to(s, data, t)
    for _ in sweep:
        assert s.retry(data, t, steps=0) == 2 * every + 1
        _run_to(s, data, t)
    for mode in sweep:
        assert s.retry(data, t, steps=0) == every + 1
        assert s.mode(every + 1) == mode and s.mode(t) == mode  # segment 2 inherits it
        _run_to(s, data, t)
    # an attempt that gets into trouble further on (past segment 1's sticky mode) is a
    # new trouble: searched from there
    i = 2 + s.sticky
    later = i * every + 5
    _run_to(s, data, later)
    assert s.retry(data, later, steps=0) == i * every + 1
    assert s.mode(later) == sweep[0] and s.mode(every + 1) == sweep[-1]


def test_a_sweep_that_finds_nothing_tries_the_combinations(search_with):
    """With the sweep through every segment in reach spent, the search runs the choices
    before it again, from the first segment they differ in, and then backtracks through
    the combinations, nearest segment first."""
    s, data, every = search_with(DEFAULT.updated({"search": {"max_backtrack": 1}}))
    modes, sweep = len(MODES), SEARCH.sweep_modes
    t = 2 * every + 5
    _run_to(s, data, t)
    for _ in range(2 * len(sweep)):  # segment 2's modes in the sweep, then segment 1's
        assert s.retry(data, t, steps=0) is not None
        _run_to(s, data, t)
    assert s.mode(every + 1) == sweep[-1] and set(sweep) < set(range(1, modes))
    # the sweep is spent: segment 1 back in the default mode, run from its start
    assert s.retry(data, t, steps=0) == every + 1
    assert s.mode(every + 1) == 0 and s.mode(t) == 0
    _run_to(s, data, t)
    # the same trouble again: now every combination in every mode, segment 2's first
    for mode in range(1, modes):
        assert s.retry(data, t, steps=0) == 2 * every + 1
        assert s.mode(every + 1) == 0 and s.mode(t) == mode
        _run_to(s, data, t)
    assert s.retry(data, t, steps=0) == every + 1
    assert s.mode(every + 1) == 1 and s.mode(t) == 1


def test_a_sweep_stays_within_reach_of_its_own_trouble(search_with):
    """A sweep whose changes get into trouble sooner than the trouble it sweeps for goes
    back no further than search.max_backtrack segments before that trouble's own segment,
    not before the sooner one's: beyond it, the combinations (the choices before it
    first)."""
    s, data, every = search_with(DEFAULT.updated({"search": {"max_backtrack": 2}}))
    sweep = SEARCH.sweep_modes
    t = 5 * every + 5
    _run_to(s, data, t)
    fail = t
    for segment in (5, 4, 3):  # each in its modes, each attempt in trouble in its own segment
        for _ in sweep:
            assert s.retry(data, fail, steps=0) == segment * every + 1
            fail = segment * every + 5
            _run_to(s, data, fail)
    # segment 2 is within reach of segment 3, where the last attempt got into trouble,
    # but not of segment 5: the sweep is spent, segment 3 back in the default mode
    assert s.retry(data, fail, steps=0) == 3 * every + 1
    assert s.mode(3 * every + 1) == 0 and s.mode(t) == 0


def test_02_01_grounded(model02, walk):
    """02_01's standing frames hover up to 6 cm above the floor once its first frame is on
    it; grounded, they touch it (within the low-pass's smoothing)."""
    from controller.balance.placement import FootPlacement
    from controller.grounding import floor_clearance, ground_reference

    qpos = to_qpos(model02, walk)
    data = mujoco.MjData(model02)
    qpos[:, 2] -= floor_clearance(model02, data, qpos[0])
    down = FootPlacement(model02, qpos, walk.fps).ref_down
    standing = np.flatnonzero(down.any(axis=1))[::4]
    before = np.array([floor_clearance(model02, data, qpos[t]) for t in standing])
    grounded, shift = ground_reference(model02, qpos, walk.fps, down)
    after = np.array([floor_clearance(model02, data, grounded[t]) for t in standing])
    assert before.max() > 0.04
    assert np.median(np.abs(after + DEFAULT.grounding.depth_m)) < 0.005
    assert np.abs(after).max() < 0.02
    # only the root's height moves, and smoothly (no step above 1 mm per frame)
    np.testing.assert_array_equal(np.delete(grounded, 2, axis=1), np.delete(qpos, 2, axis=1))
    assert np.abs(np.diff(shift)).max() < 0.001


def test_search_gives_up_on_the_attempt_that_got_furthest(search):
    s, data, every = search
    far = 2 * every + 10
    _run_to(s, data, far)
    assert s.retry(data, far, steps=0) == 2 * every + 1  # mode 1 for segment 2
    assert s.mode(far) == 1
    near = 2 * every + 3  # the new mode fails sooner, and the budget is spent
    _run_to(s, data, near)
    assert s.retry(data, near, steps=int(s.budget_steps)) == 2 * every + 1
    assert s.mode(far) == 0 and data.time == 2 * every + 1  # the first attempt again
    assert not s.in_trouble(data, far + 1)  # and no more search


def test_a_run_the_search_went_back_in_replays_to_the_same_motion(model02, walk):
    """Trouble everywhere (any pelvis height is 'too low'): the search goes back, tries
    modes, spends its budget and settles on the attempt that got furthest; the torques it
    recorded still replay open-loop to exactly the motion reported."""
    config = DEFAULT.updated({"search": {"trouble_drop_m": -10.0, "budget": 3.0}})
    qpos = to_qpos(model02, walk)[:75]
    run = follow(model02, qpos, walk.fps, config=config)
    assert run.config is config
    assert run.retries > 0
    assert sum(r.retries for r in run.troubles) == run.retries
    assert {r.outcome for r in run.troubles} <= {"budget spent", "no mode within reach"}
    assert all(r.cause == ("pelvis low",) for r in run.troubles)
    assert run.simulated_steps > run.steps
    assert run.segment_modes.max() > 0
    again = replay(model02, run)
    np.testing.assert_allclose(again, run.qpos, atol=1e-9, equal_nan=True)
    # the report takes its errors apart by the frames the search changed and the rest
    # (here the search changed the mode of every segment from the first trouble on)
    figures = BalanceTracking(run).run_summary()
    modes = balance_search.frame_modes(run.segment_modes, run.n_frames, run.fps)
    up = np.flatnonzero(np.isfinite(run.qpos[:, 0]))
    if run.fall_frame is not None:
        up = up[up < run.fall_frame]
    searched = modes[up] != 0
    assert searched.any()
    assert figures["search_mode_share"] == pytest.approx(searched.mean(), abs=1e-5)
    body, joint = run.body_error_mm[up], run.joint_error_deg[up]
    assert figures["body_error_mm_mean_search_modes"] == pytest.approx(
        body[searched].mean(), abs=1e-4)
    assert figures["error_deg_rms_search_modes"] == pytest.approx(
        np.sqrt(np.mean(joint[searched] ** 2)), abs=1e-4)
    if searched.all():  # no frame in the default mode: no figure, not a zero
        assert math.isnan(figures["body_error_mm_mean_default_mode"])
        assert math.isnan(figures["error_deg_rms_default_mode"])
    else:
        assert figures["body_error_mm_mean_default_mode"] == pytest.approx(
            body[~searched].mean(), abs=1e-4)


def test_a_run_without_search_is_all_in_the_default_mode(model02, walk):
    """02_01's first second needs no search: every frame in the default mode, whose
    errors are the whole run's."""
    run = follow(model02, to_qpos(model02, walk)[:121], walk.fps)
    assert run.retries == 0 and not run.segment_modes.any()
    figures = BalanceTracking(run).run_summary()
    assert figures["search_mode_share"] == 0.0
    assert figures["body_error_mm_mean_default_mode"] == figures["body_error_mm_mean"]
    assert figures["error_deg_rms_default_mode"] == figures["error_deg_rms"]
    assert math.isnan(figures["body_error_mm_mean_search_modes"])

