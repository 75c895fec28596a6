"""``upm bench``: every benchmark runs (quick mode) and reports finite figures."""

import json
import math

from upm.cli import main


def _numbers(obj):
    if isinstance(obj, dict):
        for v in obj.values():
            yield from _numbers(v)
    elif isinstance(obj, list):
        for v in obj:
            yield from _numbers(v)
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        yield obj


def test_bench_quick_writes_json(tmp_path, data_dir, capsys):
    out = tmp_path / "bench.json"
    assert main(["bench", "--data", str(data_dir), "--quick", "--out", str(out)]) == 0
    report = json.loads(out.read_text())
    assert report == json.loads(capsys.readouterr().out)
    assert "io" in report["benchmarks"]
    io = report["benchmarks"]["io"]
    assert io["frames"] > 0 and io["parse_us_per_frame"] > 0 and io["fk_us_per_frame"] > 0
    assert all(math.isfinite(x) for x in _numbers(report))
    # BLAS pinned for the whole run; the interleaved figures carry their reference and
    # a ratio inside the range of the per-round ratios.
    assert report["blas_threads"] == [1]
    maps = report["benchmarks"]["posture_map"]
    assert maps["upm_train_identical_neurons"] is True
    # the busier of two workers: at least the slowest class, at most all of them
    class_cpu = [c["train_cpu_s"] for c in maps["classes"].values()]
    assert 0 < max(class_cpu) <= maps["upm_train_cpu_s_busier_of_two_workers"]
    assert maps["upm_train_cpu_s_busier_of_two_workers"] <= maps["upm_train_cpu_s"]
    for kind in ("single", "batched"):
        low, high = maps[f"key_posture_ratio_{kind}_range"]
        assert low <= maps[f"key_posture_ratio_{kind}"] <= high
        assert maps[f"reference_ckdtree_4_classes_us_{kind}"] > 0
    methods = report["benchmarks"]["transitions"]["methods"]
    assert methods["upm"]["ratio_to_reference"] > 0 and methods["linear"]["us_per_transition"] > 0
    # every issue-13 target sits beside its figure, judged by the same-run ratio too
    for bench, names in (("posture_map", ("upm_train_s", "key_posture_us_single",
                                          "key_posture_us_batched")),
                         ("transitions", ("upm", "linear")), ("studio", ("slider_to_scene_ms",))):
        for name in names:
            entry = report["benchmarks"][bench]["targets"][name]
            assert entry["met"] == (entry["value"] <= entry["target"])
            if "ratio" in entry:
                assert entry["met_by_ratio"] == (entry["ratio"] <= entry["target_ratio"])
    assert maps["targets"]["key_posture_us_single"]["value"] == maps["key_posture_us_single"]
    # the studio's slider move, through its server-side API on a running server
    studio = report["benchmarks"]["studio"]
    low, high = studio["slider_to_scene_ratio_range"]
    assert low <= studio["slider_to_scene_ratio_to_reference"] <= high
    assert 0 < studio["slider_to_scene_ms"] <= studio["slider_to_scene_and_curve_ms"]
    assert studio["window_frames"] == 20 and studio["method"] == "upm"


def test_bench_unknown_name(data_dir, capsys):
    assert main(["bench", "--data", str(data_dir), "--only", "nope"]) == 2
    assert "no benchmark 'nope'" in capsys.readouterr().err
