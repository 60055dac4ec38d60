"""The package list of the wheel, discovered (the metadata is in pyproject.toml).

One import root, ``trussid``: the top-level folders ``fem/``, ``plid/`` and ``geometry/``
install as ``trussid.fem``, ``trussid.plid`` and ``trussid.geometry`` (PyPI's ``fem`` and
``geometry`` distributions own those bare names; docs/architecture.md). pyproject.toml cannot
express "every package below these folders, renamed": a hand-kept list there left
``trussid.adapt`` and ``trussid.updating`` out of the wheel (issue 30), so the list is found
here, from every folder with an ``__init__.py``.
"""

from pathlib import Path

from setuptools import find_packages, setup

HERE = Path(__file__).resolve().parent

#: import name -> source folder
ROOTS = {"trussid": "trussid", "trussid.fem": "fem", "trussid.plid": "plid",
         "trussid.geometry": "geometry"}


def packages() -> list[str]:
    """Every package of the wheel: each root and each folder below it with an __init__.py."""
    return sorted({name for root, folder in ROOTS.items()
                   for name in [root] + [f"{root}.{sub}" for sub in find_packages(str(HERE / folder))]})


setup(packages=packages(), package_dir={k: v for k, v in ROOTS.items() if k != v})
