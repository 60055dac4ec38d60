"""The command line: every command has --help; user mistakes end in one line, no traceback."""

import subprocess
import sys

import pytest

from trussid.cli import COMMANDS, main


def run(*args):
    return subprocess.run([sys.executable, "-m", "trussid", *args], capture_output=True, text=True)


def test_top_level_help_lists_available_commands():
    res = run("--help")
    assert res.returncode == 0
    for name in COMMANDS:
        assert name in res.stdout


@pytest.mark.parametrize("name", COMMANDS)
def test_every_command_has_help(name, capsys):
    """In process: one subprocess per command would pay python-control's import each time."""
    with pytest.raises(SystemExit) as exc:
        main([name, "--help"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.startswith(f"usage: trussid {name}")


def test_no_command_prints_help_and_fails():
    res = run()
    assert res.returncode == 2
    assert "usage:" in res.stdout


def test_version_has_one_home(capsys):
    """`trussid --version`, the installed distribution's metadata and the package's
    __version__ agree: pyproject.toml reads the version from trussid.__version__ (issue 30).
    (tests/test_wheel.py checks the same on installed wheels.)"""
    from importlib.metadata import version

    from trussid import __version__

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out == f"trussid {__version__}\n"
    assert version("trussid") == __version__
    text = (__import__("pathlib").Path(__file__).resolve().parents[2] / "pyproject.toml").read_text()
    assert 'dynamic = ["version"]' in text and '\nversion = "' not in text
