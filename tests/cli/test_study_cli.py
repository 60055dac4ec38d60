"""``trussid study``: a spec runs to a Parquet table with a summary; a bad spec or output
directory is one line on stderr naming the item, exit status 2, nothing written."""

from __future__ import annotations

import pandas as pd
import pytest

from trussid.cli import main

GOOD = """
[study]
name = "tiny"
evaluate = "modes"

[evaluate]
n_modes = 10

[parameters]
wall0 = {low = 0.0006, high = 0.0012, num = 3}
wall2 = {values = [0.0009, 0.0011]}
"""


@pytest.fixture
def cli(capsys):
    def call(*args):
        code = main(["study", *map(str, args)])
        out, err = capsys.readouterr()
        return code, out, err
    return call


@pytest.mark.slow  # builds the testbed and draws a figure: ~4 s unloaded, 20 s at load 15
def test_a_spec_runs_to_a_table_and_a_report(tmp_path, cli):
    spec = tmp_path / "s.toml"
    spec.write_text(GOOD)
    code, out, err = cli(spec, "--out", tmp_path / "o", "--workers", 0, "--quiet")
    assert code == 0, err
    assert "6 points: computed 6 in this run (0 failed), 0 already done" in out
    df = pd.read_parquet(tmp_path / "o")
    assert sorted(df["point"]) == list(range(6)) and (df["status"] == "ok").all()
    code, out, _ = cli(spec, "--out", tmp_path / "o", "--workers", 0, "--quiet")
    assert code == 0 and "computed 0 in this run (0 failed), 6 already done" in out
    code, out, err = cli(tmp_path / "o", "--report")
    assert code == 0, err
    report = (tmp_path / "o" / "_report" / "report.md").read_text()
    assert "6 ok, 0 failed" in report and "frequencies.png" in report
    assert (tmp_path / "o" / "_report" / "frequencies.png").stat().st_size > 20_000
    assert len(pd.read_parquet(tmp_path / "o")) == 6  # the report does not disturb the dataset


@pytest.mark.parametrize("edit, item", [
    (lambda s: s.replace("wall2 =", "wall9 ="), "'wall9'"),                                  # unknown parameter
    (lambda s: s.replace("low = 0.0006, high = 0.0012", "low = 0.0012, high = 0.0006"), "'wall0'"),  # empty range
    (lambda s: s.replace("[0.0009, 0.0011]", "[0.0009, -0.0011]"), "'wall2'"),               # negative wall
    (lambda s: s.replace('evaluate = "modes"', 'evaluate = "identify"').replace("n_modes = 10", "")
     .replace("wall0 = {low = 0.0006, high = 0.0012, num = 3}", 'method = ["plid-subspace", "arx"]')
     .replace("wall2 = {values = [0.0009, 0.0011]}", ""), "'arx'"),                           # unknown method
    (lambda s: s.replace("n_modes = 10", "n_modes = 0"), "n_modes"),
    (lambda s: s + "\n[extra]\n", "[extra]"),
    (lambda s: s.replace("[parameters]", "[parameters\n"), "not valid TOML"),
])
def test_a_bad_spec_is_one_line_naming_the_item_and_exit_2(tmp_path, cli, edit, item):
    spec = tmp_path / "bad.toml"
    spec.write_text(edit(GOOD))
    code, out, err = cli(spec, "--out", tmp_path / "o", "--workers", 0)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("trussid study: error: ") and item in lines[0], err
    assert "Traceback" not in err and not (tmp_path / "o").exists()


def test_an_output_holding_another_study_is_refused(tmp_path, cli):
    spec = tmp_path / "s.toml"
    spec.write_text(GOOD)
    assert cli(spec, "--out", tmp_path / "o", "--workers", 0, "--quiet")[0] == 0
    before = sorted(p.name for p in (tmp_path / "o").iterdir())
    spec.write_text(GOOD.replace("n_modes = 10", "n_modes = 12"))
    code, out, err = cli(spec, "--out", tmp_path / "o", "--workers", 0)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "holds another study" in err and str(tmp_path / "o") in err and "options.n_modes" in err
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == before


def test_usage_mistakes_are_one_line(tmp_path, cli):
    spec = tmp_path / "s.toml"
    spec.write_text(GOOD)
    assert "--out DIR is required" in cli(spec)[2]
    assert "no such spec file" in cli(tmp_path / "nope.toml", "--out", tmp_path / "o")[2]
    assert "--report takes a study output directory" in cli(spec, "--report")[2]
    assert "must be 0" in cli(spec, "--out", tmp_path / "o", "--workers", -1)[2]
    assert "not a study output" in cli(tmp_path, "--report")[2]
