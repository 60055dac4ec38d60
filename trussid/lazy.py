"""Package exports resolved on first use (PEP 562), so ``import fem`` stays cheap.

The packages' public names live in submodules that import scipy, python-control, trimesh
or VTK. Importing them eagerly would make every command (even ``trussid --help``) and
every error class pay for all of them.
"""

from __future__ import annotations

import importlib
import sys
import types


class _ExportingModule(types.ModuleType):
    """A package module whose exports win over same-named submodules.

    ``fem.testbed_plant`` is both a function (the export) and a submodule. When anything
    imports the submodule, the import system binds ``fem.testbed_plant`` to the module,
    and ``fem.testbed_plant(tb)`` then fails with "'module' object is not callable"
    depending on what ran before. Here that binding is replaced by the export itself;
    ``from fem.testbed_plant import X`` still works (it reads ``sys.modules``).
    """

    def __setattr__(self, name, value):
        exports = self.__dict__.get("_lazy_exports", {})
        if (isinstance(value, types.ModuleType) and exports.get(name) == name
                and value.__name__ == f"{self.__name__}.{name}" and hasattr(value, name)):
            value = getattr(value, name)
        super().__setattr__(name, value)


def lazy_exports(package: str, exports: dict[str, str]):
    """``(__getattr__, __dir__)`` for a package whose ``exports`` map names to submodules."""

    def __getattr__(name: str):
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        globals_ = importlib.import_module(package).__dict__
        globals_[name] = value  # cache: later look-ups skip this function
        return value

    def __dir__():
        return sorted(set(exports) | set(importlib.import_module(package).__dict__))

    module = sys.modules.get(package)
    if module is not None and type(module) is types.ModuleType:
        module.__dict__["_lazy_exports"] = dict(exports)
        module.__class__ = _ExportingModule
    return __getattr__, __dir__
