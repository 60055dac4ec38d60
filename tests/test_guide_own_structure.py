"""The guide page "your own structure, end to end" (docs/guide/own_structure.md) runs as
written: its Python blocks, its TOML files (``# file: NAME`` on the first line) and its
``$ trussid ...`` commands, in order, in an empty directory (issue 24, acceptance 6).

The fast test runs everything up to the campaign and the study; the slow one the whole
page (the campaign takes minutes)."""

import re
import shlex
from pathlib import Path

import pytest

from trussid.cli import main

PAGE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "own_structure.md"
BLOCK = re.compile(r"^```(\w+)\n(.*?)^```", re.S | re.M)


def steps():
    """(kind, text) of every block of the page, in order."""
    return [(m.group(1), m.group(2)) for m in BLOCK.finditer(PAGE.read_text())]


def run_page(tmp_path, monkeypatch, capsys, skip_campaign: bool):
    monkeypatch.chdir(tmp_path)
    ran = []
    for kind, text in steps():
        if kind == "python":
            exec(compile(text, str(PAGE), "exec"), {"__name__": "guide"})
        elif kind == "toml":
            first, _, body = text.partition("\n")
            name = re.fullmatch(r"# file: (\S+)", first.strip()).group(1)
            Path(name).write_text(body)
        elif kind == "console":
            for line in text.splitlines():
                assert line.startswith("$ trussid "), line
                args = shlex.split(line[len("$ trussid "):])
                if skip_campaign and args[0] in ("demo", "control", "closed-loop", "export"):
                    continue
                code = main(args)
                assert code == 0, (line, capsys.readouterr().err)
                ran.append(args[0])
        else:
            raise AssertionError(f"unexpected block kind {kind}")
    return ran


def test_the_page_has_the_steps_it_promises():
    kinds = [k for k, _ in steps()]
    assert kinds.count("python") == 1 and kinds.count("toml") == 2
    commands = " ".join(t for k, t in steps() if k == "console")
    for cmd in ("plant", "demo", "control", "closed-loop", "export", "study"):
        assert f"$ trussid {cmd} " in commands


def test_the_pages_structure_plant_and_study_run(tmp_path, monkeypatch, capsys):
    ran = run_page(tmp_path, monkeypatch, capsys, skip_campaign=True)
    assert ran == ["plant", "study"]
    assert (tmp_path / "plant.npz").exists()
    import pandas as pd

    table = pd.read_parquet(tmp_path / "study")
    assert len(table) == 4 and (table["status"] == "ok").all()


@pytest.mark.slow
def test_the_whole_page_runs(tmp_path, monkeypatch, capsys):
    ran = run_page(tmp_path, monkeypatch, capsys, skip_campaign=False)
    assert ran == ["plant", "demo", "control", "closed-loop", "export", "study"]
    assert (tmp_path / "ctrl.mat").exists() and (tmp_path / "loop" / "report.md").exists()
