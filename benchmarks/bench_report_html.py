"""What report.html costs: its size, the time the demo spends writing it, and how long it
takes to open (load event) in headless Chromium without network (issue 36, acceptance 3).

The comparator is the demo itself, in the same run: the page's writing time is timed apart
as what the demo's run takes past its summary's total (written before the page) and set against the demo's total (everything
else it does, report.md and the PNGs included). The load time is the page's own navigation
timing (``loadEventStart``, read by its probe), median of ``--opens`` cold starts of the
browser, with the browser's start-up reported beside it.

Usage::

    python benchmarks/bench_report_html.py [--quick] [--json PATH]
    python benchmarks/bench_report_html.py --report DIR [--json PATH]   # an existing report

``--quick`` runs a tiny campaign (the figures say only that the script works); without it
the full demo (``trussid demo``: a few CPU minutes).
"""

from __future__ import annotations

import argparse
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

from results_io import finish, stamp, write_json  # noqa: E402

#: The bounds of issue 36 (acceptance 3).
MAX_BYTES, MAX_LOAD_S, MAX_SHARE = 25e6, 10.0, 0.10


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--report", type=Path, help="measure this report directory (no demo run)")
    ap.add_argument("--opens", type=int, default=3)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from trussid._util.browser import find_chromium, open_page
    from trussid.campaign.demo import demo_settings, run_demo

    st = stamp()
    res = {"kind": f"report {args.report}" if args.report else ("quick" if args.quick else "full")}
    with tempfile.TemporaryDirectory() as tmp:
        out = args.report
        if out is None:
            out = Path(tmp) / "report"
            settings = (demo_settings(True, n_identification=2500, n_validation=1500,
                                      simo_order=12, mimo_order=6, h1_nperseg=256)
                        if args.quick else demo_settings())
            c0, t0 = _cpu(), time.perf_counter()
            summary = run_demo(out, settings, progress=None)
            res["demo_cpu_s"] = _cpu() - c0
            res["demo_wall_s"] = time.perf_counter() - t0
            t = summary.timings_s
            # the summary's total stops before report.html (summary.json is written first);
            # what the run took past it is the page (and the report folder's rename)
            res["report_html_s"] = res["demo_wall_s"] - t["total"]
            res["demo_total_s"] = t["total"]  # everything before report.html
            res["report_html_share"] = res["report_html_s"] / t["total"]
        page = out / "report.html"
        res["bytes"] = page.stat().st_size
        if find_chromium() is not None:
            loads, walls = [], []
            for _ in range(args.opens):
                run = open_page(page, "probe", dump_dom=True)
                if run.probe is None:
                    raise SystemExit(f"the page reported no probe: {run.log[-3:]}")
                if run.probe["resources"]:
                    raise SystemExit(f"the page requested {run.probe['resources']}")
                loads.append(run.probe["load_ms"] / 1000.0)
                walls.append(run.seconds)
            res["load_event_s"] = statistics.median(loads)
            res["load_event_s_all"] = loads
            res["browser_run_s_median"] = statistics.median(walls)
        else:
            res["load_event_s"] = None
            res["note"] = "no chromium: load time not measured"
    guards = [{"name": "report.html size [bytes]", "value": res["bytes"], "bound": MAX_BYTES,
               "ok": res["bytes"] < MAX_BYTES}]
    if res.get("load_event_s") is not None:
        guards.append({"name": "load event [s]", "value": res["load_event_s"],
                       "bound": MAX_LOAD_S, "ok": res["load_event_s"] < MAX_LOAD_S})
    payload = {"stamp": finish(st), "result": res}
    if not args.quick:  # the bounds are the full demo's; a quick run only shows it works
        payload["guards"] = guards
    for k, v in res.items():
        print(f"{k}: {v}")
    if args.json:
        write_json(args.json, payload)
    return 0


if __name__ == "__main__":
    sys.exit(main())
