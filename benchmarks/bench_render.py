"""Time offscreen mode-shape rendering: one PNG still and a 24-frame GIF (issue 8, item 5).

Each (model, VTK backend) pair runs in a fresh subprocess, so the first PNG includes what a
``trussid render`` call pays once: creating the OpenGL context and compiling shaders.
Backends side by side: OSMesa (what :mod:`trussid.fem.render` selects; Mesa llvmpipe, no X, no GPU)
and EGL (the same llvmpipe rasteriser through Mesa's surfaceless EGL; VTK's own choice on
this machine after it fails to reach an X server). Models: the default testbed when
``trussid.testbed.model`` provides it, the four-legged table deck ``examples/decks/frame.bdf``, and a
6 x 6 x 6 cubic lattice (``benchmarks/fem_models.py``) for scaling.

Usage::

    python benchmarks/bench_render.py            # all, writes benchmarks/results/render.md
    python benchmarks/bench_render.py --one MODEL   # one JSON line (used internally)
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "render.md"
BACKENDS = {"OSMesa (fem.render default)": None, "EGL": "vtkEGLRenderWindow"}
PNG_SIZE = (1024, 768)
GIF_SIZE = (800, 600)
GIF_FRAMES = 24


def load(name: str):
    """(model, modes, decorations) for a benchmark case."""
    sys.path.insert(0, str(ROOT))
    from trussid.fem.modal import solve_modes

    if name == "testbed":
        from trussid.testbed.render import testbed_decorations
        from trussid.testbed.model import build_testbed

        from trussid.testbed.walls import solve_testbed_modes

        tbm = build_testbed()
        return tbm.model, solve_testbed_modes(tbm, 12), testbed_decorations(tbm)
    elif name == "frame.bdf":
        from trussid.fem.nastran import read_bdf

        model, _ = read_bdf(ROOT / "examples" / "decks" / "frame.bdf")
        decorations = ()
    elif name == "lattice6":
        sys.path.insert(0, str(ROOT / "benchmarks"))
        from fem_models import cubic_lattice, to_trussid

        model = to_trussid(cubic_lattice(6))
        decorations = ()
    else:
        raise SystemExit(f"unknown model {name!r}")
    return model, solve_modes(model, n_modes=12), decorations


def one(name: str, warm_repeats: int = 5, gif_repeats: int = 3) -> dict:
    from trussid.fem import render

    model, modes, decorations = load(name)
    first = 7 if name == "testbed" else 1  # the testbed's modes 1-6 are the suspension
    out = Path(tempfile.mkdtemp())
    t0 = time.perf_counter()
    render.render_mode(model, modes, first, out / "cold.png", window_size=PNG_SIZE, decorations=decorations)
    cold = time.perf_counter() - t0
    warm = []
    for k in range(warm_repeats):
        t0 = time.perf_counter()
        render.render_mode(model, modes, first + 1 + k, out / f"m{k}.png", window_size=PNG_SIZE, decorations=decorations)
        warm.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    scene = render.mode_scene(model, modes, first, decorations=decorations)
    scene.meshes(1.0)
    build = time.perf_counter() - t0
    gif = []
    for _ in range(gif_repeats):
        t0 = time.perf_counter()
        frames = render.render_mode_gif(model, modes, first, out / "m.gif", frames=GIF_FRAMES,
                                        window_size=GIF_SIZE, decorations=decorations)
        gif.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    render._write_gif(frames, out / "again.gif", 1.5 / GIF_FRAMES)
    encode = time.perf_counter() - t0
    import pyvista as pv

    with render.offscreen_backend():
        p = pv.Plotter(off_screen=True)
        window = type(p.ren_win).__name__
        p.close()
    n_el = len(model.beams)
    return {"model": name, "beams": n_el, "nodes": int(model.n_nodes), "window": window,
            # min of repeats: on a shared machine the noise only ever adds time
            "png_cold_s": cold, "png_warm_s": min(warm), "png_warm_median_s": statistics.median(warm),
            "scene_build_s": build, "gif_s": min(gif), "gif_median_s": statistics.median(gif),
            "gif_encode_s": encode,
            "png_sha1": hashlib.sha1((out / "m0.png").read_bytes()).hexdigest()[:10],
            "gif_bytes": (out / "m.gif").stat().st_size, "png_bytes": (out / "m0.png").stat().st_size}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--one", metavar="MODEL")
    parser.add_argument("--quick", action="store_true",
                        help="CI form: the example deck with the default backend, 1 warm PNG, 1 GIF")
    parser.add_argument("--out", type=Path, default=RESULTS, help="Markdown file to write")
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one, *((1, 1) if args.quick else ()))))
        return
    backends = dict(list(BACKENDS.items())[:1]) if args.quick else BACKENDS
    cases = ["frame.bdf"]
    if (ROOT / "benchmarks" / "fem_models.py").exists() and not args.quick:
        cases.append("lattice6")
    try:
        import importlib.util

        if importlib.util.find_spec("trussid.testbed.model") is not None and not args.quick:
            cases.insert(0, "testbed")
    except ImportError:
        pass
    rows = []
    load_before = os.getloadavg()[0]
    # cases outer, backends inner: the two backends of a case run close together in time,
    # so a burst of load from other jobs hits both alike
    for case in cases:
        for backend, window in backends.items():
            env = {k: v for k, v in os.environ.items()
                   if k not in ("DISPLAY", "WAYLAND_DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW")}
            if window:
                env["VTK_DEFAULT_OPENGL_WINDOW"] = window
            res = subprocess.run([sys.executable, __file__, "--one", case, *(["--quick"] if args.quick else [])],
                                 capture_output=True, text=True, env=env, cwd=ROOT)
            if res.returncode != 0:
                print(res.stderr, file=sys.stderr)
                raise SystemExit(f"{case} with {backend} failed")
            row = json.loads(res.stdout.strip().splitlines()[-1])
            row["backend"] = backend
            row["stderr_warnings"] = sum("WARN" in line or "ERR" in line for line in res.stderr.splitlines())
            rows.append(row)
            print(json.dumps(row), flush=True)
    write_md(rows, cases, (load_before, os.getloadavg()[0]), args.out)


def write_md(rows, cases, load, path: Path = RESULTS) -> None:
    import vtk
    import pyvista

    cpu = platform.processor() or "unknown CPU"
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    lines = [
        "# Offscreen rendering benchmark (issue 8, item 5)",
        "",
        f"Machine: {cpu}, {os.cpu_count()} cores shared with other jobs; {platform.platform()}; "
        f"Python {platform.python_version()}, VTK {vtk.vtkVersion.GetVTKVersion()}, pyvista {pyvista.__version__}; "
        "no display, no GPU (Mesa llvmpipe software rasteriser). "
        f"1-minute load average {load[0]:.1f} before and {load[1]:.1f} after the run (other jobs share the cores: "
        "times are upper bounds for an idle machine).",
        "",
        f"PNG: {PNG_SIZE[0]}x{PNG_SIZE[1]} still of one mode (scene build, render, PNG write). "
        "Cold = first call in a fresh process (OpenGL context, shaders); warm = fastest of 5 later calls "
        "(median in brackets). "
        f"GIF: {GIF_FRAMES} frames at {GIF_SIZE[0]}x{GIF_SIZE[1]}, fastest of 3 runs (median in brackets), "
        "of which 'encode' is Pillow's palette quantisation and GIF write. "
        "'PNG sha1' is the hash of one output file: equal hashes mean pixel-identical images.",
        "Produced by `python benchmarks/bench_render.py`.",
        "",
        "| model | beams | backend (VTK window) | PNG cold [s] | PNG warm [s] | GIF 24 frames [s] | of which encode [s] | scene build [s] | VTK warnings | PNG sha1 |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in rows:
        lines.append(f"| {r['model']} | {r['beams']} | {r['backend']} ({r['window']}) | {r['png_cold_s']:.2f} | "
                     f"{r['png_warm_s']:.2f} ({r['png_warm_median_s']:.2f}) | {r['gif_s']:.2f} ({r['gif_median_s']:.2f}) | "
                     f"{r['gif_encode_s']:.2f} | {r['scene_build_s']:.3f} | {r['stderr_warnings']} | {r['png_sha1']} |")
    lines += [
        "",
        "Why OSMesa is the default: both backends run the same llvmpipe rasteriser (equal hashes "
        "above), so the picture is the same and the speed differences in the table go both ways from row to row (load from other jobs varies by the minute); OSMesa needs one Debian "
        "package (libosmesa6, which brings libglapi-mesa and libllvm15), while Mesa's EGL needs "
        "libegl1, libegl-mesa0, libgbm1, libgl1-mesa-dri and the X11/xcb client libraries that "
        "libegl-mesa0 links, and VTK's own default first tries an X server (a 'bad X server "
        "connection' warning without a display). Tracing the OSMesa path (strace) shows no "
        "libGL, libEGL or libX11 file opened.",
    ]
    if "testbed" not in cases:
        lines += ["", "The default testbed FE model (`fem.testbed`) did not exist when this was run; "
                  "the table uses the example deck and a lattice instead."]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
