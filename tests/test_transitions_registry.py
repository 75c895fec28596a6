"""One registry: a method registered in one place (its module's record, with how its key
source is built) is usable by ``transition``, the command line and the study."""

import numpy as np
import pytest

from upm.core.errors import UsageError
from upm.transitions import METHODS, TransitionMethod, WindowResult, register
from upm.transitions.registry import KeySourceContext, build_key_source, unregister

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


def test_registered_method_runs_in_transition_and_the_cli(registered, data_dir, tmp_path,
                                                           catalog):
    from upm.cli import main
    from upm.transitions import transition
    from upm.transitions.load import key_source_for

    source = key_source_for(NAME, None, catalog)
    assert isinstance(source, _AlphaPoint) and source.built_from is catalog
    before = catalog.load("02_01").frames(100, 140)
    after = catalog.load("02_03").frames(20, 60)
    result = transition(NAME, before, after, 10, 0.5, source)
    assert result.method == NAME and result.diagnostics["built_from_data"] == 1.0
    with pytest.raises(UsageError, match="the test's own source"):
        transition(NAME, before, after, 10, 0.5)
    out = tmp_path / "t.amc"
    assert main(["transition", "--data", str(data_dir), "--method", NAME, "--from",
                 "02_01@139", "--to", "02_03@20", "--out", str(out)]) == 0
    assert out.stat().st_size > 0


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


def test_a_map_method_without_map_says_so(catalog):
    with pytest.raises(UsageError, match="needs --map MAP.npz"):
        build_key_source("feasible", KeySourceContext(catalog=catalog))


def test_a_method_sees_the_windows_root(catalog):
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
        before = catalog.load("02_01").frames(100, 140)
        after = catalog.load("02_03").frames(20, 60)
        result = transition(name, before, after, 10, 0.5, _AlphaPoint(catalog))
    finally:
        unregister(name)
    assert seen[0].shape == (10, 6)
    np.testing.assert_array_equal(seen[0], result.window_root)
