"""The public API: every exported name resolves, and importing a package stays light."""

import importlib
import subprocess
import sys

import pytest

PUBLIC = ["trussid.fem", "trussid.plid", "trussid.geometry", "trussid.testbed", "trussid.campaign"]


@pytest.mark.parametrize("package", PUBLIC)
def test_every_exported_name_resolves(package):
    module = importlib.import_module(package)
    for name in module.__all__:
        assert getattr(module, name) is not None
    assert set(module.__all__) <= set(dir(module))
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        getattr(module, "no_such_name")


def test_importing_the_packages_loads_no_heavy_dependency():
    code = ("import sys, trussid.fem, trussid.geometry, trussid.plid, trussid.testbed, trussid.cli; "
            "print(sorted(m for m in ('control', 'trimesh', 'vtk', 'pyvista', 'pyNastran', 'matplotlib') "
            "if m in sys.modules))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert res.stdout.strip() == "[]"


@pytest.mark.parametrize("package", PUBLIC)
def test_no_submodule_is_named_like_an_export(package):
    """A submodule named like a function it exports would shadow the function once imported."""
    module = importlib.import_module(package)
    path = module.__path__[0]
    import pkgutil

    submodules = {m.name for m in pkgutil.iter_modules([path])}
    assert submodules.isdisjoint(module.__all__)


def test_every_module_of_the_library_imports():
    """The fast tier touches every module, at least by importing it."""
    import pkgutil

    import trussid

    names = [m.name for m in pkgutil.walk_packages(trussid.__path__, "trussid.")]
    for pkg in ("trussid.fem", "trussid.plid", "trussid.geometry"):
        mod = importlib.import_module(pkg)
        names += [m.name for m in pkgutil.walk_packages(mod.__path__, pkg + ".")]
    names = [n for n in names if not n.endswith("__main__")]  # runs the command line
    assert len(names) > 60
    for name in names:
        importlib.import_module(name)


@pytest.mark.parametrize("package", ["trussid.fem", "trussid.plid"])
def test_every_module_names_its_public_api(package):
    """Each public module of the generic packages says what it exports (``__all__``), and each
    name there exists: a reader (and ``from ... import *``) sees the API, not the helpers."""
    import pkgutil

    path = importlib.import_module(package).__path__
    for info in pkgutil.iter_modules(path, package + "."):
        if info.name.rsplit(".", 1)[1].startswith("_"):
            continue  # a private module (plid._validate) has no public API to name
        module = importlib.import_module(info.name)
        assert hasattr(module, "__all__"), info.name
        assert [n for n in module.__all__ if not hasattr(module, n)] == [], info.name
