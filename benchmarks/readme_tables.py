"""Write the README's benchmark tables from ``benchmarks/results/*.json``.

Usage::

    python benchmarks/readme_tables.py [--check] [--readme README.md] [--results DIR]

Every block ``<!-- bench:NAME -->`` ... ``<!-- /bench:NAME -->`` in the README is replaced by
the table ``NAME`` found in the ``"tables"`` entry of one results file (see
``benchmarks/results_io.py``): its notes line, then a markdown table whose rows each carry
the commit they measured. Nothing between the markers is typed by hand. ``--check`` writes
nothing and exits 1 if the README differs from what would be written
(``tests/benchmarks_smoke/test_readme_tables.py`` runs it).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
BLOCK = re.compile(r"(<!-- bench:(?P<name>[\w.-]+) -->\n)(?P<body>.*?)(<!-- /bench:(?P=name) -->)", re.S)


class TableError(ValueError):
    """A marker names a table that no results file has, or a table is malformed."""


def load_tables(results: Path) -> dict[str, dict]:
    """Every table of every results file, by name (a name in two files is an error)."""
    tables: dict[str, dict] = {}
    for path in sorted(Path(results).glob("*.json")):
        try:
            data = json.loads(path.read_text())
        except json.JSONDecodeError as exc:
            raise TableError(f"{path}: not JSON ({exc})") from None
        for name, table in (data.get("tables") or {}).items() if isinstance(data, dict) else ():
            if name in tables:
                raise TableError(f"table {name!r} is in both {tables[name]['_file']} and {path.name}")
            tables[name] = {**table, "_file": path.name}
    return tables


def render_table(name: str, table: dict) -> str:
    """Markdown of one table: notes, header, rows (each row ends with its commit)."""
    cols, rows = table.get("columns"), table.get("rows")
    if not cols or rows is None or cols[-1] != "commit":
        raise TableError(f"table {name!r} in {table.get('_file')}: needs columns ending with 'commit' and rows")
    bad = [r for r in rows if len(r) != len(cols)]
    if bad:
        raise TableError(f"table {name!r} in {table.get('_file')}: a row has {len(bad[0])} cells, not {len(cols)}")
    out = []
    if table.get("notes"):
        out += [f"{table['notes']} (from `benchmarks/results/{table['_file']}`)", ""]
    out.append("| " + " | ".join(cols) + " |")
    out.append("|" + "|".join("---" for _ in cols) + "|")
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out) + "\n"


def render(readme: str, tables: dict[str, dict]) -> str:
    """``readme`` with every marked block rewritten from ``tables``."""
    def sub(m):
        name = m.group("name")
        if name not in tables:
            raise TableError(f"README block bench:{name}: no results file has a table {name!r}")
        return m.group(1) + render_table(name, tables[name]) + m.group(4)

    return BLOCK.sub(sub, readme)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="exit 1 if the README is not up to date; write nothing")
    p.add_argument("--readme", default=str(ROOT / "README.md"))
    p.add_argument("--results", default=str(HERE / "results"))
    args = p.parse_args(argv)
    path = Path(args.readme)
    text = path.read_text()
    try:
        new = render(text, load_tables(Path(args.results)))
    except TableError as exc:
        print(f"readme_tables: {exc}", file=sys.stderr)
        return 2
    if args.check:
        if new != text:
            print(f"readme_tables: {path} differs from the results; run python benchmarks/readme_tables.py",
                  file=sys.stderr)
            return 1
        return 0
    if new != text:
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(new)
        tmp.replace(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
