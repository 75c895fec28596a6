"""The controller's one configuration (controller.config): read back from its dict and from
TOML files, bad files refused in one line naming the file and the key (exit 2 on the
command line), and a run made again from its report's configuration the same run, bit for
bit (file -> run -> report -> configuration -> the same run)."""

import json
import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from controller.config import DEFAULT, SECTIONS, ConfigError, ControllerConfig, load_config
from upm.cli import main

EXPERIMENT = """\
# a placement experiment
[placement]
gain = 0.35

[search]
budget = 5          # a whole number is a number
sweep_modes = [1, 3]

[tracking]
joint_hz = 5.5

[[modes]]
spine_held = true

[[modes]]
swing_clearance_m = 0.04

[[modes]]
placement_gain = 0.6
swing_contacts_excluded = "swing toes"
swing_clearance_m = 0.04

[[modes]]
swing_contacts_excluded = "foot"
swing_clearance_m = 0.04
"""


def test_the_default_configuration_is_read_back_from_its_dict_and_json():
    plain = DEFAULT.as_dict()
    assert list(plain) == list(SECTIONS)
    again = ControllerConfig.from_dict(json.loads(json.dumps(plain)))
    assert again == DEFAULT and again.as_dict() == plain
    # every value is JSON's own type: the report holds numbers, strings, booleans, lists
    assert json.loads(json.dumps(plain, allow_nan=False)) == plain


def test_the_duplicated_constants_are_one_field_each():
    """The 0.3 placement gain: the default mode's, the modes' that name none, and the
    lookahead's first choice; the two frictions are two fields, for two uses."""
    assert DEFAULT.placement.gain == 0.3
    assert DEFAULT.gains == (0.3, 0.6)
    assert [DEFAULT.mode_gain(m) for m in DEFAULT.modes] == [0.3, 0.3, 0.6, 0.3, 0.6, 0.3]
    moved = DEFAULT.updated({"placement": {"gain": 0.4}})
    assert moved.gains[0] == 0.4 and moved.mode_gain(moved.modes[0]) == 0.4
    assert moved.mode_gain(moved.modes[2]) == 0.6  # a mode's own gain stays its own
    assert DEFAULT.contact.friction == 0.8 and DEFAULT.residual.friction == 1.0


def test_a_file_changes_the_keys_it_names(tmp_path):
    path = tmp_path / "experiment.toml"
    path.write_text(EXPERIMENT)
    config = load_config(path)
    assert config.placement.gain == 0.35
    assert config.search.budget == 5.0 and isinstance(config.search.budget, float)
    assert config.search.sweep_modes == (1, 3)
    assert config.tracking.joint_hz == 5.5
    assert len(config.modes) == 4 and config.modes[0].spine_held
    assert config.modes[2].placement_gain == 0.6 and config.modes[1].placement_gain is None
    # the rest are the defaults
    assert replace(config, placement=DEFAULT.placement, search=DEFAULT.search,
                   tracking=DEFAULT.tracking, modes=DEFAULT.modes) == DEFAULT
    assert ControllerConfig.from_dict(config.as_dict()) == config
    empty = tmp_path / "empty.toml"
    empty.write_text("")
    assert load_config(empty) == DEFAULT


@pytest.mark.parametrize("text, key, message", [
    ("[placement]\ngian = 0.3\n", "placement.gian", "unknown key"),
    ("[plaecment]\ngain = 0.3\n", "plaecment", "unknown key"),
    ("[placement]\ngain = 'high'\n", "placement.gain", "must be a number"),
    ("[placement]\ngain = true\n", "placement.gain", "must be a number"),
    ("[placement]\nenabled = 1\n", "placement.enabled", "must be true or false"),
    ("[search]\nmax_backtrack = 2.5\n", "search.max_backtrack", "must be a whole number"),
    ("[search]\nsweep_modes = 3\n", "search.sweep_modes", "must be a list"),
    ("[search]\nsweep_modes = [1, 9]\n", "search.sweep_modes", "ascending indices"),
    ("[search]\nbudget = -1\n", "search.budget", "at least 0"),
    ("[lookahead]\nother_gains = [0.6, 'x']\n", "lookahead.other_gains[1]", "a number"),
    ("placement = 3\n", "placement", "must be a table"),
    ("[[modes]]\nswing_contacts_excluded = 'hand'\n", "modes[0].swing_contacts_excluded",
     "must be one of"),
    ("[spine]\nheld_m = 0.5\n", "spine.free_m", "must be above spine.held_m"),
    ("[placement\ngain = 0.3\n", "line 1", "not a TOML file"),
])
def test_a_bad_file_is_one_line_naming_the_file_and_the_key(tmp_path, text, key, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    error = str(caught.value)
    assert error.startswith(f"{path}: ") and key in error and message in error, error
    assert "\n" not in error


def test_a_missing_file_is_named():
    with pytest.raises(ConfigError, match=r"nosuch\.toml: cannot read the configuration"):
        load_config("nosuch.toml")


@pytest.mark.parametrize("command", [
    ["simulate", "--sequence", "02_01", "--report", "r.json"],
    ["robustness", "--rows", "02_01"],
    ["eval", "--physics"],
])
def test_a_bad_file_on_the_command_line_is_one_line_exit_2(tmp_path, capsys, monkeypatch,
                                                           command):
    """Before any data is read: the commands check the file first."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.toml").write_text("[search]\nbudgit = 3\n")
    assert main([*command, "--data", str(tmp_path / "nodata"), "--config", "bad.toml"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert "bad.toml: unknown key 'search.budgit'" in err
    assert not (tmp_path / "r.json").exists()


def test_the_command_line_budget_is_laid_over_the_file(tmp_path):
    from upm.commands.common import controller_config

    path = tmp_path / "c.toml"
    path.write_text("[search]\nbudget = 5\n[placement]\ngain = 0.35\n")
    args = SimpleNamespace(config=str(path), search_budget=12.0, command="simulate")
    config = controller_config(args)
    assert config.search.budget == 12.0 and config.placement.gain == 0.35
    assert controller_config(SimpleNamespace(config=None, search_budget=None,
                                             command="simulate")) is DEFAULT
    # a section the command does not use is refused, not silently ignored
    path.write_text("[residual]\nfriction = 0.9\n")
    with pytest.raises(ConfigError, match=r"c\.toml: \[residual\] is not used by upm eval"):
        controller_config(SimpleNamespace(config=str(path), search_budget=None,
                                          command="eval"), unused=("residual",))


def test_eval_takes_a_configuration_only_with_physics(tmp_path, capsys):
    (tmp_path / "c.toml").write_text("")
    assert main(["eval", "--data", str(tmp_path), "--config", str(tmp_path / "c.toml"),
                 "--out", str(tmp_path / "out")]) == 2
    assert "--config sets the free-root test's controller" in capsys.readouterr().err


@pytest.mark.physics
def test_a_run_made_again_from_its_report_is_the_same_run(data_dir, catalog, tmp_path,
                                                          capsys):
    """file -> upm simulate -> report -> ControllerConfig.from_dict -> the same run: the
    report's configuration is the file's, and the controller run with it applies the
    same torque at every physics step, bit for bit (and not those of the defaults)."""
    from controller import to_qpos
    from controller.balance.follow import follow
    from humanoid_xml.models import catalog_model_path, load_model
    from upm.transitions import build_sequence

    path = tmp_path / "experiment.toml"
    path.write_text(EXPERIMENT)
    report_path, control = tmp_path / "r.json", tmp_path / "c.npz"
    assert main(["simulate", "--data", str(data_dir), "--sequence", "02_01@0:90",
                 "--method", "linear", "--modes", "free", "--no-window-runs",
                 "--processes", "1", "--config", str(path), "--control", str(control),
                 "--report", str(report_path)]) == 0
    capsys.readouterr()
    report = json.loads(report_path.read_text())
    settings = report["settings"]
    config = ControllerConfig.from_dict(settings["controller_config"])
    assert config == load_config(path) != DEFAULT
    assert settings["tracking"]["search_budget"] == 5.0
    recorded = np.load(control)

    model = load_model(catalog_model_path(catalog, "02_01"))
    motion = build_sequence([catalog.load_ref("02_01@0:90")], "linear").motion
    qpos = to_qpos(model, motion)
    again = follow(model, qpos, motion.fps, config=config)
    np.testing.assert_array_equal(again.start_qpos, recorded["start_qpos"])
    np.testing.assert_array_equal(again.ctrl, recorded["ctrl"])
    free = report["totals"]["tracking"]["free"]
    assert free["fell"] == again.fell
    assert free["search_retries"] == again.retries
    default = follow(model, qpos, motion.fps)
    assert default.ctrl.shape != again.ctrl.shape or not np.array_equal(default.ctrl,
                                                                         again.ctrl)
    assert math.isfinite(free["error_deg_rms"])


def test_the_offline_section_round_trips_and_is_checked(tmp_path):
    path = tmp_path / "offline.toml"
    path.write_text("[offline]\nsamples = 60\nsigma_deg = 4\n\n[offline.weights]\n"
                    "balance = 10\n")
    config = load_config(path)
    assert config.offline.samples == 60 and config.offline.sigma_deg == 4.0
    assert config.offline.weights.balance == 10.0
    assert config.offline.weights.pose == DEFAULT.offline.weights.pose
    assert ControllerConfig.from_dict(json.loads(json.dumps(config.as_dict()))) == config
    assert config.with_threads(1).offline.threads == 1 and config.with_threads(None) == config
    for text, words in (("[offline]\ncoherence = 1.5\n", "offline.coherence must be"),
                        ("[offline]\nsamples = 4\nkeep = 8\n", "offline.keep (8)"),
                        ("[offline]\nsamples = 2.5\n", "offline.samples must be a whole"),
                        ("[offline.weights]\nposes = 1\n", "unknown key 'offline.weights.poses'"),
                        ("[offline]\nbudget = 0.5\n", "offline.budget must be at least 1")):
        path.write_text(text)
        with pytest.raises(ConfigError) as info:
            load_config(path)
        assert words in str(info.value) and "\n" not in str(info.value)
        assert str(info.value).startswith(str(path))


def test_threads_goes_with_the_offline_effort_only(capsys):
    assert main(["simulate", "--sequence", "02_01", "--report", "x.json",
                 "--threads", "2"]) == 2
    assert "--threads is the offline effort's" in capsys.readouterr().err
    assert main(["simulate", "--sequence", "02_01", "--report", "x.json",
                 "--effort", "offline", "--search-budget", "3"]) == 2
    assert "--search-budget is the real-time controller's" in capsys.readouterr().err
