"""NASTRAN deck reading against solving: parse + build of a 1e5-element deck vs 20 modes (issue 13),
and the project's own parser against the old pyNastran-based reader (issue 30).

Usage::

    python benchmarks/bench_nastran_parse.py [--elements 100000] [--modes 20] [--repeat 1]
        [--baseline REV_OR_CHECKOUT] [--corpus ../shared/nastran-corpus]
        [--out benchmarks/results/nastran_parse]

A cubic lattice frame of CBARs (:func:`fem_models.cubic_lattice`, ``3 n^2 (n - 1)``
elements, base clamped) with at least ``--elements`` elements is written as a deck with
:func:`trussid.fem.nastran.write_bdf` (large-field GRID, CBAR, PBAR, MAT1, SPC1, EIGRL; not
timed). (A 1e5-element truss boom is 2.2 km long: its first bending eigenvalue is 1e-16 of
the stiffest element's and the modal solver's zero-eigenvalue test takes it for a mechanism.)
Then, in this process:

- *parse*: pyNastran reading the deck (:func:`trussid.fem.nastran.deck.parse_bdf`: the BDF object);
- *read_bdf*: the whole :func:`trussid.fem.nastran.read_bdf` (parse + translation into a
  :class:`trussid.fem.Model`); *build* = read_bdf - parse, the part that is trussid's;
- *assemble*: :func:`trussid.fem.assembly.assemble`;
- *eigen*: :func:`trussid.fem.modal.solve_modes` for the lowest ``--modes`` modes
  (``--modes 0`` skips it: half an hour on a loaded 2-core machine, and not what a reading
  regression needs).

Wall and CPU time (``time.perf_counter``, ``time.process_time``) per phase, best of
``--repeat``; the load average before and after, machine and commit go beside them in
``OUT.md`` and ``OUT.json``.

Reader against reader (issue 30, acceptance 2), in the same run: ``--baseline`` names an older
version of the project (a git revision of this repository, exported with ``git archive``, or
a checkout directory), e.g. 2b468f8, the last commit whose reader parsed through pyNastran.
Each reader runs in a subprocess of its own (imports not timed) over the same decks: the
41 published decks of the NASTRAN corpus (``--corpus``, when present: every deck read, or
refused, counts) and the 1e5-element deck; the CPU time of each ``read_bdf`` is summed. The
old reader needs pyNastran importable: pyNastran 1.4.1 uses ``np.in1d``, removed in numpy 2.4,
so its subprocess aliases ``np.in1d`` to ``np.isin`` (and ``np.chararray`` to numpy's
``char.chararray``) when they are missing; the comparator only, never the package. pyNastran
is no dependency of any extra (every release declares ``numpy<2``, which no extra of a numpy-2
project can resolve): for ``--baseline`` install it beside the project by hand,
``.venv/bin/python -m pip install --no-deps pyNastran==1.4.1 cpylog docopt-ng colorama``. A cProfile of one read_bdf call lists the functions where the
time goes (top 12 by cumulative time) so that what is trussid's can be told from pyNastran's.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_fem_vs_opensees import machine_info  # noqa: E402
from fem_models import cubic_lattice, to_trussid  # noqa: E402


def timed(fn, *args, **kw):
    w, c = time.perf_counter(), time.process_time()
    out = fn(*args, **kw)
    return out, time.perf_counter() - w, time.process_time() - c


def main(argv=None) -> int:
    from trussid._util.threads import blas_threads  # noqa: F401  (documented BLAS setting)
    from trussid.fem import nastran
    from trussid.fem.assembly import assemble
    from trussid.fem.modal import solve_modes

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--elements", type=int, default=100_000)
    ap.add_argument("--modes", type=int, default=20)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--out", default=str(HERE / "results" / "nastran_parse"))
    ap.add_argument("--baseline", default=None, metavar="REV_OR_CHECKOUT",
                    help="also time read_bdf of another version of the project (a git revision, or a "
                    "checkout directory) on the same decks, in a subprocess, in the same run")
    ap.add_argument("--corpus", default=str(HERE.parent.parent / "shared" / "nastran-corpus"),
                    help="the NASTRAN corpus (its 41 published decks are read by both readers)")
    args = ap.parse_args(argv)

    n = 2
    while 3 * n * n * (n - 1) < args.elements:
        n += 1
    spec = cubic_lattice(n)
    model = to_trussid(spec)
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        deck = Path(tmp) / "lattice.bdf"
        nastran.write_bdf(model, deck, n_modes=args.modes or 20, title="benchmark lattice")
        size_mb = deck.stat().st_size / 1e6
        best = {}
        for _ in range(args.repeat):
            _, w_parse, c_parse = timed(nastran.deck.parse_bdf, deck)
            (m2, info), w_read, c_read = timed(nastran.read_bdf, deck)
            system, w_asm, c_asm = timed(assemble, m2, autospc=info.autospc)
            if args.modes > 0:
                modes, w_eig, c_eig = timed(solve_modes, system, n_modes=args.modes)
            else:
                modes, w_eig, c_eig = None, float("nan"), float("nan")
            run = {"parse": (w_parse, c_parse), "read_bdf": (w_read, c_read),
                   "build": (w_read - w_parse, c_read - c_parse), "assemble": (w_asm, c_asm),
                   "eigen": (w_eig, c_eig)}
            for k, v in run.items():
                best[k] = min(best.get(k, v), v)
        decks = _corpus_decks(Path(args.corpus)) + [deck]
        current = _timed_reads(None, decks)
        baseline = _timed_reads(_checkout(args.baseline, Path(tmp)), decks) if args.baseline else None
        prof = cProfile.Profile()
        prof.enable()
        nastran.read_bdf(deck)
        prof.disable()
    load_after = os.getloadavg()
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats("cumulative").print_stats(12)
    profile = "\n".join(ln for ln in s.getvalue().splitlines() if ln.strip())

    info_m = machine_info()
    res = {"elements": int(len(model.beams)), "grids": int(len(model.node_ids)), "dof": int(system.n_dof),
           "deck_mb": size_mb, "modes": args.modes, "lowest_hz": [float(f) for f in modes.frequencies_hz[:3]] if modes is not None else [],
           "wall_s": {k: v[0] for k, v in best.items()}, "cpu_s": {k: v[1] for k, v in best.items()},
           "readers": {"current": current, "baseline": baseline}, "load_before": load_before, "load_after": load_after, "machine": info_m,
           "parse_build_below_eigen": (best["read_bdf"][0] + best["assemble"][0] < best["eigen"][0]
                                       if args.modes > 0 else None)}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(res, indent=2, default=float))
    w, c = res["wall_s"], res["cpu_s"]
    rows = "\n".join(f"| {k} | {w[k]:.2f} | {c[k]:.2f} |" for k in ("parse", "build", "read_bdf", "assemble", "eigen"))
    if args.modes > 0:
        versus = (f"Parse + build + assemble: {w['read_bdf'] + w['assemble']:.2f} s wall against {w['eigen']:.2f} s "
                  f"for the\nlowest {args.modes} modes ({'below' if res['parse_build_below_eigen'] else 'ABOVE'} "
                  f"the eigen time).")
    else:
        versus = (f"Parse + build + assemble: {w['read_bdf'] + w['assemble']:.2f} s wall, "
                  f"{c['read_bdf'] + c['assemble']:.2f} s CPU (eigen not run: --modes 0).")
    md = f"""# NASTRAN deck: parse + build{f' vs {args.modes} modes' if args.modes > 0 else ''}

`python benchmarks/bench_nastran_parse.py --elements {args.elements} --modes {args.modes}` (issue 13, acceptance 5; issue 25, acceptance 4).

Deck: cubic lattice frame ({n}^3 grids, base clamped) of {res['elements']} CBAR elements, {res['grids']} grids ({res['dof']} free DOF after
the clamp), {size_mb:.1f} MB of large-field bulk data written by `write_bdf`; consistent mass.

| phase | wall [s] | CPU [s] |
| --- | --- | --- |
{rows}

{versus}
{_versus(current, baseline)}
*parse* is trussid's parser (`fem/nastran/cards.py`, `bulk.py`: text to typed entries);
*build* (the translation into the model) is {w['build']:.2f} s of read_bdf.

Machine: {info_m['nproc']} cores ({info_m['cpu']}), {info_m['memory']}; load average
{load_before[0]:.2f} before, {load_after[0]:.2f} after (a shared machine: times are best of
{args.repeat}); Python {info_m['python']}, numpy {info_m['numpy']}, scipy {info_m['scipy']};
fem at {info_m['fem']}; {info_m['date_utc']}.

Where read_bdf's time goes (cProfile, cumulative):

```
{profile}
```
"""
    out.with_suffix(".md").write_text(md)
    print(md)
    return 0


_READ_RUNNER = """
import json, sys, time
if sys.argv[1] != "-":
    # the worktree's editable install would shadow the other version: drop its import finders
    sys.meta_path = [f for f in sys.meta_path if "editable" not in getattr(f, "__name__", type(f).__name__).lower()]
    sys.path.insert(0, sys.argv[1])
    import numpy as np
    # pyNastran 1.4.1 (the old reader's parser) uses names numpy removed: the comparator only
    if not hasattr(np, "in1d"):
        np.in1d = np.isin
    if not hasattr(np, "chararray"):
        np.chararray = np.char.chararray
import warnings
warnings.simplefilter("ignore")
from trussid.fem import nastran
from trussid.fem.errors import ModelError
if sys.argv[1] != "-":
    assert nastran.__file__.startswith(sys.argv[1]), nastran.__file__
out = []
for deck in sys.argv[2:]:
    w, c = time.perf_counter(), time.process_time()
    try:
        nastran.read_bdf(deck)
        status = "read"
    except ModelError as exc:
        status = "refused: " + str(exc)[:120]
    out.append({"deck": deck, "status": status, "wall_s": time.perf_counter() - w,
                "cpu_s": time.process_time() - c})
print(json.dumps(out))
"""


def _corpus_decks(corpus: Path) -> list:
    """The published deck of each corpus case (``original_deck``), or none without the corpus."""
    cases = sorted((corpus / "cases").glob("*.json")) if corpus.is_dir() else []
    return [corpus / json.loads(c.read_text())["original_deck"] for c in cases]


def _checkout(rev_or_dir: str, tmp: Path) -> Path:
    """A package tree of another version: trussid/ with fem, plid, geometry linked in, as the
    project's installation maps them (a git revision is exported first)."""
    import subprocess

    src = Path(rev_or_dir)
    if not src.is_dir():
        src = tmp / "baseline_src"
        src.mkdir()
        archive = subprocess.run(["git", "-C", str(HERE.parent), "archive", rev_or_dir], capture_output=True,
                                 check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(src)], input=archive, check=True)
    pkg_root = tmp / "baseline_pkg"
    pkg = pkg_root / "trussid"
    pkg.mkdir(parents=True)
    for item in (src / "trussid").iterdir():
        (pkg / item.name).symlink_to(item)
    for sub in ("fem", "plid", "geometry"):
        (pkg / sub).symlink_to(src / sub)
    commit = subprocess.run(["git", "-C", str(HERE.parent), "rev-parse", "--short", rev_or_dir],
                            capture_output=True, text=True).stdout.strip() if src.name == "baseline_src" else \
        subprocess.run(["git", "-C", str(src), "rev-parse", "--short", "HEAD"], capture_output=True,
                       text=True).stdout.strip()
    (pkg_root / "COMMIT").write_text(commit or str(rev_or_dir))
    return pkg_root


def _timed_reads(pkg_root: Path | None, decks: list) -> dict:
    """CPU and wall time of read_bdf per deck, in a subprocess (``None``: this checkout)."""
    import subprocess

    p = subprocess.run([sys.executable, "-c", _READ_RUNNER, str(pkg_root) if pkg_root else "-",
                        *map(str, decks)], capture_output=True, text=True, cwd=str(Path(decks[-1]).parent))
    if p.returncode != 0:
        raise RuntimeError(f"reader subprocess failed: {p.stderr.strip().splitlines()[-1:]}")
    runs = json.loads(p.stdout)
    corpus, big = runs[:-1], runs[-1]
    return {"version": (pkg_root / "COMMIT").read_text() if pkg_root else "this checkout",
            "corpus_decks": len(corpus), "corpus_read": sum(r["status"] == "read" for r in corpus),
            "corpus_cpu_s": sum(r["cpu_s"] for r in corpus), "corpus_wall_s": sum(r["wall_s"] for r in corpus),
            "big_cpu_s": big["cpu_s"], "big_wall_s": big["wall_s"],
            "total_cpu_s": sum(r["cpu_s"] for r in runs), "per_deck": runs}


def _versus(current: dict, baseline: dict | None) -> str:
    rows = [("this checkout", current)] + ([(f"baseline {baseline['version']} (pyNastran parser)", baseline)]
                                           if baseline else [])
    table = "\n".join(f"| {name} | {r['corpus_read']} of {r['corpus_decks']} | {r['corpus_cpu_s']:.2f} | "
                      f"{r['big_cpu_s']:.2f} | {r['total_cpu_s']:.2f} |" for name, r in rows)
    verdict = ""
    if baseline:
        ratio = current["total_cpu_s"] / baseline["total_cpu_s"]
        verdict = (f"\nThe project's parser takes {ratio:.2f} x the old reader's CPU time "
                   f"({'at most' if ratio <= 1 else 'MORE than'} the old reader's).")
    return f"""Reader against reader, same decks, same run (read_bdf in a subprocess each, CPU time summed):

| reader | corpus decks read | corpus CPU [s] | lattice deck CPU [s] | total CPU [s] |
| --- | --- | --- | --- | --- |
{table}
{verdict}
"""


if __name__ == "__main__":
    sys.exit(main())
