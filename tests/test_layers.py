"""The layer rule, with no exemptions: which top-level package and which room of ``upm/``
may import which -- module-level and in-function imports, and ``"pkg.mod"`` /
``"pkg.mod:name"`` strings alike -- no import circle between modules, and no module over
400 lines."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit

REPO = Path(__file__).resolve().parent.parent
PACKAGES = ("upm", "humanoid_xml", "controller", "eval", "studio")
_LOWER_UPM = {"upm.core", "upm.ops", "upm.motion", "upm.bvh", "upm.maps", "upm.transitions"}

#: Who may import whom (room -> rooms), lowest first. A room of ``upm/`` is its first
#: subpackage; ``upm.app`` is the application layer (``upm.cli``, ``upm.commands``,
#: ``upm.__main__``), the only code in upm/ that may import the packages above it.
ALLOWED: dict[str, set[str]] = {
    "upm.core": set(),
    "upm.ops": {"upm.core"},
    "upm.motion": {"upm.core", "upm.ops"},
    "upm.bvh": {"upm.core", "upm.ops", "upm.motion"},
    "upm.maps": {"upm.core", "upm.ops", "upm.motion"},
    "upm.transitions": {"upm.core", "upm.ops", "upm.motion", "upm.maps"},
    "upm": set(_LOWER_UPM),
    "humanoid_xml": {"upm.core", "upm.ops", "upm.motion"},
    "controller": {"humanoid_xml"} | _LOWER_UPM,
    "studio": {"controller", "humanoid_xml"} | _LOWER_UPM,
    "eval": {"studio", "controller", "humanoid_xml"} | _LOWER_UPM,
    "upm.app": {"eval", "studio", "controller", "humanoid_xml", "upm"} | _LOWER_UPM,
}
_MODULE_STRING = re.compile(r"((?:" + "|".join(PACKAGES) + r")(?:\.\w+)*)(?::\w+)?")


def _modules() -> dict[str, Path]:
    out = {}
    for package in PACKAGES:
        for path in (REPO / package).rglob("*.py"):
            parts = path.relative_to(REPO).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = path
    return out


def room(module: str) -> str:
    parts = module.split(".")
    if parts[0] != "upm":
        return parts[0]
    if len(parts) == 1:
        return "upm"
    return "upm.app" if parts[1] in ("cli", "commands", "__main__") else f"upm.{parts[1]}"


def imports_of(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """Every project module ``name`` imports (anywhere in the file) or names as a
    ``"pkg.mod[:name]"`` string; a package's own ancestors are left out (Python imports
    them first whatever the code says)."""

    def resolve(target: str) -> str | None:
        while target and target not in modules:
            target = target.rpartition(".")[0]
        return target or None

    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".")[: len(name.split(".")) - node.level
                                      + (path.name == "__init__.py")]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            subs = [f"{module}.{a.name}" for a in node.names if f"{module}.{a.name}" in modules]
            targets = subs if len(subs) == len(node.names) else [module, *subs]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            match = _MODULE_STRING.fullmatch(node.value)
            if match and "." in match.group(1):
                targets = [match.group(1)]
        for target in targets:
            if target.split(".")[0] in PACKAGES:
                resolved = resolve(target)
                if resolved and resolved != name and not name.startswith(resolved + "."):
                    found.add(resolved)
    return found


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    modules = _modules()
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def test_every_room_has_a_rule(graph):
    assert {room(m) for m in graph} <= set(ALLOWED)


def test_imports_follow_the_layers(graph):
    offenders = sorted(f"{a} -> {b}" for a, targets in graph.items() for b in targets
                       if room(b) != room(a) and room(b) not in ALLOWED[room(a)])
    assert not offenders, "imports against the layers:\n" + "\n".join(offenders)


def test_no_import_circle(graph):
    """Tarjan's strongly connected components of the module graph: none of two or more."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert not circles, f"import circles: {circles}"


def test_the_checker_finds_a_circle_and_a_string_import(tmp_path):
    """The rule's own machinery on a made-up pair of modules: an in-function import and a
    ``"pkg.mod:fn"`` string are both edges."""
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("def f():\n    from controller.x import y\n")
    b.write_text("BUILDER = 'upm.motion.z:make'\nDOC = 'see controller.x for more'\n")
    modules = {"upm.motion.z": b, "controller.x": a}
    assert imports_of("upm.motion.z", b, modules) == set()  # a docstring-like text is not one
    assert imports_of("controller.x", a, modules) == set()  # its own name
    assert imports_of("upm.transitions.q", a, modules) == {"controller.x"}
    assert imports_of("upm.transitions.q", b, modules) == {"upm.motion.z"}


def test_no_module_over_400_lines():
    long = [f"{p.relative_to(REPO)} ({n})" for package in PACKAGES
            for p in sorted((REPO / package).rglob("*.py"))
            if (n := len(p.read_text().splitlines())) > 400]
    assert not long, "modules over 400 lines: " + ", ".join(long)


def test_upm_below_the_application_layer_never_imports_mujoco():
    offenders = []
    for name, path in _modules().items():
        if room(name) in _LOWER_UPM | {"upm"}:
            tree = ast.parse(path.read_text())
            for node in ast.walk(tree):
                mods = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                        [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
                offenders += [f"{name}: {m}" for m in mods if m.split(".")[0] == "mujoco"]
    assert not offenders, offenders


def test_rooms_export_their_api():
    import upm
    import upm.motion
    import upm.transitions

    for name in ("read_asf", "read_amc", "write_amc", "forward_kinematics", "Motion",
                 "Skeleton", "Catalog", "UniformPostureMap", "load_map", "transition"):
        assert getattr(upm, name) is not None
    assert upm.motion.Motion is upm.Motion
    assert callable(upm.transitions.transition)


def test_edges_are_found_in_the_real_tree(graph):
    """The graph is not empty by accident: known edges of the code base are in it."""
    assert "upm.motion.skeleton" in graph["upm.motion.kinematics"]
    assert "upm.transitions.feasible_keys" in graph["controller.checks.kinematic_check"]
    assert sum(len(v) for v in graph.values()) > 300
