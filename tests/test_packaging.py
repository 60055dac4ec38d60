"""Every third-party module the packages import is a declared runtime dependency.

A module that only a test extra installs (nfoursid was one) makes `trussid demo` fail on a
machine set up with the README's first command; the source is read with ``ast``, so
imports inside functions count too.
"""

import ast
import re
import sys
import tomllib
from importlib.metadata import packages_distributions
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("geometry", "fem", "plid", "trussid")  # source folders (trussid.* when installed)


def _imported_top_levels():
    names = {}
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.Import):
                    mods = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    mods = [node.module]
                else:
                    continue
                for m in mods:
                    names.setdefault(m.split(".")[0], str(path.relative_to(ROOT)))
    return names


def _declared():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    return {re.split(r"[<>=!~\[; ]", d, maxsplit=1)[0].lower().replace("_", "-")
            for d in meta["project"]["dependencies"]}


#: Installed by scripts/setup.sh outside dependency resolution, with the reason there: none
#: since slycot became an ordinary dependency and pyNastran left (issue 30).
SETUP_INSTALLED: set = set()

#: Optional features: the module -> the extra that installs it. Each is imported only where
#: the feature is used, inside ``try``/``except ImportError`` that names the extra.
OPTIONAL = {"dask_jobqueue": "cluster"}


def _extra(name):
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    return {re.split(r"[<>=!~\[; ]", d, maxsplit=1)[0].lower().replace("_", "-")
            for d in meta["project"]["optional-dependencies"][name]}


def test_every_third_party_import_is_a_runtime_dependency():
    dists = packages_distributions()
    declared = _declared() | SETUP_INSTALLED
    missing = {}
    for top, where in _imported_top_levels().items():
        if top in sys.stdlib_module_names or top in PACKAGES or top == "__future__":
            continue
        if top in OPTIONAL:
            assert top.replace("_", "-") in _extra(OPTIONAL[top]), (top, OPTIONAL[top])
            text = (ROOT / where).read_text()
            assert "except ImportError" in text and f"trussid[{OPTIONAL[top]}]" in text, where
            continue
        owners = {d.lower().replace("_", "-") for d in dists.get(top, [top])}
        if not owners & declared:
            missing[top] = where
    assert not missing, f"imported but not in [project.dependencies]: {missing}"


def test_what_setup_installs_outside_resolution_is_in_setup_sh():
    setup = (ROOT / "scripts" / "setup.sh").read_text()
    for name in SETUP_INSTALLED:
        assert f'--no-deps "{name}==' in setup
        assert name not in _declared()
