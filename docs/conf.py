"""Sphinx configuration of the trussid documentation site.

Build (from the repository root)::

    python -m sphinx -W -b html docs docs/_build/html

The API reference is generated from the docstrings (numpydoc); the examples in
``examples/`` are run by sphinx-gallery, which keeps their figures.
"""

from __future__ import annotations

import importlib
import inspect
import os
import pkgutil
import shutil
import sys
from pathlib import Path

from sphinx.errors import ExtensionError
from sphinx.pycode import ModuleAnalyzer

import trussid

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS))  # for the gallery's argv helper, _gallery_argv.py

project = "trussid"
author = "trussid contributors"
copyright = "2026, trussid contributors"  # noqa: A001 - Sphinx's name
release = version = trussid.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "**.ipynb_checkpoints", "auto_examples/*.ipynb",
                    "auto_examples/*.py", "auto_examples/*.zip"]
templates_path = ["_templates"]
root_doc = "index"

# API reference: one page per public name of each subpackage's __all__.
autosummary_generate = True
autosummary_ignore_module_all = False
autosummary_imported_members = True  # the exports live in submodules
autodoc_default_options = {"members": False}
API_MODULES = ("trussid.fem", "trussid.plid", "trussid.geometry", "trussid.testbed",
               "trussid.plots", "trussid.updating", "trussid.campaign")


def _constants(name: str) -> list[dict]:
    """The values in a module's ``__all__`` (materials, unit factors), with their doc.

    autosummary sorts a module's members into classes, functions and exceptions; a
    constant re-exported from a submodule falls in none of them, and autodoc would show
    the docstring of its type (``float``). The module template lists these itself, with
    the ``#:`` comment of the submodule that defines the value.
    """
    module = importlib.import_module(name)
    docs = {}
    if hasattr(module, "__path__"):
        for info in pkgutil.iter_modules(module.__path__, name + "."):
            analyzer = ModuleAnalyzer.for_module(info.name)
            docs.update({attr: " ".join(lines).strip()
                         for (_, attr), lines in analyzer.find_attr_docs().items()})
    out = []
    for n in getattr(module, "__all__", ()):
        value = getattr(module, n)
        if not (inspect.isclass(value) or callable(value) or inspect.ismodule(value)):
            out.append({"name": n, "value": repr(value), "doc": docs.get(n, "")})
    return out


autosummary_context = {"constants": {name: _constants(name) for name in API_MODULES}}
autodoc_typehints = "none"  # numpydoc sections carry the types and units
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

myst_heading_anchors = 3

# Formulas render offline: MathJax is served from the site itself, not from a CDN (a page
# opened without network would show raw TeX). The copy is Debian's libjs-mathjax (MathJax
# 2.7, installed by scripts/setup.sh); TRUSSID_MATHJAX points elsewhere (a MathJax 2.7 tree)
# on a machine without apt. SVG output: the glyphs are JavaScript paths, no web fonts.
MATHJAX_SOURCE = Path(os.environ.get("TRUSSID_MATHJAX", "/usr/share/javascript/mathjax"))
#: The parts of the MathJax tree that the TeX-AMS_SVG configuration loads (5 MB of 54).
MATHJAX_PARTS = ("MathJax.js", "config/TeX-AMS_SVG.js", "extensions", "jax/element", "jax/input/TeX",
                 "jax/output/PreviewHTML", "jax/output/SVG/jax.js", "jax/output/SVG/config.js",
                 "jax/output/SVG/autoload", "jax/output/SVG/fonts/TeX")
mathjax_path = "mathjax/MathJax.js?config=TeX-AMS_SVG"  # relative to the site's _static
mathjax2_config = {"tex2jax": {"inlineMath": [["\\(", "\\)"]], "displayMath": [["\\[", "\\]"]]},
                   "menuSettings": {"zoom": "None"}}

# The examples: run at build time unless they take minutes; figures kept.
sphinx_gallery_conf = {
    "examples_dirs": [str(ROOT / "examples")],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": r".*\.py$",
    "ignore_pattern": r"__init__\.py",
    "reset_argv": "_gallery_argv.reset_argv",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "plot_gallery": "True",
    "matplotlib_animations": False,
    "show_memory": False,
    # Run every example on every build: sphinx-gallery would otherwise skip an example
    # whose file is unchanged, and a library change that breaks it would go unseen.
    "run_stale_examples": True,
}

html_theme = "alabaster"
html_title = f"trussid {release}"
html_static_path: list[str] = []
html_theme_options = {
    "description": "Beam FE, control-ready plants and PLID identification for piezo-actuated trusses",
    "fixed_sidebar": True,
    "page_width": "1180px",  # room for the examples' code lines (up to ~100 characters)
    "body_max_width": "none",
}


def _skip_foreign(app, what, name, obj, skip, options):
    """Leave out names a module merely imports (matplotlib's Figure in trussid.plots).

    Modules with an ``__all__`` list only its names; this matters for those without one,
    where autosummary would otherwise document every imported class and function. Class
    members always belong to trussid, so the rule leaves them alone.
    """
    module = getattr(obj, "__module__", None)
    if isinstance(module, str):
        if not module.startswith("trussid.") or module.startswith("trussid._util"):
            return True
    return None


def _check_mathjax(app):
    """Fail at the start of the build, not after it, when the local MathJax is missing."""
    if app.builder.format == "html" and not (MATHJAX_SOURCE / "MathJax.js").is_file():
        raise ExtensionError(f"MathJax 2.7 not found at {MATHJAX_SOURCE} (the formulas must render "
                             "offline): install Debian's libjs-mathjax (bash scripts/setup.sh docs) "
                             "or set TRUSSID_MATHJAX to a MathJax 2.7 folder")


def _copy_mathjax(app, exception):
    """Copy the parts of the local MathJax the pages load into the site's ``_static``."""
    if exception is not None or app.builder.format != "html":
        return
    target = Path(app.outdir) / "_static" / "mathjax"
    for part in MATHJAX_PARTS:
        src, dst = MATHJAX_SOURCE / part, target / part
        dst.parent.mkdir(parents=True, exist_ok=True)
        if src.is_dir():
            shutil.copytree(src, dst, dirs_exist_ok=True)
        else:
            shutil.copyfile(src, dst)


def _write_cli_reference(app):
    """docs/cli.md from the parsers themselves: every subcommand's ``--help`` as the command
    line prints it (generated at each build, so the page cannot drift from the code)."""
    import argparse

    from trussid.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    lines = ["# Command-line reference", "",
             "Generated from the parsers at each build: what `trussid --help` and "
             "`trussid COMMAND --help` print.", "", "```text", parser.format_help().rstrip(),
             "```", ""]
    for name, p in sub.choices.items():
        lines += [f"## trussid {name}", "", "```text", p.format_help().rstrip(), "```", ""]
    text = "\n".join(lines)
    path = DOCS / "cli.md"
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def setup(app):
    app.connect("builder-inited", _write_cli_reference)
    app.connect("autodoc-skip-member", _skip_foreign)
    app.connect("builder-inited", _check_mathjax)
    app.connect("build-finished", _copy_mathjax)
