"""Figures: the paper's Fig. 13 (one DOF across the window, UPM vs linear)."""

import pytest

from tests.transition_data import pair, sources
from upm.core.errors import UsageError
from upm.transitions import transition
from upm.transitions.dof_plot import SHOULDER_DOFS, plot_window_dof


@pytest.fixture(scope="module")
def upm_and_linear(data_dir):
    before, after = pair(data_dir, 0)
    return {"upm": transition("upm", before, after, 20, 0.5, sources(data_dir)["upm"]),
            "linear": transition("linear", before, after, 20)}


def test_fig13_is_a_png(upm_and_linear, tmp_path):
    path = tmp_path / "figures" / "fig13.png"
    dof = plot_window_dof(path, upm_and_linear)
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert 20_000 < len(data) < 2_000_000
    assert dof in SHOULDER_DOFS
    assert not [p for p in path.parent.iterdir() if p.name.startswith(".tmp-")]


def test_fig13_named_dof_and_bad_dof(upm_and_linear, tmp_path):
    assert plot_window_dof(tmp_path / "a.png", upm_and_linear, dof="lfemur.rx") == "lfemur.rx"
    with pytest.raises(UsageError, match="no DOF"):
        plot_window_dof(tmp_path / "b.png", upm_and_linear, dof="lfemur.rw")
    assert not (tmp_path / "b.png").exists()
