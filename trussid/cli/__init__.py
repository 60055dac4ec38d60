"""The ``trussid`` command line.

Each sub-command lives in its own module under :mod:`trussid.cli.commands` and exposes
``add_parser(subparsers)``, which registers the parser and sets ``func(args) -> int``.
Mistakes in user input (:class:`trussid._util.errors.UserError`, missing files) end in one line on
stderr and exit status 2; ``--debug`` (or ``TRUSSID_DEBUG=1``) shows the traceback instead.

Every command runs with one BLAS thread unless ``--threads N`` (or ``TRUSSID_THREADS``)
says otherwise (:func:`trussid._util.threads.threads_setting`). Both ``--debug`` and
``--threads`` are accepted before or after the command name.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import re
import sys

from trussid import __version__
from trussid._util.errors import UserError

#: Sub-commands in the order ``--help`` lists them (module ``trussid.cli.commands.<name>``
#: with ``-`` read as ``_``).
COMMANDS = ("demo", "modes", "render", "plant", "simulate", "identify", "compare", "greybox",
            "export", "control", "closed-loop", "study")


class Parser(argparse.ArgumentParser):
    """argparse with negative numbers in scientific or list form taken as values.

    argparse treats any argument that starts with '-' as an option unless it matches
    ``-123`` or ``-1.5``; ``--scale -1e9`` and ``--flywheel -0.1,0.02`` then failed with
    "expected one argument", which names the wrong cause (the audit's B29 and B96).
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(
            r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?(,[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?)*$")


def _add_common(p, default) -> None:
    p.add_argument("--debug", action="store_true", default=default,
                   help="show tracebacks for errors")
    p.add_argument("--threads", type=int, default=default, metavar="N",
                   help="BLAS threads (default 1, or $TRUSSID_THREADS; 0: the libraries' "
                   "own default)")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="trussid",
        description="Finite-element models, control-ready plants and PLID identification "
        "for piezo-actuated truss structures.",
    )
    parser.add_argument("--version", action="version", version=f"trussid {__version__}")
    _add_common(parser, None)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        modname = f"trussid.cli.commands.{name.replace('-', '_')}"
        try:
            module = importlib.import_module(modname)
        except ModuleNotFoundError as exc:
            # A command whose module is not there yet is simply not offered; any other
            # missing module is a real installation problem and must surface.
            if exc.name == modname:
                continue
            raise
        module.add_parser(sub)
        # SUPPRESS: given after the command they override, absent they keep the top level's
        _add_common(sub.choices[name], argparse.SUPPRESS)
    return parser


def _early_threads(argv) -> None:
    """Set the BLAS environment for this process before numpy loads, when run as ``trussid``.

    threadpoolctl (used around the command) limits only libraries already loaded; scipy
    loads its own OpenBLAS on first use, so a process entry point also sets the variables
    that libraries read when they load. Skipped when numpy is already imported (``main``
    called from Python): then the scoped limit alone applies and the caller's environment
    is left as it was.
    """
    if "numpy" in sys.modules:
        return
    from trussid._util.threads import blas_env, threads_setting

    value = None
    for k, a in enumerate(argv):
        if a == "--threads" and k + 1 < len(argv):
            value = argv[k + 1]
        elif a.startswith("--threads="):
            value = a.split("=", 1)[1]
    try:
        n = threads_setting(value)
    except ValueError:
        return  # the parser reports it
    if n is not None:
        os.environ.update(blas_env(n))


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    _early_threads(argv)
    parser = build_parser()
    args = parser.parse_args(argv)
    args.argv = argv  # the command line as given, for reports' provenance
    if args.command is None:
        parser.print_help()
        return 2
    debug = args.debug or os.environ.get("TRUSSID_DEBUG") == "1"
    try:
        with _thread_limit(args.threads), _one_line_warnings(args.command):
            return int(args.func(args) or 0)
    except MemoryError as exc:
        if debug:
            raise
        detail = f" ({exc})" if str(exc) else ""
        print(f"trussid {args.command}: error: out of memory{detail}; ask for less (fewer "
              "samples, modes or orders)", file=sys.stderr)
        return 2
    except (UserError, FileNotFoundError, FileExistsError, NotADirectoryError,
            IsADirectoryError, PermissionError) as exc:
        if debug:
            raise
        if isinstance(exc, UserError):
            msg = str(exc)
        elif isinstance(exc, (FileExistsError, NotADirectoryError)):
            msg = f"{exc.filename}: {exc.strerror}"
        else:
            msg = f"{exc.strerror}: {exc.filename}"
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
    except OSError as exc:
        # Any other OSError about a file the user named (read-only file system, disk
        # full) is about their input too; one without a file name is a bug.
        if debug or exc.filename is None:
            raise
        print(f"trussid {args.command}: error: {exc.strerror}: {exc.filename}",
              file=sys.stderr)
        return 2


@contextlib.contextmanager
def _one_line_warnings(command: str):
    """Show each distinct warning raised during the command as one line on stderr
    (``trussid CMD: warning: ...``), not as Python's two-line ``file:line: Category`` form."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        warnings.filterwarnings("ignore", category=DeprecationWarning)
        warnings.filterwarnings("ignore", category=PendingDeprecationWarning)
        try:
            yield
        finally:
            seen = set()
            for w in caught:
                text = " ".join(str(w.message).split())
                if text not in seen:
                    seen.add(text)
                    print(f"trussid {command}: warning: {text}", file=sys.stderr)


@contextlib.contextmanager
def _thread_limit(value):
    """BLAS threads for the command (threadpoolctl, scoped to the call)."""
    from trussid._util.threads import blas_threads, threads_setting

    try:
        n = threads_setting(value)
    except ValueError as exc:
        raise UserError(str(exc)) from None
    if n is None:
        yield
        return
    import scipy.linalg  # noqa: F401  - load scipy's own BLAS now, so that the limit covers it

    with blas_threads(n):
        yield
