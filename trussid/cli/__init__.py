"""The ``trussid`` command line.

Each sub-command lives in its own module under :mod:`trussid.cli.commands` and exposes
``add_parser(subparsers)``, which registers the parser and sets ``func(args) -> int``.
Mistakes in user input (:class:`trussid._util.errors.UserError`, missing files) end in one line on
stderr and exit status 2; ``--debug`` (or ``TRUSSID_DEBUG=1``) shows the traceback instead.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from trussid import __version__
from trussid._util.errors import UserError

#: Sub-commands in the order ``--help`` lists them.
COMMANDS = ("demo", "modes", "render", "plant", "simulate", "identify", "compare", "greybox", "study")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="trussid",
        description="Finite-element models, control-ready plants and PLID identification "
        "for piezo-actuated truss structures.",
    )
    parser.add_argument("--version", action="version", version=f"trussid {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks for errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"trussid.cli.commands.{name}")
        except ModuleNotFoundError as exc:
            # A command whose module is not there yet is simply not offered; any other
            # missing module is a real installation problem and must surface.
            if exc.name == f"trussid.cli.commands.{name}":
                continue
            raise
        module.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    debug = args.debug or os.environ.get("TRUSSID_DEBUG") == "1"
    try:
        return int(args.func(args) or 0)
    except (UserError, FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        if debug:
            raise
        msg = str(exc) if isinstance(exc, UserError) else f"{exc.strerror}: {exc.filename}"
        print(f"trussid {args.command}: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"trussid {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # Output piped into a reader that stopped early (e.g. ``| head``): end quietly, as
        # the Python documentation recommends, without a second error at interpreter exit.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
