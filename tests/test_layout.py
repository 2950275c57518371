"""The emulator's layering (emulator/*/__init__.py say what each package may import): no import
cycle between its modules, and no package reaching into a layer above it. Every import counts,
those under TYPE_CHECKING and inside functions too: each is a dependency a reader must follow."""
from __future__ import annotations

import ast
from pathlib import Path

EMULATOR = Path(__file__).resolve().parent.parent / "emulator"

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
