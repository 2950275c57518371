"""The emulator's layering (emulator/*/__init__.py say what each package may import): no import
cycle between its modules, and no package reaching into a layer above it. Every import counts,
those under TYPE_CHECKING and inside functions too: each is a dependency a reader must follow.

And the test suite's own layout (tests/README.md): every test file in one of the tiers, no two of
the same name (they are not packages: pytest imports each by its basename), and what tests share
in tests/support, imported by name (pyproject.toml's pythonpath), never from another test file
and never by editing sys.path."""
from __future__ import annotations

import ast
from pathlib import Path

from suite import ROOT

EMULATOR = ROOT / "emulator"

# what each package may import besides itself (emulator.errors, emulator.memory_map and emulator.vtime: everyone)
SHARED = {"emulator.errors", "emulator.memory_map", "emulator.vtime"}
ALLOWED = {
    "emulator.cpu": set(),
    "emulator.devices": set(),
    "emulator.board": {"emulator.cpu", "emulator.devices"},
    "emulator.frontends": {"emulator.cpu", "emulator.devices", "emulator.board"},
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(EMULATOR.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(path): path for path in EMULATOR.rglob("*.py")}


def _imports(name: str, path: Path, known: set[str]) -> set[str]:
    """The emulator modules `name` imports (a package's name stands for its __init__)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[:len(anchor) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            # `from pkg import mod` names a module; `from mod import name` names the module
            targets = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in known else base for alias in node.names]
        else:
            continue
        found.update(target for target in targets if target in known and target != name)
    return found


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    known = set(modules)
    return {name: _imports(name, path, known) for name, path in modules.items()}


def _package(name: str) -> str:
    parts = name.split(".")
    return ".".join(parts[:2])


def test_no_import_cycle():
    graph = _graph()
    state: dict[str, int] = {}     # 1: on the path, 2: done
    path: list[str] = []
    cycles = []

    def visit(node: str) -> None:
        state[node] = 1
        path.append(node)
        for target in sorted(graph[node]):
            if state.get(target) == 1:
                cycles.append(path[path.index(target):] + [target])
            elif target not in state:
                visit(target)
        path.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node)
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(cycle) for cycle in cycles)


def test_packages_import_only_the_layers_below():
    wrong = []
    for name, targets in _graph().items():
        package = _package(name)
        if package not in ALLOWED:
            continue
        for target in targets:
            other = _package(target)
            if other != package and target not in SHARED and other not in ALLOWED[package]:
                wrong.append(f"{name} imports {target}")
    assert not wrong, "\n".join(sorted(wrong))


def test_the_checker_sees_a_cycle_and_a_layer_broken(tmp_path, monkeypatch):
    """The two tests above can fail: on a made-up package with a cycle and a device importing the board."""
    root = tmp_path / "emulator"
    (root / "devices").mkdir(parents=True)
    (root / "board").mkdir()
    (root / "__init__.py").write_text("")
    (root / "devices" / "__init__.py").write_text("")
    (root / "board" / "__init__.py").write_text("")
    (root / "devices" / "a.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                                           "    from ..board.b import B\n")
    (root / "board" / "b.py").write_text("from ..devices import a\n")
    monkeypatch.setattr(__import__(__name__), "EMULATOR", root)
    graph = _graph()
    assert graph["emulator.devices.a"] == {"emulator.board.b"}
    assert graph["emulator.board.b"] == {"emulator.devices.a"}
    try:
        test_no_import_cycle()
    except AssertionError as error:
        assert "emulator.board.b -> emulator.devices.a -> emulator.board.b" in str(error)
    else:
        raise AssertionError("the cycle was not found")
    try:
        test_packages_import_only_the_layers_below()
    except AssertionError as error:
        assert "emulator.devices.a imports emulator.board.b" in str(error)
    else:
        raise AssertionError("the broken layer was not found")


def test_only_cpu_touches_a_hart_s_unicorn():
    """The engines stay behind the hart: outside emulator/cpu/ nothing reaches a hart's Unicorn
    instance (`hart.uc`); the hart's methods (reg, set_reg, map_memory, ...) do it."""
    import re
    offenders = []
    for path in sorted(EMULATOR.rglob("*.py")):
        if path.parent.name == "cpu":
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            if re.search(r"\.uc\b", line.split("#")[0]):
                offenders.append(f"{path.relative_to(EMULATOR.parent)}:{number}: {line.strip()}")
    assert not offenders, "\n".join(offenders)


TESTS = ROOT / "tests"
TIERS = {"unit/cpu", "unit/board", "unit/devices", "unit/frontends", "unit/shared", "unit/tools",
         "firmware_routines", "end_to_end", "slow"}


def _suite_modules() -> list[Path]:
    """The suite's Python files: test files, conftest.py and tests/support (not the C test firmware)."""
    return sorted(path for path in TESTS.rglob("*.py") if "firmware" not in path.relative_to(TESTS).parts[:1])


def test_every_test_file_is_in_a_tier_and_has_a_name_of_its_own():
    files = sorted(TESTS.rglob("test_*.py"))
    outside = [str(path.relative_to(TESTS)) for path in files
               if path.parent.relative_to(TESTS).as_posix() not in TIERS]
    assert not outside, f"test files outside the tiers {sorted(TIERS)}: {outside}"
    names: dict[str, list[str]] = {}
    for path in files:
        names.setdefault(path.name, []).append(str(path.relative_to(TESTS)))
    assert not {name: paths for name, paths in names.items() if len(paths) > 1}
    assert all(any((TESTS / tier).glob("test_*.py")) for tier in TIERS), "a tier without tests"


def test_tests_share_code_through_support_only():
    """No test module imports another test module, and nothing in tests/ edits sys.path."""
    wrong = []
    for path in _suite_modules():
        tree = ast.parse(path.read_text(), str(path))
        where = path.relative_to(TESTS)
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                modules = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                modules = [node.module or ""]
            else:
                modules = []
            wrong += [f"{where}:{node.lineno} imports {module}" for module in modules
                      if module.split(".")[0].startswith("test_") or module.split(".")[0] == "conftest"]
            if isinstance(node, ast.Attribute) and node.attr == "path" and isinstance(node.value, ast.Name) \
                    and node.value.id == "sys":
                wrong.append(f"{where}:{node.lineno} uses sys.path")
    assert not wrong, "\n".join(wrong)
