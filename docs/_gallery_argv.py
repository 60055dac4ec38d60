"""Command-line arguments the documentation build gives each gallery example.

Examples with a command line run in the gallery as ``python examples/NAME.py ARGS``; the
build passes a scratch ``--out`` (so no file lands in the source tree) and, where the
default run takes minutes, the example's own fast setting.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

_SCRATCH = Path(tempfile.mkdtemp(prefix="trussid-gallery-"))

ARGS = {
    "model_updating.py": ["--exact"],  # updating from exact frequencies: seconds, not a minute
    "wall_thickness_study.py": ["--points", "9"],
}
OUT = {"model_updating.py", "wall_thickness_study.py"}  # the examples with an --out file


def reset_argv(gallery_conf, script_vars) -> list[str]:
    """``sys.argv[1:]`` for the example ``script_vars["src_file"]``."""
    name = Path(script_vars["src_file"]).name
    args = list(ARGS.get(name, []))
    if name in OUT:
        args += ["--out", str(_SCRATCH / name.replace(".py", ".png"))]
    return args
