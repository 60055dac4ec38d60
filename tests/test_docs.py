"""The documentation: the clone holds what it links to, and the site builds.

- Every relative link of README.md and docs/*.md resolves inside the repository, and the
  licence pyproject names is there.
- The documentation site builds with warnings as errors, with the gallery's figures. The
  build is the README's command (``python -m sphinx -W -b html docs OUT``), into a
  temporary directory; it runs every example of ``examples/`` through sphinx-gallery, so a
  broken example, a bad docstring or a dangling reference fails here.
"""

import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
EXAMPLES = sorted(p.stem for p in (ROOT / "examples").glob("*.py"))
SUBPACKAGES = ("fem", "plid", "geometry", "testbed", "campaign", "plots", "updating")


def _links():
    for doc in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for target in LINK.findall(doc.read_text()):
            if not re.match(r"[a-z]+://|mailto:", target):
                yield doc, target


def test_every_relative_link_resolves_inside_the_repository():
    bad = []
    for doc, target in _links():
        path = (doc.parent / target).resolve()
        if not path.is_relative_to(ROOT) or not path.exists():
            bad.append(f"{doc.relative_to(ROOT)} -> {target}")
    assert bad == []


def test_no_source_or_document_points_to_the_shared_reference_folder():
    files = [*ROOT.glob("*.md"), *(ROOT / "docs").glob("*.md"),
             *(p for d in ("trussid", "fem", "plid", "geometry") for p in (ROOT / d).rglob("*.py"))]
    bad = [str(p.relative_to(ROOT)) for p in files if "shared/docs" in p.read_text()
           or "../shared" in p.read_text()]
    assert bad == []


def test_the_licence_pyproject_names_is_in_the_repository():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert meta["license"] == "MIT"  # an SPDX expression (PEP 639)
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")


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
                 "guide/identification", "guide/testbed", "guide/own_structure", "cli"):
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


@pytest.mark.slow
def test_formulas_render_offline_from_the_site_itself(site):
    """A page with formulas loads MathJax from the site's own ``_static``, never from a CDN:
    opened without network it still shows rendered math (the screenshot
    docs/images/site_math_offline.png was taken so, in Chromium in a network namespace with no
    interface)."""
    html = (site / "auto_examples" / "cantilever_frame.html").read_text()
    assert r"\frac{(\beta_n L)^2}" in html  # the formula is on the page, for MathJax
    scripts = re.findall(r"<script[^>]*src=\"([^\"]+)\"", html)
    assert "../_static/mathjax/MathJax.js?config=TeX-AMS_SVG" in scripts
    assert not [s for s in scripts if re.match(r"[a-z]+://|//", s)]  # nothing from the network
    mathjax = site / "_static" / "mathjax"
    for part in ("MathJax.js", "config/TeX-AMS_SVG.js", "jax/input/TeX/jax.js", "jax/output/SVG/jax.js",
                 "jax/output/SVG/fonts/TeX/fontdata.js", "extensions/TeX/AMSmath.js"):
        assert (mathjax / part).is_file(), part


@pytest.mark.slow
def test_cli_reference_page_is_every_commands_help(site):
    """docs/cli.md is generated from the parsers at each build: every subcommand is on it."""
    from trussid.cli import build_parser

    text = (site / "cli.html").read_text()
    help_text = build_parser().format_help()
    for cmd in ("plant", "demo", "control", "closed-loop", "study", "export", "identify"):
        assert f"trussid {cmd}" in text and cmd in help_text
