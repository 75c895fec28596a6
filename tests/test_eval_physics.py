"""The study's free-root test (``upm eval --physics``) and its executors, on a small real
study: every method's physics figures exist and are finite where the character was up;
the local pool and Ray give the same records; a failing run is reported with its pair and
method, keeps what finished, and a rerun completes only what is missing; the long-form
table refuses a misspelt metric."""

import math

import numpy as np
import pytest

from eval.physics import PHYSICS_METRICS, run_physics
from eval.physics_unit import REALTIME_FIGURES
from eval.records import Records
from eval.runs import StudyIncomplete
from eval.study import STUDY_METHODS, StudyConfig, run_study

PAIRS = 3


@pytest.fixture(scope="module")
def study(data_dir):
    config = StudyConfig(data_dir=str(data_dir), pairs=PAIRS, windows=(20,), seed=3,
                         methods=STUDY_METHODS)
    return run_study(config, workers=2, show_progress=False)


@pytest.fixture(scope="module")
def local_run(study, tmp_path_factory):
    out = tmp_path_factory.mktemp("physics-local")
    return run_physics(study, PAIRS, out, executor="local", workers=2, show_progress=False,
                       effort="realtime")


def test_every_method_and_the_real_windows_have_finite_physics_figures(local_run):
    records = local_run.records
    for method in [*STUDY_METHODS, "real"]:
        kind = "real" if method == "real" else "pair"
        assert records.ids(kind, 20, method) == list(range(PAIRS)), method
        fell = records.values(kind, 20, method, "fell")
        assert set(fell) <= {0.0, 1.0}
        fall_time = records.values(kind, 20, method, "fall_after_window_start_s")
        assert all(math.isnan(t) == (f == 0.0) for f, t in zip(fell, fall_time, strict=True))
        # going down at the end is counted only where the character did not fall
        down = records.values(kind, 20, method, "ends_in_trouble")
        assert set(down) <= {0.0, 1.0} and not np.any((down == 1.0) & (fell == 1.0))
        either = records.values(kind, 20, method, "fell_or_going_down")
        np.testing.assert_array_equal(either, np.maximum(fell, down))
        # in the real-time effort, the real-time controller's figures are the run's own
        for name, figure in REALTIME_FIGURES.items():
            np.testing.assert_array_equal(records.values(kind, 20, method, name),
                                          records.values(kind, 20, method, figure))
        for metric in PHYSICS_METRICS:
            if metric in ("fell", "fall_after_window_start_s", "realtime_fell"):
                continue
            values = records.values(kind, 20, method, metric)
            up = fell == 0.0
            assert all(math.isfinite(v) for v in values[up]), (method, metric, values)
    # The controller must hold the real windows of these clips at least once: the test
    # can fail if the physics is broken.
    assert records.values("real", 20, "real", "fell").min() == 0.0
    errors = records.values("real", 20, "real", "joint_error_deg_rms")
    assert 0.0 < min(e for e in errors if math.isfinite(e)) < 10.0
    statistics = local_run.statistics
    assert {(w, m) for (w, g, m, k) in statistics.summary} == {
        (20, m) for m in [*STUDY_METHODS, "real"]}
    assert set(statistics.compared(20)) == set(STUDY_METHODS) - {"upm"}
    assert {x for (w, x, g, k) in statistics.paired} == set(statistics.compared(20))
    back = Records.from_csv(records.to_csv(), PHYSICS_METRICS, "physics.csv")
    assert back == records


def test_ray_gives_the_same_records_as_the_local_pool(data_dir, tmp_path):
    """On one pair of two methods and its real window (the executors are compared, not
    the methods: the full test above runs every method)."""
    pytest.importorskip("ray")
    config = StudyConfig(data_dir=str(data_dir), pairs=1, windows=(20,), seed=3,
                         methods=("upm", "linear"))
    small = run_study(config, workers=2, show_progress=False)
    local = run_physics(small, 1, tmp_path / "local", executor="local", workers=2,
                        show_progress=False, effort="realtime")
    ray_run = run_physics(small, 1, tmp_path / "ray", executor="ray", workers=2,
                          show_progress=False, effort="realtime")
    assert len(local.records.to_csv().splitlines()) > 3  # a header and the three runs
    assert ray_run.records.to_csv() == local.records.to_csv()
    assert ray_run.statistics == local.statistics


def _fake_figures(unit):
    return {name: float(unit.index + len(unit.method)) for name in PHYSICS_METRICS} | {
        "fell": 0.0, "fall_after_window_start_s": math.nan}


def test_a_failed_run_is_named_kept_and_completed_by_a_rerun(study, tmp_path, monkeypatch):
    import eval.physics as physics

    calls = []

    def failing(model, motion, start, stop, config, effort):
        unit = calls[-1]
        if unit.kind == "pair" and unit.index == 1 and unit.method == "linear":
            raise RuntimeError("the simulation diverged")
        return _fake_figures(unit)

    original_run_unit = physics.run_unit

    def run_unit(unit):
        calls.append(unit)
        return original_run_unit(unit)

    monkeypatch.setattr(physics, "simulate_unit", failing)
    monkeypatch.setattr(physics, "run_unit", run_unit)
    with pytest.raises(StudyIncomplete, match=r"1 of \d+ free-root runs failed.*pair 1, "
                                              r"linear, L = 20.*diverged.*run the same"):
        run_physics(study, PAIRS, tmp_path, workers=1, show_progress=False)
    total = len(calls)
    lines = (tmp_path / "physics-partial.jsonl").read_text().splitlines()
    assert len(lines) == 1 + total - 1  # the settings line and every finished run

    calls.clear()
    monkeypatch.setattr(physics, "simulate_unit",
                        lambda model, motion, start, stop, config, effort: _fake_figures(calls[-1]))
    result = run_physics(study, PAIRS, tmp_path, workers=1, show_progress=False)
    assert [(u.kind, u.index, u.method) for u in calls] == [("pair", 1, "linear")]
    assert result.resumed == total - 1
    assert len(result.records) == total * len(PHYSICS_METRICS)


def test_the_controller_configuration_reaches_the_workers_and_keys_the_checkpoint(
        study, tmp_path, monkeypatch):
    """The configuration given to the free-root test is the one every unit runs with, in
    forked workers too; it is in the checkpoint's settings (a rerun with it resumes, one
    with another configuration starts afresh) and in results.json's physics protocol."""
    import eval.physics as physics
    from controller.config import DEFAULT
    from eval.outputs import physics_document

    def figures_of(model, motion, start, stop, config, effort):
        value = config.placement.gain + (1.0 if effort == "offline" else 0.0)
        return {name: value for name in PHYSICS_METRICS} | {
            "fell": 0.0, "fall_after_window_start_s": math.nan}

    monkeypatch.setattr(physics, "simulate_unit", figures_of)
    other = DEFAULT.updated({"placement": {"gain": 0.45}})
    first = run_physics(study, PAIRS, tmp_path, workers=2, show_progress=False,
                        controller_config=other, effort="realtime")
    assert set(first.records.values("pair", 20, "linear", "joint_error_deg_rms")) == {0.45}
    assert physics_document(first)["protocol"]["controller_config"] == other.as_dict()
    again = run_physics(study, PAIRS, tmp_path, workers=1, show_progress=False,
                        controller_config=other, effort="realtime")
    assert again.resumed == len(again.records) // len(PHYSICS_METRICS) > 0
    default = run_physics(study, PAIRS, tmp_path, workers=1, show_progress=False)
    assert default.resumed == 0
    assert set(default.records.values("real", 20, "real", "joint_error_deg_rms")) == {1.3}
    # the effort keys the checkpoint too, and reaches the workers; the default is offline
    realtime = run_physics(study, PAIRS, tmp_path, workers=2, show_progress=False,
                           effort="realtime")
    assert realtime.resumed == 0
    assert set(realtime.records.values("real", 20, "real", "joint_error_deg_rms")) == {0.3}
    assert physics_document(realtime)["protocol"]["effort"] == "realtime"
    assert physics_document(default)["protocol"]["effort"] == "offline"


@pytest.mark.parametrize("args, effort", [
    (["--physics"], "offline"),
    (["--physics", "--threads", "1"], "offline"),
    (["--physics", "--effort", "realtime"], "realtime"),
    (["--physics", "--effort", "offline"], "offline"),
])
def test_the_free_root_test_is_the_offline_effort_unless_told(args, effort):
    """Issue 61: the physics column asks whether a body can perform the window (the
    offline effort, the real-time controller's figures beside it)."""
    from upm.cli import build_parser
    from upm.commands.eval import physics_effort

    assert physics_effort(build_parser().parse_args(["eval", *args])) == effort


def test_the_offline_effort_performs_a_real_window_with_the_same_figures(study):
    """One real window of the study performed by the offline effort (a small search: 24
    samples, one pass), scored with the real-time test's figures: every figure is there,
    the body stands on the floor (about one body weight on it) and follows the window
    within a few degrees; the real-time controller's figures beside them are those of the
    real-time effort's own run of the window (the search's warm start is that run)."""
    from controller.config import DEFAULT
    from eval.pairs import draw_real_windows
    from eval.physics import Unit, context_frames, unit_motion
    from eval.physics_unit import simulate_unit

    real = {20: draw_real_windows(study.data.lengths, PAIRS, 20, study.config.seed,
                                  context=context_frames(120.0))}
    window = real[20][0]
    model, motion, start, stop = unit_motion(study.data, Unit("real", window.index, 20,
                                                              "real"), {}, real)
    small = DEFAULT.updated({"offline": {"samples": 24, "keep": 4, "budget": 1.0}})
    figures = simulate_unit(model, motion, start, stop, small, effort="offline")
    assert set(figures) == set(PHYSICS_METRICS)
    assert figures["fell"] == 0.0, figures
    assert 0.8 < figures["contact_force_peak_bw"] < 4.0, figures
    assert 0.0 < figures["joint_error_deg_rms"] < 12.0, figures
    assert 0.0 <= figures["torque_saturation_share"] <= 1.0
    realtime = simulate_unit(model, motion, start, stop, small, effort="realtime")
    for name, figure in REALTIME_FIGURES.items():
        assert figures[name] == pytest.approx(realtime[figure], abs=1e-6), name
    with pytest.raises(ValueError, match="unknown effort 'fast'"):
        simulate_unit(model, motion, start, stop, small, effort="fast")


def test_the_long_form_table_refuses_a_misspelt_metric():
    records = Records(PHYSICS_METRICS)
    records.add("pair", 0, 20, "upm", {"fell": 1.0})
    with pytest.raises(KeyError, match="joint_eror_deg_rms"):
        records.add("pair", 0, 20, "upm", {"joint_eror_deg_rms": 1.0})
    with pytest.raises(KeyError, match="fel"):
        records.values("pair", 20, "upm", "fel")
    assert records.to_csv().splitlines() == ["kind,id,window,method,metric,value",
                                             "pair,0,20,upm,fell,1.0"]


@pytest.mark.parametrize("methods, note", [(["linear", "slerp"], "No paired tables"),
                                           (["upm", "som"], "No UPM - linear tables")])
def test_every_methods_subset_writes_a_complete_output(data_dir, tmp_path, methods, note):
    from upm.cli import main

    out = tmp_path / "out"
    assert main(["eval", "--data", str(data_dir), "--pairs", "2", "--windows", "10",
                 "--methods", *methods, "--no-figures", "--out", str(out)]) == 0
    names = {p.name for p in out.iterdir()}
    assert names == {"results.json", "scores.csv", "summary.csv", "paired.csv", "summary.md",
                     "timing.json", "table4.md"}
    assert note in (out / "summary.md").read_text()


def test_a_failing_output_leaves_no_half_written_folder(data_dir, tmp_path, monkeypatch,
                                                        capsys):
    import eval.outputs
    from upm.cli import main

    def broken(*args, **kwargs):
        raise ValueError("the renderer broke")

    monkeypatch.setattr(eval.outputs, "write_figures", broken)
    out = tmp_path / "out"
    with pytest.raises(ValueError, match="renderer"):
        main(["eval", "--data", str(data_dir), "--pairs", "2", "--windows", "10",
              "--methods", "upm", "linear", "--out", str(out)])
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args, message", [
    (["--physics-pairs", "2"], "--physics-pairs goes with --physics"),
    (["--physics", "--physics-pairs", "9"], "between 1 and --pairs (3)"),
    (["--address", "ray://head:10001"], "--address goes with --executor ray"),
    (["--config", "c.toml"], "--config sets the free-root test's controller"),
    (["--physics", "--config", "nosuch.toml"], "nosuch.toml: cannot read"),
    (["--effort", "offline"], "--effort goes with --physics"),
    (["--threads", "2"], "--threads goes with --physics"),
    (["--physics", "--effort", "realtime", "--threads", "2"], "--threads is the offline"),
    (["--physics", "--threads", "0"], "--threads 0: use a whole number from 1 to 64"),
])
def test_bad_physics_arguments_are_one_line_errors(data_dir, tmp_path, capsys, args, message):
    from upm.cli import main

    assert main(["eval", "--data", str(data_dir), "--pairs", "3", "--out",
                 str(tmp_path / "out"), *args]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()
