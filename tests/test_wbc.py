"""The whole-body QP (controller.balance.wbc) on states of a real free-root walk (02_01):
its compiled set-up (controller.balance.qp_kernels) is the least squares the module
documents, built here again row by row with numpy; the solve that starts from the torque
bounds near binding finds the minimiser of the QP with every bound; the swing leg's damped
least squares is its formula."""

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest
import quadprog

from controller import to_qpos
from controller.balance.control import spine_held
from controller.balance.follow import follow
from controller.balance.leg_kernels import damped_least_squares
from controller.balance.placement import FootPlacement, capture_error_m
from controller.balance.qp_kernels import qp_terms, recall_active, remember_active, solve_active_set
from controller.balance.wbc import WholeBodyID
from controller.checks.contacts import floor_contacts
from controller.config import DEFAULT

CONTACT_DAMPING = DEFAULT.contact.damping_per_s
FORCE_TOLERANCE = DEFAULT.solver.force_tolerance_bw
MULTIPLIER_TOLERANCE = DEFAULT.solver.multiplier_tolerance
SPINE = DEFAULT.spine
#: The default configuration without the search (runs of its default mode alone).
NO_SEARCH = DEFAULT.with_search_budget(0)


@pytest.fixture(scope="module")
def captured_run(model02, walk):
    """``(states, spine_held)``: (solver, data copy, qdd_des, exclude) at every 7th
    control step of 1 s of 02_01, and how firmly the spine was held at every step."""
    captured, held = [], []
    calls = [0]
    torques = WholeBodyID.torques

    def spy(self, data, qdd_des, exclude=(), floor=None, spine_held=0.0):
        held.append(spine_held)
        # every 7th step only: an MjData holds a 16 MB arena, and a process holding
        # hundreds of them cannot fork the balance controller's helper in later tests
        if calls[0] % 7 == 0:
            copy = mujoco.MjData(self.model)
            mujoco.mj_copyData(copy, self.model, data)
            captured.append((self, copy, np.array(qdd_des), exclude))
        calls[0] += 1
        return torques(self, data, qdd_des, exclude, floor, spine_held)

    qpos = to_qpos(model02, walk)[:121]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(WholeBodyID, "torques", spy)
        run = follow(model02, qpos, walk.fps, config=NO_SEARCH)
    assert not run.fell
    return captured, np.array(held)


@pytest.fixture(scope="module")
def states(captured_run):
    return captured_run[0]


def _documented_joint_weights(solver, spine_held):
    """Each hinge row's weight as the module documents it, from the joints' names."""
    w = solver.w
    bodies = [solver.model.joint(int(solver.model.dof_jntid[d])).name.split("_")[0]
              for d in range(6, solver.nv)]
    return np.array([w.joints * (1.0 + (w.spine - 1.0) * spine_held)
                     if body in SPINE.bodies else w.joints for body in bodies])


def _terms(solver, data, exclude):
    model, nv = solver.model, solver.nv
    M = np.zeros((nv, nv))
    mujoco.mj_fullM(model, data, M)
    h = data.qfrc_bias - data.qfrc_passive
    pts, bodies, _ = solver.floor_contacts(data, exclude)
    jacp = np.zeros((3, nv))
    Jc = np.zeros((3 * len(pts), nv))
    for i, (p, b) in enumerate(zip(pts, bodies, strict=True)):
        mujoco.mj_jac(model, data, jacp, None, p, int(b))
        Jc[3 * i:3 * i + 3] = jacp
    return M, h, Jc


def _least_squares_rows(solver, M, h, Jc, qvel, qdd_des, spine_held=0.0):
    """A and b of the rows listed in controller.balance.wbc, and qdd = G x + g0, tau = T x + t0."""
    w, nv = solver.w, solver.nv
    nj, nc = nv - 6, Jc.shape[0] // 3
    nl = 4 * nc
    Jl = np.zeros((nv, nl))
    for i in range(nc):
        Jl[:, 4 * i:4 * i + 4] = (solver.edges @ Jc[3 * i:3 * i + 3]).T * solver.weight_n
    inv = np.linalg.inv(M[:6, :6])
    G = np.zeros((nv, nj + nl))
    G[:6, :nj] = -inv @ M[:6, 6:]
    G[:6, nj:] = inv @ Jl[:6]
    G[6:, :nj] = np.eye(nj)
    g0 = np.zeros(nv)
    g0[:6] = -inv @ h[:6]
    root_w = solver.root_w if nc else solver.root_w * w.flight_root
    T = M[6:] @ G
    T[:, nj:] -= Jl[6:]
    t0 = M[6:] @ g0 + h[6:]
    scale = w.torque / solver.strength
    joint_w = _documented_joint_weights(solver, spine_held)
    rows = [root_w[:, None] * G[:6], joint_w[:, None] * G[6:]]
    rhs = [root_w * (qdd_des[:6] - g0[:6]), joint_w * qdd_des[6:]]
    if nc:
        rows += [w.contact * (Jc @ G), np.hstack([np.zeros((nl, nj)), w.force * np.eye(nl)])]
        rhs += [w.contact * (-CONTACT_DAMPING * (Jc @ qvel) - Jc @ g0), np.zeros(nl)]
    rows.append(scale[:, None] * T)
    rhs.append(-scale * t0)
    return np.vstack(rows), np.concatenate(rhs), G, g0, T, t0


def test_the_spine_is_held_while_the_walk_keeps_to_its_capture_offset(captured_run, model02):
    """On 02_01 the character's capture offset stays near the reference's: the spine is
    held at every step (weight ``spine``); it is eased off linearly as the offsets part
    (the difference carried in the state), and free from ``spine.free_m``."""
    assert np.all(captured_run[1] == 1.0)
    data = mujoco.MjData(model02)
    held = []
    for error in (0.0, SPINE.held_m, 0.5 * (SPINE.held_m + SPINE.free_m), SPINE.free_m, 1.0):
        capture_error_m(data)[:] = error
        held.append(spine_held(data, SPINE))
    assert held == pytest.approx([1.0, 1.0, 0.5, 0.0, 0.0])
    # the configuration's distances, not fixed ones
    wider = replace(SPINE, held_m=0.4, free_m=0.8)
    capture_error_m(data)[:] = 0.6
    assert spine_held(data, wider) == pytest.approx(0.5)


def test_a_mode_without_the_hold_leaves_the_spine_free(model02, walk, monkeypatch):
    """The hold acts only through the spine's rows and only in a mode that asks for it:
    with the default mode's flag off, every step asks for none, and the run is the one of
    a spine weighted like every hinge (the search's other modes are such runs)."""
    qpos = to_qpos(model02, walk)[:61]
    assert [m.spine_held for m in DEFAULT.modes] == [True] + [False] * 5
    free = replace(DEFAULT.modes[0], spine_held=False)
    unheld_config = replace(NO_SEARCH, modes=(free, *DEFAULT.modes[1:]))
    asked = []
    torques = WholeBodyID.torques

    def spy(self, data, qdd_des, exclude=(), floor=None, spine_held=0.0):
        asked.append(spine_held)
        return torques(self, data, qdd_des, exclude, floor, spine_held)

    with monkeypatch.context() as patch:
        patch.setattr(WholeBodyID, "torques", spy)
        unheld = follow(model02, qpos, walk.fps, config=unheld_config)
    assert asked and not any(asked)
    even = NO_SEARCH.updated({"qp": {"spine": DEFAULT.qp.joints}})
    uniform = follow(model02, qpos, walk.fps, config=even)
    np.testing.assert_array_equal(unheld.qpos, uniform.qpos)
    # and the hold does change the run (the test above is not of two equal defaults)
    held = follow(model02, qpos, walk.fps, config=NO_SEARCH)
    assert not np.array_equal(held.qpos, uniform.qpos, equal_nan=True)


def test_states_have_contacts_and_flight_free_steps(states):
    contacts = [len(s.floor_contacts(d, e)[0]) for s, d, _, e in states]
    assert len(states) > 50 and min(contacts) >= 1 and max(contacts) >= 3


def test_floor_contact_scan_is_the_floor_pairs(states):
    """The per-step scan (compiled) finds the contacts whose one geom is the world's, in
    order, and the feet touching the floor are those of its bodies."""
    sides_seen = set()
    for solver, data, _, _ in states:
        model = solver.model
        index, body = floor_contacts(model, data)
        pairs = model.geom_bodyid[data.contact.geom[:data.ncon]].reshape(-1, 2)
        want = np.flatnonzero((pairs[:, 0] == 0) != (pairs[:, 1] == 0))
        np.testing.assert_array_equal(index, want)
        np.testing.assert_array_equal(body, pairs[want].max(axis=1))
        placement = FootPlacement(model, np.array([data.qpos, data.qpos]), 120.0)
        touching = placement.touching(body.tolist())
        for side, name in enumerate(("lfoot", "rfoot")):
            foot = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            on = any(_descends(model, int(b), foot) for b in body)
            assert touching[side] == on
        sides_seen.add(touching)
    # single and double support both occur on the walk
    assert {(True, True), (True, False), (False, True)} <= sides_seen


def _descends(model, body, ancestor):
    while body > 0:
        if body == ancestor:
            return True
        body = int(model.body_parentid[body])
    return False


def test_compiled_terms_are_the_documented_least_squares(states):
    for i, (solver, data, qdd_des, exclude) in enumerate(states):
        held = (i % 3) / 2.0  # the spine free, half held, held
        M, h, Jc = _terms(solver, data, exclude)
        A, b, G, g0, T, t0 = _least_squares_rows(solver, M, h, Jc, data.qvel, qdd_des, held)
        w = solver.w
        root_w = solver.root_w if Jc.shape[0] else solver.root_w * w.flight_root
        P, q, C, d, G_, g0_, T_, t0_ = qp_terms(
            M, h, Jc, data.qvel.copy(), qdd_des, solver.edges, solver.weight_n, root_w,
            solver.joint_weights(held), w.contact, w.force, solver.torque_scale,
            CONTACT_DAMPING, solver.low, solver.high)
        P_ref = A.T @ A + 1e-9 * np.eye(A.shape[1])
        np.testing.assert_allclose(P, P_ref, rtol=1e-9, atol=1e-9 * np.abs(P_ref).max())
        np.testing.assert_allclose(q, A.T @ b, rtol=1e-9, atol=1e-9 * np.abs(A.T @ b).max())
        for got, want in ((G_, G), (g0_, g0), (T_, T), (t0_, t0)):
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
        # C^T x >= d is lambda >= 0 and low <= T x + t0 <= high
        nl = P.shape[0] - (solver.nv - 6)
        x = np.random.default_rng(0).normal(size=P.shape[0])
        tau = T @ x + t0
        np.testing.assert_allclose(C.T @ x - d, np.concatenate(
            [x[solver.nv - 6:], solver.high - tau, tau - solver.low]), atol=1e-6)
        assert C.shape[1] == nl + 2 * (solver.nv - 6)


def test_solve_finds_the_minimiser_with_every_bound(states):
    bound_hit = 0
    for solver, data, qdd_des, exclude in states:
        copy = mujoco.MjData(solver.model)  # the fixture's states stay as captured
        mujoco.mj_copyData(copy, solver.model, data)
        tau, qdd, normal = solver.solve(copy, qdd_des, exclude=exclude)
        M, h, Jc = _terms(solver, data, exclude)
        A, b, G, g0, T, t0 = _least_squares_rows(solver, M, h, Jc, data.qvel, qdd_des)
        n, nl = A.shape[1], A.shape[1] - (solver.nv - 6)
        C = np.hstack([np.vstack([np.zeros((n - nl, nl)), np.eye(nl)]), -T.T, T.T])
        d = np.concatenate([np.zeros(nl), t0 - solver.high, solver.low - t0])
        x = quadprog.solve_qp(A.T @ A + 1e-9 * np.eye(n), A.T @ b, C, d, 0)[0]
        want = (T @ x + t0)[solver.hinge_row]
        scale = np.maximum(1.0, np.abs(want).max())
        np.testing.assert_allclose(tau, want, atol=1e-6 * scale)
        np.testing.assert_allclose(qdd, G @ x + g0, atol=1e-6 * np.abs(G @ x + g0).max())
        low, high = solver.low[solver.hinge_row], solver.high[solver.hinge_row]
        assert np.all(tau <= high + 1e-6) and np.all(tau >= low - 1e-6)
        bound_hit += int(np.any(np.isclose(tau, high) | np.isclose(tau, low)))
        assert normal >= 0.0
    # the walk leans on its torque bounds: the case the trimmed solve must get right
    assert bound_hit > 0


def _cold_minimiser(solver, data, qdd_des, exclude):
    """The hinge torques (actuator order) and P, q, T, t0 of a state, solved from scratch."""
    copy = mujoco.MjData(solver.model)
    mujoco.mj_copyData(copy, solver.model, data)
    copy.userdata[:] = -1.0  # nothing remembered
    tau = solver.solve(copy, qdd_des, exclude=exclude)[0]
    return tau


def test_warm_start_is_taken_and_finds_the_cold_minimiser(states):
    """The active set remembered from the step before (in the state's userdata) mostly
    solves the QP; its torques are the cold solve's to well below a milli-newton-metre."""
    cold_calls = [0]
    cold = WholeBodyID._solve_cold

    def counting(self, *args):
        cold_calls[0] += 1
        return cold(self, *args)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(WholeBodyID, "_solve_cold", counting)
        planned = warm_solves = 0
        for solver, data, qdd_des, exclude in states:
            copy = mujoco.MjData(solver.model)
            mujoco.mj_copyData(copy, solver.model, data)
            before = cold_calls[0]
            tau = solver.solve(copy, qdd_des, exclude=exclude)[0]
            warm = cold_calls[0] == before
            planned += int(len(solver.floor_contacts(data, exclude)[0]) > 0)
            warm_solves += int(warm)
            want = _cold_minimiser(solver, data, qdd_des, exclude)
            np.testing.assert_allclose(tau, want, atol=1e-4, err_msg=f"warm {warm}")
    # from the states as the run left them (its memory of the step before): 156 of the
    # 215 with planned contacts, as over whole runs (72 % of 02_03's contact steps)
    assert warm_solves > 0.6 * planned, (warm_solves, planned)


def test_a_wrong_active_set_is_refused(states):
    """A guessed active set is taken only where it solves the QP: guesses that leave out
    one edge at zero force, or that put one more edge at zero force, are refused (the
    minimiser moves) or give the minimiser (a degenerate edge); never a wrong answer."""
    refused = 0
    for solver, data, qdd_des, exclude in states[::3]:
        M, h, Jc = _terms(solver, data, exclude)
        if not Jc.shape[0]:
            continue
        w = solver.w
        P, q, C, d, G, g0, T, t0 = qp_terms(
            M, h, Jc, data.qvel.copy(), qdd_des, solver.edges, solver.weight_n,
            solver.root_w, solver.joint_weights(0.0), w.contact, w.force,
            solver.torque_scale, CONTACT_DAMPING, solver.low, solver.high)
        nl = P.shape[0] - (solver.nv - 6)
        want = _cold_minimiser(solver, data, qdd_des, exclude)[solver.actuator_of_hinge]
        x_cold = quadprog.solve_qp(P, q, C, d, 0)
        fixed_right = np.zeros(nl, dtype=bool)
        active = x_cold[5][(x_cold[5] >= 1) & (x_cold[5] <= nl)] - 1
        fixed_right[active] = True
        tau_cold = T @ x_cold[0] + t0
        upper = tau_cold >= solver.high - 1e-6 * solver.strength
        lower = tau_cold <= solver.low + 1e-6 * solver.strength
        guesses = [fixed_right]
        for i in range(nl):
            wrong = fixed_right.copy()
            wrong[i] = not wrong[i]
            guesses.append(wrong)
        for n, fixed in enumerate(guesses):
            x, ok = solve_active_set(P, q, T, t0, solver.low, solver.high, nl, fixed,
                                     upper.copy(), lower.copy(), solver.tolerance,
                                     FORCE_TOLERANCE, MULTIPLIER_TOLERANCE)
            if n == 0:
                assert ok  # the right active set is taken
            if ok:
                np.testing.assert_allclose(T @ x + t0, want, atol=1e-4)
            else:
                refused += 1
    assert refused > 0


def test_active_set_memory_round_trip():
    memory = np.zeros(16)
    geoms = np.array([[0, 5], [0, 7], [0, 7]], dtype=np.int32)
    fixed = np.array([1, 0, 0, 1, 0, 0, 0, 0, 1, 1, 1, 1], dtype=bool)
    remember_active(memory, geoms, fixed)
    got, known = recall_active(memory, geoms)
    assert known and np.array_equal(got, fixed)
    assert not recall_active(memory, geoms[[1, 0, 2]])[1]  # another contact order
    assert not recall_active(memory, geoms[:2])[1]
    remember_active(memory, np.zeros((6, 2), dtype=np.int32), np.zeros(24, dtype=bool))
    assert memory[0] == -1 and not recall_active(memory, np.zeros((6, 2), np.int32))[1]
    assert not recall_active(np.zeros(0), geoms)[1]  # a model without user data


def test_damped_least_squares_is_its_formula():
    rng = np.random.default_rng(1)
    for _ in range(50):
        jac = rng.normal(size=(3, 4)) * 0.3
        move = rng.normal(size=3) * 0.1
        want = jac.T @ np.linalg.solve(jac @ jac.T + 0.05 ** 2 * np.eye(3), move)
        want = np.clip(want, -math.radians(45), math.radians(45))
        np.testing.assert_allclose(
            damped_least_squares(jac, move, 0.05, math.radians(45)), want, atol=1e-12)
