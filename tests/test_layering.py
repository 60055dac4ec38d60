"""The package's layers import only downwards, and nothing imports the command line.

Layers, lowest first (``docs/architecture.md``):

    trussid._util                 leaf: imports nothing of trussid
    trussid.fem, trussid.plid,    fem and plid never import each other; geometry is
      trussid.geometry            the testbed's parametric description
    trussid.testbed               fem + geometry (the thesis testbed as an FE application)
    trussid.plots                 figures of plid results (no FE)
    trussid.adapt                 closed-loop identification and adaptive redesign (plid, lqg)
    trussid.campaign, .updating,  workflows composing the layers below
      .study, .lqg_study
    trussid.cli                   parses, calls the library, prints; imported by nobody

Every import statement counts, including those inside functions (they exist to keep
``trussid --help`` fast, not to hide a dependency).
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
    "trussid.adapt": {"trussid.plid", "trussid.lqg", "trussid.testbed"},
    "trussid.plots": {"trussid.plid"},
    "trussid.campaign": {"trussid.fem", "trussid.plid", "trussid.geometry", "trussid.testbed",
                         "trussid.plots", "trussid.lqg", "trussid.updating", "trussid.adapt"},
    "trussid.updating": {"trussid.fem", "trussid.plid", "trussid.geometry", "trussid.testbed",
                         "trussid.plots"},
    "trussid.study": {"trussid.fem", "trussid.plid", "trussid.geometry", "trussid.testbed",
                      "trussid.plots", "trussid.lqg", "trussid.campaign", "trussid.updating",
                      "trussid.adapt"},
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
