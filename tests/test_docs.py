"""The documentation site builds with warnings as errors, with the gallery's figures.

The build is the README's command (``python -m sphinx -W -b html docs OUT``), into a
temporary directory; it runs every example of ``examples/`` through sphinx-gallery, so a
broken example, a bad docstring or a dangling reference fails here.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted(p.stem for p in (ROOT / "examples").glob("*.py"))
SUBPACKAGES = ("fem", "plid", "geometry", "testbed", "campaign", "plots", "updating")


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("html")
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                          str(ROOT / "docs"), str(out)],
                         cwd=ROOT, env=env, capture_output=True, text=True, timeout=1800)
    assert run.returncode == 0, f"sphinx -W failed:\n{run.stderr[-6000:]}"
    return out


@pytest.mark.slow
def test_site_builds_with_warnings_as_errors_and_has_every_page(site):
    for page in ("index", "api", "architecture", "auto_examples/index",
                 "guide/install", "guide/demo", "guide/frame", "guide/nastran",
                 "guide/identification", "guide/testbed"):
        assert (site / f"{page}.html").is_file(), page
    # The API reference: one page per subpackage, one per public name of its __all__.
    import trussid.fem
    import trussid.plid

    for name in SUBPACKAGES:
        assert (site / "generated" / f"trussid.{name}.html").is_file(), name
    for module in (trussid.fem, trussid.plid):
        overview = (site / "generated" / f"{module.__name__}.html").read_text()
        for name in module.__all__:
            if callable(getattr(module, name)):  # classes and functions: a page each
                assert (site / "generated" / f"{module.__name__}.{name}.html").is_file(), name
            else:  # constants (fem.ALUMINIUM): on the subpackage's page
                assert f"{module.__name__}.{name}" in overview, name
    page = (site / "generated" / "trussid.fem.solve_modes.html").read_text()
    assert "Parameters" in page and "Returns" in page  # numpydoc rendered the sections


@pytest.mark.slow
def test_gallery_has_every_example_with_its_figure(site):
    for name in EXAMPLES:
        assert (site / "auto_examples" / f"{name}.html").is_file(), name
        png = site / "_images" / f"sphx_glr_{name}_001.png"
        assert png.is_file(), f"no figure for {name}"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert png.stat().st_size > 10_000, f"{name}'s figure is nearly empty"
        html = (site / "auto_examples" / f"{name}.html").read_text()
        assert f"sphx_glr_{name}_001.png" in html  # the page shows it
