"""The unit tier runs as a user without the CMU data would run it.

The checkout is copied to a temporary folder (so no ``../shared/data/cmu`` lies beside
it: :func:`upm.motion.catalog.default_data_dir`'s fallback finds nothing), ``UPM_DATA``
points to an empty folder and ``UPM_CACHE`` to a fresh one, and ``python -m pytest -m
unit`` runs there in a subprocess. Marked ``clone`` (tests/conftest.py), so that it is
not itself part of the unit tier it runs; it takes about as long as the tier.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.clone

REPO = Path(__file__).resolve().parent.parent
#: What a clone does not have (or what is the machine's, not the project's).
_NOT_COPIED = shutil.ignore_patterns(".git", ".venv", "venv", ".pytest_cache", ".ruff_cache",
                                     ".hypothesis", "site", "*.egg-info")


def _environment(tmp_path: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PYTEST_", "UPM_", "HYPOTHESIS_"))}
    (tmp_path / "no-data").mkdir()
    env.update(UPM_DATA=str(tmp_path / "no-data"), UPM_CACHE=str(tmp_path / "cache"))
    env.pop("PYTHONPATH", None)
    return env


def test_the_unit_tier_passes_without_the_data(tmp_path):
    clone = tmp_path / "checkout"
    shutil.copytree(REPO, clone, ignore=_NOT_COPIED)  # keeps mtimes: numba's caches stay valid
    env = _environment(tmp_path)
    # The clone's own packages are the ones imported there, and it finds no data.
    probe = subprocess.run(
        [sys.executable, "-c", "import upm.motion.catalog as c, tests.conftest as t; "
         "print(c.__file__); print(c.default_data_dir()); print(t.have_data())"],
        cwd=clone, env=env, capture_output=True, text=True, check=True)
    module, data, have = probe.stdout.split()
    assert Path(module).is_relative_to(clone), probe.stdout
    assert data == env["UPM_DATA"] and have == "False"
    assert not (clone.parent / "shared").exists()

    result = subprocess.run([sys.executable, "-m", "pytest", "-m", "unit", "-q",
                             "-p", "no:cacheprovider"], cwd=clone, env=env,
                            capture_output=True, text=True)
    output = result.stdout + result.stderr
    assert result.returncode == 0, output[-4000:]
    summary = output.strip().splitlines()[-1]
    counts = {word: int(n) for n, word in re.findall(r"(\d+) (\w+)", summary)}
    assert counts.get("passed", 0) >= 50, summary
    assert not counts.get("failed") and not counts.get("error"), summary
    # No unit test skipped for want of the data (conftest's data fixtures skip with "the
    # CMU data is not at ..."; -ra lists every skip with its reason).
    skipped = [line for line in output.splitlines() if line.startswith("SKIPPED")]
    assert len(skipped) <= counts.get("skipped", 0)
    assert not [line for line in skipped if "CMU data" in line or "UPM_DATA" in line], skipped
