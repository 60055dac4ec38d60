"""The documentation a clone gets is in the clone: every relative link of README.md and
docs/*.md resolves inside the repository, and the licence pyproject names is there."""

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


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
    assert meta["license"]["text"] == "MIT"
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
