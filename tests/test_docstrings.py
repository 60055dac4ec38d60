"""Every argument of a documented public function is documented (python-control's habit,
``control/tests/docstrings_test.py``; issue 31).

A public library function whose numpydoc docstring has a ``Parameters`` section must name
every one of its arguments there (``a, b : type`` names both). Functions without such a
section (one-line helpers, properties) are not held to it.
"""

from __future__ import annotations

import ast
import re

from tests import test_layering as layering

_SECTION = re.compile(r"\n\s*Parameters\n\s*-{3,}\n(.*?)(?=\n\s*\n\s*[A-Z][A-Za-z ]+\n\s*-{3,}\n|\Z)",
                      re.S)


def documented(doc: str) -> set | None:
    """Names the ``Parameters`` section of ``doc`` documents (None: it has none)."""
    m = _SECTION.search("\n" + doc)
    if not m:
        return None
    lines = [line for line in m.group(1).splitlines() if line.strip()]
    indent = min(len(line) - len(line.lstrip()) for line in lines) if lines else 0
    names = set()
    for line in lines:
        if len(line) - len(line.lstrip()) == indent:
            names |= {n.strip().lstrip("*") for n in line.strip().split(" : ")[0].split(",")}
    return names - {""}


def undocumented(paths=None) -> list[str]:
    """``module.function: arguments`` missing from a public function's Parameters."""
    gaps = []
    for path in paths or layering.library_files():
        module = layering._module_name(path)
        for f in ast.walk(ast.parse(path.read_text())):
            if not isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)) or f.name.startswith("_"):
                continue
            names = documented(ast.get_docstring(f) or "")
            if names is None:
                continue
            a = f.args
            args = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs
                    if x.arg not in ("self", "cls")]
            args += [x.arg for x in (a.vararg, a.kwarg) if x is not None]
            missing = [x for x in args if x not in names]
            if missing:
                gaps.append(f"{module}.{f.name}: {', '.join(missing)}")
    return sorted(gaps)


def test_every_argument_of_a_documented_function_is_documented():
    assert undocumented() == []


def test_an_undocumented_argument_is_caught(tmp_path, monkeypatch):
    (tmp_path / "planted.py").write_text(
        'def scale(x, factor, *, clip=None):\n'
        '    """Scale.\n\n    Parameters\n    ----------\n    x, factor : float\n'
        '        The value and its factor.\n\n    Returns\n    -------\n    float\n    """\n'
        '    return x * factor\n')
    monkeypatch.setitem(layering.SOURCES, "trussid.elsewhere", tmp_path)
    assert undocumented() == ["trussid.elsewhere.planted.scale: clip"]
