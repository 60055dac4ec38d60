"""The package's layers import only downwards, and nothing imports the command line.

Layers, lowest first (``docs/architecture.md``):

    trussid._util                 leaf: imports nothing of trussid
    trussid.fem, trussid.plid,    fem and plid never import each other; geometry is
      trussid.geometry            the testbed's parametric description
    trussid.testbed               fem + geometry (the thesis testbed as an FE application)
    trussid.plots                 figures of plid results (no FE)
    trussid.lqg                   LQG design and evaluation (plid's frequency response and poles)
    trussid.campaign, .updating,  workflows composing the layers below
      .study
    trussid.cli                   parses, calls the library, prints; imported by nobody

Every import statement counts, including those inside functions (they exist to keep
``trussid --help`` fast, not to hide a dependency).

Inside each package the modules import each other without a cycle (imports inside
functions count: they hide a cycle from Python, not from a reader), and the library
imports trussid modules at module top: at most :data:`MAX_DEFERRED` imports inside
functions, each with the reason on its line (the command line's ``run()`` functions defer
on purpose, for ``trussid --help``, and are not counted).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Source folder of each installed subpackage (pyproject maps fem/, plid/, geometry/).
SOURCES = {
    "trussid.fem": ROOT / "fem",
    "trussid.plid": ROOT / "plid",
    "trussid.geometry": ROOT / "geometry",
    "trussid": ROOT / "trussid",
}

#: Which trussid subpackages each may import (besides itself and ``trussid._util``).
ALLOWED = {
    "trussid._util": set(),
    "trussid.fem": set(),
    "trussid.plid": set(),
    "trussid.geometry": set(),
    "trussid.testbed": {"trussid.fem", "trussid.geometry"},
    "trussid.lqg": {"trussid.plid"},
    "trussid.plots": {"trussid.plid"},
    "trussid.campaign": {"trussid.fem", "trussid.plid", "trussid.geometry", "trussid.testbed",
                         "trussid.plots", "trussid.lqg", "trussid.updating"},
    "trussid.updating": {"trussid.fem", "trussid.plid", "trussid.geometry", "trussid.testbed",
                         "trussid.plots"},
    "trussid.study": {"trussid.fem", "trussid.plid", "trussid.geometry", "trussid.testbed",
                      "trussid.plots", "trussid.lqg", "trussid.campaign", "trussid.updating"},
    "trussid.cli": {"*"},
}
TOP_LEVEL = {"trussid"}  # the bare package: __version__ only


def _module_name(path: Path) -> str:
    for package, folder in sorted(SOURCES.items(), key=lambda kv: -len(str(kv[1]))):
        if folder in path.parents:
            rel = path.relative_to(folder).with_suffix("")
            parts = [p for p in rel.parts if p != "__init__"]
            return ".".join([package, *parts])
    raise AssertionError(path)


def _layer(module: str) -> str | None:
    """The layer of a trussid module name (its first two components)."""
    parts = module.split(".")
    if parts[0] != "trussid":
        return None
    if len(parts) == 1:
        return "trussid"
    if parts[1] == "__main__":  # `python -m trussid` is the command line
        return "trussid.cli"
    return ".".join(parts[:2])


def _imports(path: Path, module: str):
    tree = ast.parse(path.read_text(), filename=str(path))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module
            if name == "trussid":  # `from trussid import fem` imports trussid.fem
                for alias in node.names:
                    if not alias.name.startswith("__"):  # __version__ is the bare package's
                        yield node.lineno, f"trussid.{alias.name}"
            else:
                yield node.lineno, name


def library_files():
    for package, folder in SOURCES.items():
        for path in sorted(folder.rglob("*.py")):
            if package == "trussid" and any(path.is_relative_to(f) for f in SOURCES.values() if f != folder):
                continue
            yield path


def _shown(path: Path) -> str:
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def violations(paths=None) -> list[str]:
    """Every upward or sideways import, as ``file:line: A imports B``."""
    found = []
    for path in paths or library_files():
        module = _module_name(path)
        layer = _layer(module)
        if layer in TOP_LEVEL:
            continue
        allowed = ALLOWED.get(layer)
        if allowed is None:
            found.append(f"{_shown(path)}: layer {layer} is not declared in ALLOWED")
            continue
        for line, name in _imports(path, module):
            target = _layer(name) if name else None
            if target is None or target in (layer, "trussid._util"):
                continue
            if target == "trussid.cli" or ("*" not in allowed and target not in allowed):
                found.append(f"{_shown(path)}:{line}: {layer} imports {name}")
    return found


def test_every_import_points_down_the_layers_and_nothing_imports_the_cli():
    assert violations() == []


def test_bare_top_level_names_are_not_used():
    """``fem``, ``plid`` and ``geometry`` are only ever imported under ``trussid``."""
    bad = []
    for folder in (*SOURCES.values(), ROOT / "tests", ROOT / "examples", ROOT / "benchmarks"):
        for path in folder.rglob("*.py"):
            for line, name in _imports(path, "x.y"):
                if name and name.split(".")[0] in ("fem", "plid", "geometry"):
                    bad.append(f"{path.relative_to(ROOT)}:{line}: {name}")
    assert bad == []


@pytest.mark.parametrize("source, message", [
    ("from trussid.testbed.model import build_testbed\n", "trussid.fem imports trussid.testbed.model"),
    ("from trussid.fem.model import Model\n", "trussid.plid imports trussid.fem.model"),
    ("import trussid.cli\n", "imports trussid.cli"),
    ("from trussid import plots\n", "trussid.plid imports trussid.plots"),
])
def test_an_upward_import_is_caught(tmp_path, monkeypatch, source, message):
    """The check itself: a planted upward import in fem or plid is reported."""
    package = "trussid.fem" if "testbed" in source else "trussid.plid"
    folder = tmp_path / package.split(".")[1]
    folder.mkdir()
    (folder / "planted.py").write_text(source)
    monkeypatch.setitem(SOURCES, package, folder)
    found = violations([folder / "planted.py"])
    assert len(found) == 1 and message in found[0]


# --------------------------------------------------------------------------- inside packages


#: Most imports of trussid modules inside library functions (issue 22: about 120 before).
MAX_DEFERRED = 20


def _module_index() -> dict[str, Path]:
    return {_module_name(p): p for p in library_files()}


def _target(name: str, alias: str | None, modules) -> str | None:
    """The library module an import statement loads: ``from a.b import c`` is ``a.b.c``
    when that is a module, else ``a.b``."""
    if alias is not None and f"{name}.{alias}" in modules:
        return f"{name}.{alias}"
    return name if name in modules else None


def _edges(path: Path, module: str, modules):
    """``(line, imported module)`` for every import of a library module in ``path``."""
    tree = ast.parse(path.read_text(), filename=str(path))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name in modules:
                    yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module
            for alias in node.names:
                target = _target(name, alias.name, modules)
                if target is not None:
                    yield node.lineno, target


def import_cycles(paths=None) -> list[str]:
    """Every import cycle among the modules of one package, one line each:
    ``import cycle in trussid.plid (2 modules: a, b): trussid.plid.a -> trussid.plid.b
    (plid/a.py:12) -> trussid.plid.a (plid/b.py:30)``.

    Tarjan's strongly connected components over the import graph restricted to each
    package (the edges between packages are :func:`violations`' business); for each
    component with more than one module (or a module importing itself) one cycle through
    it is shown with the file and line of each import.
    """
    files = list(paths or library_files())
    index = {_module_name(p): p for p in files}
    graph: dict[str, dict[str, int]] = {m: {} for m in index}
    for module, path in index.items():
        for line, target in _edges(path, module, index):
            if _layer(target) == _layer(module) and target != _layer(module):
                graph[module].setdefault(target, line)  # the package's __init__ is a leaf
    order, low, stack, on_stack, components = {}, {}, [], set(), []

    def connect(v):  # Tarjan, recursive: a package has a few dozen modules
        order[v] = low[v] = len(order)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in order:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], order[w])
        if low[v] == order[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            components.append(comp)

    for v in sorted(graph):
        if v not in order:
            connect(v)
    found = []
    for comp in components:
        members = set(comp)
        if len(comp) == 1 and comp[0] not in graph[comp[0]]:
            continue
        start = min(comp)
        path, seen, v = [start], {start}, start
        while True:  # walk inside the component until a module repeats: that is a cycle
            v = min(w for w in graph[v] if w in members)
            if v in seen:
                path = path[path.index(v):] + [v]
                break
            path.append(v)
            seen.add(v)
        hops = [f"{b} ({_shown(index[a])}:{graph[a][b]})" for a, b in zip(path, path[1:])]
        short = ", ".join(m.rpartition(".")[2] for m in sorted(comp))
        found.append(f"import cycle in {_layer(start)} ({len(comp)} modules: {short}): "
                     f"{path[0]} -> " + " -> ".join(hops))
    return found


def test_no_package_imports_itself_in_a_circle():
    assert import_cycles() == []


def test_a_planted_cycle_is_caught(tmp_path, monkeypatch):
    """The check itself: three plid modules in a loop, two edges inside functions."""
    folder = tmp_path / "plid"
    folder.mkdir()
    (folder / "a.py").write_text("from trussid.plid.b import x\n")
    (folder / "b.py").write_text("def f():\n    from trussid.plid import c\n")
    (folder / "c.py").write_text("def g():\n    import trussid.plid.a\n")
    (folder / "d.py").write_text("from trussid.plid.a import y\n")  # into the loop, not in it
    monkeypatch.setitem(SOURCES, "trussid.plid", folder)
    found = import_cycles(sorted(folder.glob("*.py")))
    assert found == [
        "import cycle in trussid.plid (3 modules: a, b, c): trussid.plid.a -> "
        f"trussid.plid.b ({folder}/a.py:1) -> trussid.plid.c ({folder}/b.py:2) -> "
        f"trussid.plid.a ({folder}/c.py:2)"]


def deferred_imports(paths=None) -> list[tuple[str, str]]:
    """Imports of trussid modules inside functions of the library (the command line's
    excepted), as ``(file:line, source line)``."""
    found = []
    for path in paths or library_files():
        if _layer(_module_name(path)) == "trussid.cli":
            continue
        text = path.read_text()
        lines = text.splitlines()
        tree = ast.parse(text, filename=str(path))
        for func in ast.walk(tree):
            if not isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(func):
                if isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom):
                    names = ["trussid" if node.level else (node.module or "")]
                else:
                    continue
                if any(n == "trussid" or n.startswith("trussid.") for n in names):
                    found.append((f"{_shown(path)}:{node.lineno}",
                                  " ".join(lines[node.lineno - 1:node.end_lineno])))
    return sorted(set(found))


def test_library_imports_trussid_modules_at_module_top():
    """At most MAX_DEFERRED imports inside functions, each saying why on its line."""
    found = deferred_imports()
    silent = [f"{where}: {line.strip()}" for where, line in found if "#" not in line]
    assert silent == [], "a deferred import without its reason:\n" + "\n".join(silent)
    assert len(found) <= MAX_DEFERRED, (
        f"{len(found)} imports of trussid modules inside library functions (at most "
        f"{MAX_DEFERRED}):\n" + "\n".join(w for w, _ in found))
