"""The docstring examples: every ``>>>`` line of the library's numpydoc ``Examples`` sections
runs, and prints what the docstring says it prints (issue 22: a reader copies them).

doctest over the imported ``trussid.*`` modules, not ``pytest --doctest-modules``: the folders
``fem/``, ``plid/``, ``geometry/`` install as ``trussid.fem``... (pyproject's package-dir), and
a path-based import would load them a second time under other names. Each example runs in an
empty temporary folder (files it writes go there), with numpy printing 4 significant decimals;
examples print rounded values (f-strings or ``np.round``) so that they read the same on every
numpy and BLAS.
"""

import doctest
import importlib
import pkgutil

import numpy as np
import pytest

PACKAGES = ("trussid", "trussid.fem", "trussid.plid", "trussid.geometry")
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _module_names() -> list[str]:
    names = set(PACKAGES)
    for pkg in PACKAGES:
        path = importlib.import_module(pkg).__path__
        names |= {m.name for m in pkgutil.walk_packages(path, pkg + ".")}
    return sorted(n for n in names if not n.endswith("__main__"))


MODULES = _module_names()


def _examples(name: str) -> list[doctest.DocTest]:
    module = importlib.import_module(name)
    return [t for t in doctest.DocTestFinder(exclude_empty=True).find(module, name) if t.examples]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run_and_print_what_they_say(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    failures = []
    for test in _examples(name):
        runner = doctest.DocTestRunner(optionflags=FLAGS)
        with np.printoptions(precision=4, suppress=True):
            runner.run(test, out=failures.append, clear_globs=True)
    assert failures == [], "\n".join(failures)


def test_the_main_public_functions_carry_runnable_examples():
    tests = [t for name in MODULES for t in _examples(name)]
    names = sorted({t.name for t in tests})
    assert len(names) >= 30, names
    assert sum(len(t.examples) for t in tests) >= 150
