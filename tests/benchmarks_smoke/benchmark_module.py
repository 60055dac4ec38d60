"""The benchmark scripts of ``benchmarks/`` imported as modules, for the tests of their
tables and guards (they are scripts, not a package: their folder goes on the path only
while one is imported, so that their imports of each other resolve)."""

import importlib
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


def benchmark_module(name: str):
    """The module of ``benchmarks/<name>.py``."""
    sys.path.insert(0, str(BENCHMARKS))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(BENCHMARKS))
