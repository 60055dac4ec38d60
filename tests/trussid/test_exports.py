"""The packages' public names: every export resolves, and importing a package stays light."""

import importlib
import subprocess
import sys

import pytest


@pytest.mark.parametrize("package", ["fem", "geometry", "plid"])
def test_every_exported_name_resolves(package):
    module = importlib.import_module(package)
    for name in module.__all__:
        assert getattr(module, name) is not None
    assert set(module.__all__) <= set(dir(module))
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        getattr(module, "no_such_name")


def test_importing_the_packages_loads_no_heavy_dependency():
    code = ("import sys, fem, geometry, plid, trussid.cli; "
            "print(sorted(m for m in ('control', 'trimesh', 'vtk', 'pyvista', 'pyNastran', 'matplotlib') "
            "if m in sys.modules))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert res.stdout.strip() == "[]"


@pytest.mark.parametrize("package, name", [("fem", "testbed_plant"), ("plid", "stabilise")])
def test_an_export_stays_callable_after_its_same_named_submodule_is_imported(package, name):
    # fem.testbed_plant is a function and a submodule; importing the submodule first (as
    # trussid.pipeline does) used to leave the package attribute bound to the module.
    code = (f"import importlib, {package}; importlib.import_module('{package}.{name}'); "
            f"from {package}.{name} import {name} as f; "
            f"print(callable({package}.{name}), {package}.{name} is f)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert res.stdout.split() == ["True", "True"]
