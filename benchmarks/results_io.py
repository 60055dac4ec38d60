"""Stamps and writers for benchmark results: every result says what it measured and where.

A result file ``benchmarks/results/<name>.json`` is one JSON object with at least

- ``"stamp"``: :func:`stamp` — the commit measured (and whether the work tree had
  uncommitted changes), the machine, the date, and the load average at start and end;
- ``"tables"`` (optional): ``{table_name: {"columns": [...], "rows": [[...], ...],
  "notes": "..."}}``, the figures meant for the README. ``benchmarks/readme_tables.py``
  renders each as the block between ``<!-- bench:table_name -->`` and
  ``<!-- /bench:table_name -->`` in README.md, with the commit of the measurement in every
  row;
- ``"guards"`` (optional): ``[{"name", "value", "bound", "ok"}, ...]``, scaling checks;
  ``benchmarks/run.py`` fails when one is not ok.

Adding a benchmark: write a module with ``run(quick: bool, out: Path) -> dict`` (the dict as
above, without the stamp) and list it in ``benchmarks/run.py``'s ``BENCHMARKS``.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"


def git_commit(root: Path = ROOT) -> str:
    """Short hash of HEAD, with ``+dirty`` when tracked files under the package differ."""
    try:
        sha = subprocess.run(["git", "-C", str(root), "rev-parse", "--short=7", "HEAD"], capture_output=True,
                             text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return os.environ.get("TRUSSID_COMMIT", "unknown")
    dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no", "--",
                            "fem", "plid", "geometry", "trussid"], capture_output=True, text=True).stdout.strip()
    return sha + ("+dirty" if dirty else "")


def machine() -> dict:
    """Cores, CPU model, memory, Python and the numeric libraries' versions."""
    import numpy as np
    import scipy

    cpu = platform.processor() or "?"
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        cpu = next((ln.split(":", 1)[1].strip() for ln in lscpu.splitlines() if ln.startswith("Model name")), cpu)
    except OSError:
        pass
    mem = "?"
    with open("/proc/meminfo") as fh:
        for line in fh:
            if line.startswith("MemTotal:"):
                mem = f"{int(line.split()[1]) / 1024**2:.1f} GiB"
    return {"nproc": len(os.sched_getaffinity(0)), "cpu": cpu, "memory": mem, "host": platform.node(),
            "python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__}


def stamp() -> dict:
    """Commit, machine, UTC date and 1/5/15-minute load averages at the start."""
    return {"commit": git_commit(), "machine": machine(), "date_utc": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "loadavg_start": [round(x, 2) for x in os.getloadavg()]}


def finish(st: dict) -> dict:
    """``st`` with the load average at the end."""
    return {**st, "loadavg_end": [round(x, 2) for x in os.getloadavg()]}


def write_json(path: Path, payload: dict) -> Path:
    """Write ``payload`` to ``path`` atomically (a temporary name, then rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(payload, indent=1, default=float) + "\n")
    os.replace(tmp, path)
    return path


def peak_rss_mb() -> float:
    """This process's peak resident set size (``VmHWM``) [MB]."""
    return _status_mb("VmHWM")


def rss_mb() -> float:
    """This process's resident set size (``VmRSS``) [MB]."""
    return _status_mb("VmRSS")


def _status_mb(field: str) -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024.0
    return float("nan")
