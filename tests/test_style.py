"""House rules of the library code that a reader relies on, checked on the source.

- A function longer than 80 lines (its docstring not counted: numpydoc parameter tables
  are documentation, not complexity) says why in a comment starting ``# Long:``.
- Library code has no process-wide side effects: no ``matplotlib.use`` (figures are made
  without pyplot, :mod:`trussid.plots`), no warning filter that ignores every category, no
  assignment to ``os.environ`` except the one scoped and restored VTK window selection
  (:func:`trussid.fem.render.offscreen_backend`: VTK reads its window class from the
  environment when a window is created, and pyvista offers no per-plotter choice).
- A broad ``except Exception`` says on its line why (a foreign library's many types).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ("fem", "plid", "geometry", "trussid")
MAX_LINES = 80
ENV_ALLOWED = {("fem/render.py", "offscreen_backend")}


def _files():
    for folder in FOLDERS:
        yield from sorted((ROOT / folder).rglob("*.py"))


def _functions(tree):
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node


def _length(node) -> int:
    n = node.end_lineno - node.lineno + 1
    first = node.body[0] if node.body else None
    if isinstance(first, ast.Expr) and isinstance(getattr(first, "value", None), ast.Constant) \
            and isinstance(first.value.value, str):
        n -= first.end_lineno - first.lineno + 1
    return n


def long_functions_without_reason() -> list[str]:
    found = []
    for path in _files():
        lines = path.read_text().splitlines()
        for node in _functions(ast.parse("\n".join(lines))):
            if _length(node) > MAX_LINES:
                body = lines[node.lineno - 1:node.end_lineno]
                if not any(line.strip().startswith("# Long:") for line in body):
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name} "
                                 f"({_length(node)} lines)")
    return found


def test_long_functions_say_why():
    assert long_functions_without_reason() == []


def test_no_process_wide_side_effects_in_library_code():
    found = []
    for path in _files():
        rel = str(path.relative_to(ROOT))
        text = path.read_text()
        tree = ast.parse(text)
        for node in ast.walk(tree):
            if isinstance(node, ast.Call):
                f = ast.unparse(node.func)
                if f.endswith("matplotlib.use") or f == "use" and "matplotlib" in text:
                    found.append(f"{rel}:{node.lineno}: {ast.unparse(node)}")
                if f.endswith("simplefilter") and len(node.args) == 1 and not node.keywords \
                        and ast.unparse(node.args[0]) in ("'ignore'", '"ignore"'):
                    found.append(f"{rel}:{node.lineno}: {ast.unparse(node)} ignores every warning")
        for fn in _functions(tree):
            for node in ast.walk(fn):
                targets = node.targets if isinstance(node, ast.Assign) else []
                for t in targets:
                    if "os.environ" in ast.unparse(t) and (rel, fn.name) not in ENV_ALLOWED:
                        found.append(f"{rel}:{node.lineno}: {ast.unparse(node)}")
    assert found == []


def test_broad_exception_handlers_say_why():
    found = []
    for path in _files():
        for k, line in enumerate(path.read_text().splitlines(), 1):
            if re.match(r"\s*except (Exception|BaseException)\b", line) and "#" not in line:
                found.append(f"{path.relative_to(ROOT)}:{k}: {line.strip()}")
    assert found == []


def stand_ins() -> list[str]:
    """Objects posing as others: a ``types.SimpleNamespace`` or a class forwarding attributes
    by ``__getattr__`` (a module-level ``__getattr__``, PEP 562's lazy exports, is not one)."""
    found = []
    for path in _files():
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            name = getattr(node, "id", None) or getattr(node, "attr", None) or \
                (node.name if isinstance(node, ast.alias) else None)
            if name == "SimpleNamespace":
                found.append(f"{path.relative_to(ROOT)}:{node.lineno} SimpleNamespace")
            if isinstance(node, ast.ClassDef):
                for item in node.body:
                    if isinstance(item, ast.FunctionDef) and item.name == "__getattr__":
                        found.append(f"{path.relative_to(ROOT)}:{item.lineno} {node.name}.__getattr__")
    return found


def test_no_stand_ins_pose_as_models_or_results():
    assert stand_ins() == []
