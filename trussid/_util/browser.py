"""Open a local page in headless Chromium without network: screenshots and the page's probe.

For the checks that a report page works offline (tests, ``benchmarks/bench_report_html.py``):
Chromium is Debian's ``chromium`` package (``scripts/setup.sh test`` installs it) and runs in
a network namespace with no interface (``unshare -n``, as root or with user namespaces), so
a request outside the file cannot succeed and shows in the browser's log. WebGL runs on
SwiftShader (software), as on a machine without a GPU.
"""

from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

__all__ = ["find_chromium", "BrowserRun", "open_page"]


def find_chromium() -> str | None:
    """The Chromium executable on PATH, or None."""
    return shutil.which("chromium") or shutil.which("chromium-browser")


@dataclass(frozen=True)
class BrowserRun:
    """What one headless run gave.

    Attributes
    ----------
    probe : dict or None
        The page's ``<pre id="probe">`` JSON (``dump_dom`` runs of a page with the probe).
    log : list of str
        The browser's console lines about the page itself (``CONSOLE ... source: file://``)
        and every line that names a failed request (``net::ERR_``).
    seconds : float
        Wall time of the whole run, browser start included [s].
    """

    probe: dict | None
    log: list
    seconds: float


def open_page(path, fragment: str = "", *, screenshot=None, dump_dom: bool = False,
              window=(1400, 1800), budget_ms: int = 8000, offline: bool = True,
              timeout: float = 240.0) -> BrowserRun:
    """Open ``path`` (a local HTML file) with ``#fragment`` in headless Chromium.

    Parameters
    ----------
    path : path-like
        The HTML file.
    fragment : str
        The URL fragment (no ``#``); empty: none.
    screenshot : path-like, optional
        PNG of the window after ``budget_ms`` of (virtual) time.
    budget_ms : int
        Chromium's virtual-time budget for the screenshot [ms].
    dump_dom : bool
        Read the page's probe from the DOM after the load event (no time budget: the DOM
        is dumped once the page has loaded, so the probe's load time is real time).
    window : (int, int)
        Window size [pixels].
    offline : bool
        Run in a network namespace without interfaces (``unshare -n``).
    timeout : float
        Wall time after which the browser is stopped [s] (``subprocess.TimeoutExpired``).
    """
    exe = find_chromium()
    if exe is None:
        raise FileNotFoundError(2, "no chromium on PATH (Debian: apt-get install chromium)",
                                "chromium")
    url = Path(path).resolve().as_uri() + (f"#{fragment}" if fragment else "")
    with tempfile.TemporaryDirectory(prefix="trussid-chromium-") as profile:
        cmd = (["unshare", "-n"] if offline else []) + [
            exe, "--headless", "--no-sandbox", "--enable-unsafe-swiftshader",
            "--hide-scrollbars", "--no-first-run", "--disable-extensions",
            f"--user-data-dir={profile}", f"--window-size={window[0]},{window[1]}",
            "--enable-logging=stderr", "--log-level=0"]
        if screenshot is not None:
            cmd += [f"--virtual-time-budget={int(budget_ms)}", f"--screenshot={screenshot}"]
        if dump_dom:
            cmd += ["--dump-dom"]
        t0 = time.perf_counter()
        run = subprocess.run(cmd + [url], capture_output=True, text=True, timeout=timeout)
        seconds = time.perf_counter() - t0
    page = Path(path).resolve().as_uri()
    log = [ln for ln in run.stderr.splitlines()
           if ("CONSOLE" in ln and page in ln) or "net::ERR_" in ln]
    probe = None
    if dump_dom:
        m = re.search(r'<pre id="probe">(.*?)</pre>', run.stdout, re.S)
        probe = json.loads(html.unescape(m.group(1))) if m else None
    if screenshot is not None and not Path(screenshot).is_file():
        raise RuntimeError(f"chromium wrote no screenshot (exit {run.returncode}): "
                           f"{run.stderr.strip().splitlines()[-1:] or ''}")
    return BrowserRun(probe, log, seconds)

