"""One registry: a method registered in one place (its module's record, with how its key
source is built) is usable by ``transition``, the command line and the study."""

import numpy as np
import pytest

from upm.core.errors import UsageError
from upm.transitions import METHODS, TransitionMethod, WindowResult, register
from upm.transitions.base import ROLES
from upm.transitions.registry import (
    KeySourceContext,
    build_key_source,
    map_free_methods,
    methods_with_role,
    unregister,
)

NAME = "test-halfway"


class _AlphaPoint:
    """A key source with no data: the alpha-point of A->B itself."""

    kind = NAME

    def __init__(self, built_from):
        self.built_from = built_from

    def key_posture(self, a_deg, b_deg, alpha=0.5):
        return np.asarray(a_deg) + alpha * (np.asarray(b_deg) - np.asarray(a_deg))


def _solve(problem):
    key = problem.key_source.key_posture(problem.a_deg, problem.b_deg, problem.alpha)
    s = problem.window_times / problem.end_time
    return WindowResult(problem.a_deg + s[:, None] * (problem.b_deg - problem.a_deg),
                        key_posture_deg=key, diagnostics={"built_from_data": 1.0})


def _build(context):
    return _AlphaPoint(context.catalog)


@pytest.fixture
def registered():
    method = register(TransitionMethod(name=NAME, solve=_solve, continuity="C0",
                                       key_kind=NAME, summary="test method",
                                       key_source=_build, key_help="the test's own source"))
    try:
        yield method
    finally:
        unregister(NAME)
    assert NAME not in METHODS


def test_registered_method_runs_in_transition_and_the_cli(registered, synthetic_dir,
                                                           tmp_path, synthetic_catalog):
    from upm.cli import main
    from upm.motion.amc import read_amc
    from upm.transitions import transition
    from upm.transitions.load import key_source_for

    catalog = synthetic_catalog
    source = key_source_for(NAME, None, catalog)
    assert isinstance(source, _AlphaPoint) and source.built_from is catalog
    before = catalog.load("81_01").frames(100, 140)
    after = catalog.load("81_02").frames(20, 60)
    result = transition(NAME, before, after, 10, 0.5, source)
    assert result.method == NAME and result.diagnostics["built_from_data"] == 1.0
    with pytest.raises(UsageError, match="the test's own source"):
        transition(NAME, before, after, 10, 0.5)
    out = tmp_path / "t.amc"
    assert main(["transition", "--data", str(synthetic_dir), "--method", NAME, "--from",
                 "81_01@139", "--to", "81_02@20", "--frames", "10", "--context", "30",
                 "--out", str(out)]) == 0
    written = read_amc(out, catalog.skeleton("81"))
    assert written.n_frames == 30 + 10 + 30


def test_registered_method_runs_in_the_study(registered, data_dir):
    from eval.study import StudyConfig, run_study

    config = StudyConfig(data_dir=str(data_dir), pairs=1, windows=(10,), seed=3,
                         methods=("linear", NAME))
    result = run_study(config, workers=1, show_progress=False)
    scores = result.records
    assert scores.ids("pair", 10, NAME) == scores.ids("pair", 10, "linear") == [0]
    # The same blend as linear, so the same scores: the study ran the registered method.
    assert scores.values("pair", 10, NAME, "valid_pct") == scores.values(
        "pair", 10, "linear", "valid_pct")
    assert np.isfinite(scores.values("pair", 10, NAME, "jerk_rms_deg_s3")).all()


def test_names_are_unique_and_builders_required():
    with pytest.raises(UsageError, match="already registered"):
        register(METHODS["linear"])
    with pytest.raises(UsageError, match="no key_source builder"):
        register(TransitionMethod(name="no-builder", solve=_solve, continuity="C0",
                                  key_kind="x", summary="s"))
    with pytest.raises(UsageError, match="built-in"):
        unregister("upm")


@pytest.mark.parametrize("method", [n for n, m in METHODS.items() if m.needs_map])
def test_a_map_method_without_map_says_so(synthetic_catalog, method):
    with pytest.raises(UsageError, match="needs --map MAP.npz") as info:
        build_key_source(method, KeySourceContext(catalog=synthetic_catalog))
    assert "classnn" in str(info.value)  # and names the methods that need none


def test_a_method_sees_the_windows_root(synthetic_catalog):
    """``transition`` hands every method the shared root of its window (a method may check
    its frames against the floor with it): the root the joined motion gets."""
    from upm.transitions import transition

    seen = []

    def solve(problem):
        seen.append(problem.root_window)
        return _solve(problem)

    name = "test-root"
    register(TransitionMethod(name=name, solve=solve, continuity="C0", key_kind=NAME,
                              summary="test method", key_source=_build))
    try:
        before = synthetic_catalog.load("81_01").frames(100, 140)
        after = synthetic_catalog.load("82_02").frames(20, 60)
        result = transition(name, before, after, 10, 0.5, _AlphaPoint(synthetic_catalog))
    finally:
        unregister(name)
    assert seen[0].shape == (10, 6)
    np.testing.assert_array_equal(seen[0], result.window_root)


def test_get_method_and_register_refuse_clearly():
    from upm.transitions import get_method

    assert get_method("linear") is METHODS["linear"]
    with pytest.raises(UsageError, match="no transition method 'wiggle'") as info:
        get_method("wiggle")
    assert all(name in str(info.value) for name in METHODS)  # lists what there is
    with pytest.raises(UsageError, match="takes a TransitionMethod, not dict"):
        register({"name": "x"})
    with pytest.raises(UsageError, match="role 'star' is not one of"):
        TransitionMethod(name="x", solve=_solve, continuity="C0", key_kind=None,
                         summary="s", role="star")
    unregister("never-registered")  # nothing to remove: no error
    assert "never-registered" not in METHODS


def test_register_unregister_round_trip(registered):
    from upm.transitions import get_method

    assert get_method(NAME) is registered and list(METHODS)[-1] == NAME
    assert registered.needs_key_source and not registered.needs_map
    assert NAME in map_free_methods()


def test_roles_come_from_the_registry():
    """Every method has one of the roles of ``upm.transitions.base.ROLES``; the roles
    partition the registry; one method is recommended, one is the paper's (the UPM's)."""
    assert ROLES == ("recommended", "paper", "paper-comparison", "baseline", "ablation",
                     "performed")
    by_role = {role: methods_with_role(role) for role in ROLES}
    assert sorted(n for names in by_role.values() for n in names) == sorted(METHODS)
    assert all(by_role[role] == [n for n in METHODS if METHODS[n].role == role]
               for role in ROLES)  # in registration (table) order
    assert len(by_role["recommended"]) == 1 and len(by_role["paper"]) == 1
    assert METHODS[by_role["paper"][0]].key_kind == "upm"
    assert by_role["baseline"] and by_role["paper-comparison"]
    assert by_role["performed"] == ["performed"]
    # Whether a method needs --map is a field too, and map_free_methods reads it.
    assert map_free_methods() == [n for n, m in METHODS.items() if not m.needs_map]
    assert {n for n, m in METHODS.items() if m.needs_map} == {"upm", "som", "feasible"}
    assert all(m.needs_key_source for m in METHODS.values() if m.needs_map)
