"""The command line: every command has --help; user mistakes end in one line, no traceback."""

import subprocess
import sys

from trussid.cli import COMMANDS, build_parser


def run(*args):
    return subprocess.run([sys.executable, "-m", "trussid", *args], capture_output=True, text=True)


def test_top_level_help_lists_available_commands():
    res = run("--help")
    assert res.returncode == 0
    parser = build_parser()
    offered = parser._subparsers._group_actions[0].choices  # noqa: SLF001 - argparse has no public accessor
    for name in offered:
        assert name in COMMANDS
        assert name in res.stdout


def test_every_command_has_help():
    parser = build_parser()
    for name in parser._subparsers._group_actions[0].choices:  # noqa: SLF001
        res = run(name, "--help")
        assert res.returncode == 0, (name, res.stderr)
        assert "usage:" in res.stdout


def test_no_command_prints_help_and_fails():
    res = run()
    assert res.returncode == 2
    assert "usage:" in res.stdout
