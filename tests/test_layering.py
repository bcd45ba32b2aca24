"""The plug-in levels never import the platform, and the platform's modules import each other in one direction."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LEVELS = ("sources", "processors", "controllers")
"""The plug-in levels."""


@pytest.mark.timeout(180)  # a cold import of every module, in a child bounded at 120 s
def test_levels_load_without_the_platform() -> None:
    script = (
        "import importlib, pkgutil, sys\n"
        f"for level in {LEVELS!r}:\n"
        "    package = importlib.import_module(level)\n"
        "    for info in pkgutil.walk_packages(package.__path__, level + '.'):\n"
        "        if info.name.endswith('__main__'):\n"
        "            continue\n"
        "        try:\n"
        "            importlib.import_module(info.name)\n"
        "        except ImportError as exc:\n"
        "            if not (exc.name or '').split('.')[0] in ('picamera2', 'ultralytics', 'onnxruntime', 'torch'):\n"
        "                raise\n"
        "print(sorted(name for name in sys.modules if name.split('.')[0] == 'uav_tui'))\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=True,
                          cwd=ROOT)
    assert done.stdout.strip() == "[]", done.stdout


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, name: str, modules: set[str]) -> set[str]:
    """The modules of ``modules`` that ``path`` names in any import statement: at module level, in a function
    or under ``TYPE_CHECKING`` (a type-only import still ties the two modules together)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[:len(package.split(".")) - node.level + 1] + [base]).strip(".")
            names = [base] + [f"{base}.{alias.name}" for alias in node.names]
        else:
            continue
        for imported in names:
            while imported and imported not in modules:
                imported = imported.rpartition(".")[0]
            if imported and imported != name:
                found.add(imported)
    return found


def _cycle(graph: dict[str, set[str]]) -> list[str]:
    """One import circle in ``graph`` (module -> modules it imports), or [] when there is none."""
    done: set[str] = set()
    path: list[str] = []

    def visit(module: str) -> list[str]:
        if module in path:
            return path[path.index(module):] + [module]
        if module in done:
            return []
        path.append(module)
        for imported in sorted(graph[module]):
            if cycle := visit(imported):
                return cycle
        path.pop()
        done.add(module)
        return []

    for module in sorted(graph):
        if cycle := visit(module):
            return cycle
    return []


def test_cycle_finder_finds_a_circle() -> None:
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) == []


def test_no_import_circle_in_the_platform() -> None:
    """Helpers (operations, recorder, replay, relays) are given the parts they use, the web page sees the core through a
    Protocol, and none imports the core back."""
    paths = {_module_name(path): path for path in (ROOT / "uav_tui").rglob("*.py")}
    graph = {name: _imports(path, name, set(paths)) for name, path in paths.items()}
    assert {"uav_tui.operations", "uav_tui.recording", "uav_tui.web"} <= graph["uav_tui.core"]  # edges are seen
    assert _cycle(graph) == []


def test_the_platforms_top_level_stays_small() -> None:
    """A newcomer reads ``uav_tui/`` from its folder listing: at most 15 modules, the rest in packages by subject."""
    modules = sorted(p.name for p in (ROOT / "uav_tui").glob("*.py") if p.name not in ("__init__.py", "__main__.py"))
    assert len(modules) <= 15, modules


def test_modules_and_classes_stay_readable_in_one_sitting() -> None:
    """No module over 400 lines and no class over 300, in the code and its tests (#40): past that, split by job."""
    too_long = []
    for path in sorted(p for folder in ("uav_tui", "controllers", "processors", "sources", "tests", "scripts")
                       for p in (ROOT / folder).rglob("*.py")):
        text = path.read_text()
        if (lines := len(text.splitlines())) > 400:
            too_long.append(f"{path.relative_to(ROOT)}: {lines} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef) and (lines := (node.end_lineno or 0) - node.lineno + 1) > 300:
                too_long.append(f"{path.relative_to(ROOT)}: class {node.name}, {lines} lines")
    assert too_long == []


def _roots(path: Path) -> set[str]:
    """The top-level packages ``path`` imports absolutely, in any import statement (type-only and lazy ones too)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and not node.level:
            found.add((node.module or "").split(".")[0])
    return found


def test_the_value_types_are_a_leaf() -> None:
    """``uav_values`` imports only the standard library and NumPy: every level may import it, it imports none."""
    allowed = set(sys.stdlib_module_names) | {"numpy", "uav_values", "__future__"}
    found = set().union(*(_roots(path) for path in (ROOT / "uav_values").rglob("*.py")))
    assert found and found <= allowed, found - allowed


@pytest.mark.parametrize("level", LEVELS)
def test_a_level_imports_no_other_level_and_not_the_platform(level: str) -> None:
    """What the levels share lives in ``uav_values`` (the camera model, the telemetry, the outputs' types): a
    processor imports no source, a source no controller, none of them the platform."""
    forbidden = {*LEVELS, "uav_tui"} - {level}
    found = sorted(f"{path.relative_to(ROOT)} imports {root}" for path in (ROOT / level).rglob("*.py")
                   for root in _roots(path) & forbidden)
    assert found == []
