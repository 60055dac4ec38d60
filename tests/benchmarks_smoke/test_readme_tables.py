"""The README's benchmark tables are exactly what benchmarks/readme_tables.py writes from
benchmarks/results/, every figure with the commit it measured."""

import importlib.util
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _module():
    spec = importlib.util.spec_from_file_location("readme_tables", ROOT / "benchmarks" / "readme_tables.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_readme_tables_match_the_results_files():
    rt = _module()
    readme = (ROOT / "README.md").read_text()
    names = re.findall(r"<!-- bench:([\w.-]+) -->", readme)
    assert {"fem", "testbed", "plant"} <= set(names), names
    expected = rt.render(readme, rt.load_tables(ROOT / "benchmarks" / "results"))
    assert readme == expected, "README benchmark tables are stale: run python benchmarks/readme_tables.py"


def test_every_readme_table_row_carries_a_commit():
    rt = _module()
    for name, table in rt.load_tables(ROOT / "benchmarks" / "results").items():
        assert table["columns"][-1] == "commit"
        for row in table["rows"]:
            assert re.fullmatch(r"[0-9a-f]{7}(\+dirty)?", str(row[-1])), (name, row)


def test_a_block_is_rewritten_from_the_results_and_unknown_names_are_refused(tmp_path):
    rt = _module()
    (tmp_path / "x.json").write_text(json.dumps({"tables": {"demo": {
        "columns": ["case", "seconds", "commit"], "rows": [["a", "1.5", "abc1234"]], "notes": "n"}}}))
    tables = rt.load_tables(tmp_path)
    text = "intro\n<!-- bench:demo -->\nhand-typed 0.1 s\n<!-- /bench:demo -->\nend\n"
    out = rt.render(text, tables)
    assert "hand-typed" not in out and "| a | 1.5 | abc1234 |" in out
    assert out.startswith("intro\n<!-- bench:demo -->\n") and out.endswith("<!-- /bench:demo -->\nend\n")
    assert rt.render(out, tables) == out
    with pytest.raises(rt.TableError, match="bench:other"):
        rt.render("<!-- bench:other -->\n<!-- /bench:other -->\n", tables)
