"""The code base passes its linter (ruff, configured in pyproject.toml)."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent


def test_ruff_check_passes():
    ruff = shutil.which("ruff") or str(Path(sys.executable).parent / "ruff")
    if not Path(ruff).exists():
        pytest.fail("ruff is not installed: pip install -e .[dev]")
    result = subprocess.run([ruff, "check", "--quiet", str(REPO)], capture_output=True,
                            text=True)
    assert result.returncode == 0, result.stdout + result.stderr


def _imported_packages(path: Path) -> set[str]:
    import ast

    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package, forbidden", [
    ("upm", {"eval", "studio", "mujoco", "controller"}),
    ("controller", {"eval", "studio"}),
    ("studio", {"eval"}),
])
def test_data_flows_one_way(package, forbidden):
    """upm/ -> controller/ -> studio/, eval/: no module imports a package downstream of it
    (the CLI's command modules, which run every part, are the one exception)."""
    offenders = [f"{p.relative_to(REPO)} imports {sorted(_imported_packages(p) & forbidden)}"
                 for p in sorted((REPO / package).rglob("*.py"))
                 if "commands" not in p.parts and _imported_packages(p) & forbidden]
    assert not offenders, "\n".join(offenders)
