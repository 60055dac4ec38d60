"""Package exports resolved on first use (PEP 562), so ``import trussid.fem`` stays cheap.

The packages' public names live in submodules that import scipy, python-control, trimesh
or VTK. Importing them eagerly would make every command (even ``trussid --help``) and every
error class pay for all of them. No module is named like one of its package's exported
functions, so the import system's binding of a submodule never shadows an export.
"""

from __future__ import annotations

import importlib


def lazy_exports(package: str, exports: dict[str, str]):
    """``(__getattr__, __dir__)`` for a package whose ``exports`` map names to submodules.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : dict
        Exported name -> submodule (relative to ``package``) that defines it.
    """

    def __getattr__(name: str):
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        importlib.import_module(package).__dict__[name] = value  # later look-ups skip this
        return value

    def __dir__():
        return sorted(set(exports) | set(importlib.import_module(package).__dict__))

    return __getattr__, __dir__
