"""``trussid render [MODEL] --mode K --out FILE.png|FILE.gif``: draw mode shapes offscreen;
``trussid render [MODEL] --html FILE.html``: the modes in an interactive 3-D page.

MODEL is read exactly as ``trussid modes`` reads it (:func:`trussid.cli.loaders.load_structure`).
A ``.png`` gets a still of mode K (or, with ``--grid N``, modes 1..N side by side), a
``.gif`` one period of mode K's vibration. No display or GPU is needed (:mod:`trussid.fem.render`).
``--html`` writes one self-contained page (plotly.js inline, works offline) in which the
modes can be picked, watched moving, rotated and zoomed (:mod:`trussid.fem.render_html`),
mode K selected when it opens. When the loaded model carries ``decorations`` (solids such as adapters and wafers, see
:class:`trussid.fem.render.Decoration`), they are drawn too.
"""

from __future__ import annotations

import re
from pathlib import Path

from trussid._util.errors import UserError

SUFFIXES = (".png", ".gif")
#: Modes offered by ``--html`` (at least; more when --mode asks for a higher one).
HTML_MODES = 20


def _size(text: str) -> tuple[int, int]:
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not m:
        raise UserError(f"--size {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 1024x768")
    return int(m.group(1)), int(m.group(2))


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "render", help="draw a mode shape to a PNG or an animated GIF (offscreen)",
        description="Render mode shapes of MODEL (a NASTRAN bulk-data deck, a testbed parameter "
        "file (.toml), or the default testbed when omitted) without a display: the structure as "
        "solids, deformed by the mode and coloured by displacement magnitude over a faint "
        "undeformed ghost. FILE.png: a still of mode K, or with --grid N the first N modes; "
        "FILE.gif: one period of mode K's vibration.")
    p.add_argument("model", nargs="?", metavar="MODEL", help="bulk-data deck or testbed .toml file")
    p.add_argument("--mode", type=int, default=1, metavar="K", help="mode number, 1 = lowest (default 1)")
    p.add_argument("--out", metavar="FILE", help="output image: .png or .gif")
    p.add_argument("--html", metavar="FILE.html",
                   help="write the modes (the first max(K, %d)) as an interactive 3-D page "
                   "instead: pick a mode, watch it move, rotate and zoom; one file that opens "
                   "offline in a browser" % HTML_MODES)
    p.add_argument("--grid", type=int, default=None, metavar="N",
                   help="PNG only: show modes 1..N side by side instead of mode K")
    p.add_argument("--size", default=None, metavar="WxH",
                   help="image size in pixels (default 1024x768; GIF 800x600; grid 420x340 per mode)")
    p.add_argument("--scale", type=float, default=None, metavar="S",
                   help="multiply the mass-normalised mode shape by S for drawing "
                   "(default: largest displacement = --amplitude x model size)")
    p.add_argument("--amplitude", type=float, default=None, metavar="A",
                   help="largest drawn displacement as a fraction of the bounding-box diagonal (default 0.08)")
    p.add_argument("--frames", type=int, default=24, metavar="F", help="GIF frames per period (default 24)")
    p.add_argument("--view", default="iso", choices=("iso", "xz", "xy", "yz"),
                   help="camera direction (default iso; z is up)")
    p.set_defaults(func=run)


def _decorations_and_labels(loaded, modes):
    """Solids and mode labels to draw: for a testbed, its solids
    (:func:`trussid.testbed.render.testbed_decorations`) and energy labels
    (:mod:`trussid.testbed.labels`); nothing for a deck."""
    if loaded.testbed is None:
        return (), None
    from trussid.testbed.labels import label_testbed_modes
    from trussid.testbed.render import testbed_decorations

    return (testbed_decorations(loaded.testbed),
            label_testbed_modes(loaded.testbed, modes).labels)


def run(args) -> int:
    from trussid._util.files import check_parent
    from trussid.fem import render

    if (args.out is None) == (args.html is None):
        raise UserError("give --out FILE.png|FILE.gif or --html FILE.html (one of them)")
    if args.html is not None:
        return _run_html(args)
    out = Path(args.out)
    suffix = out.suffix.lower()
    if suffix not in SUFFIXES:
        raise UserError(f"--out {args.out}: unknown image type {suffix or '(no suffix)'!r}; "
                        f"use {' or '.join(SUFFIXES)}")
    check_parent(out, "--out")  # before the model is built and drawn
    if args.mode < 1:
        raise UserError(f"--mode {args.mode}: mode numbers start at 1 (the lowest mode)")
    if args.grid is not None:
        if suffix != ".png":
            raise UserError(f"--grid draws a still image: give a .png output, not {args.out}")
        if args.grid < 1:
            raise UserError(f"--grid {args.grid}: must be at least 1")
    if suffix == ".gif" and not 2 <= args.frames <= 1000:
        raise UserError(f"--frames {args.frames}: must be from 2 to 1000")
    size = _size(args.size) if args.size is not None else None
    kwargs = {}
    if args.scale is not None:
        kwargs["scale"] = args.scale
    if args.amplitude is not None:
        kwargs["amplitude"] = args.amplitude

    from trussid.fem.assembly import assemble
    from trussid.fem.modal import solve_modes
    from trussid.cli.loaders import load_structure

    loaded = load_structure(args.model)
    wanted = args.grid if args.grid is not None else args.mode
    system = assemble(loaded.model, autospc=loaded.autospc)
    tbm = loaded.testbed
    if tbm is not None:
        # as `trussid modes` does: the testbed's own solver keeps its sub-hertz suspension
        # modes, which solve_modes would round to zero
        from trussid.testbed.walls import solve_testbed_modes

        modes = solve_testbed_modes(tbm, wanted, system=system)
    else:
        modes = solve_modes(system, n_modes=wanted)
    n = len(modes.frequencies_hz)
    if wanted > n:
        what = f"--grid {args.grid}: only" if args.grid is not None else f"--mode {args.mode} is out of range:"
        raise UserError(f"{what} the model has {n} modes ({system.n_dof} free DOF); "
                        f"valid mode numbers are 1 to {n}")
    decorations, labels = _decorations_and_labels(loaded, modes)
    common = dict(decorations=decorations, view=args.view, labels=labels, **kwargs)
    if args.grid is not None:
        render.render_mode_grid(loaded.model, modes, args.grid, out,
                                **({"window_size": size} if size else {}), **common)
        print(f"wrote {out}: modes 1 to {args.grid} of {loaded.source}")
        return 0
    if suffix == ".gif":
        render.render_mode_gif(loaded.model, modes, args.mode, out, frames=args.frames,
                               **({"window_size": size} if size else {}), **common)
    else:
        render.render_mode(loaded.model, modes, args.mode, out,
                           **({"window_size": size} if size else {}), **common)
    f = float(modes.frequencies_hz[args.mode - 1])
    label = f", {labels[args.mode - 1]}" if labels is not None and len(labels) >= args.mode else ""
    print(f"wrote {out}: mode {args.mode} ({f:.6g} Hz{label}) of {loaded.source}")
    return 0


def _run_html(args) -> int:
    """``--html``: the viewer page of the first max(K, HTML_MODES) modes, mode K selected."""
    import os

    from trussid._util.files import check_parent
    from trussid.fem import render_html

    out = Path(args.html)
    if out.suffix.lower() not in (".html", ".htm"):
        raise UserError(f"--html {args.html}: give an .html file")
    check_parent(out, "--html")
    if out.is_dir():
        raise UserError(f"--html {args.html} is a directory")
    if not os.access(out.parent, os.W_OK):
        raise PermissionError(13, "cannot write there (permission denied)", str(out))
    if args.mode < 1:
        raise UserError(f"--mode {args.mode}: mode numbers start at 1 (the lowest mode)")
    for name in ("grid", "size", "scale"):
        if getattr(args, name) is not None:
            raise UserError(f"--{name} applies to images (--out), not to --html")

    from trussid.fem.assembly import assemble
    from trussid.fem.modal import solve_modes
    from trussid.cli.loaders import load_structure

    loaded = load_structure(args.model)
    wanted = max(args.mode, HTML_MODES)
    system = assemble(loaded.model, autospc=loaded.autospc)
    if loaded.testbed is not None:
        from trussid.testbed.walls import solve_testbed_modes  # as the images do, above

        modes = solve_testbed_modes(loaded.testbed, min(wanted, system.n_dof), system=system)
    else:
        modes = solve_modes(system, n_modes=min(wanted, system.n_dof))
    n = len(modes.frequencies_hz)
    if args.mode > n:
        raise UserError(f"--mode {args.mode} is out of range: the model has {n} modes "
                        f"({system.n_dof} free DOF); valid mode numbers are 1 to {n}")
    labels = None
    if loaded.testbed is not None:
        from trussid.testbed.labels import label_testbed_modes  # testbed only

        labels = label_testbed_modes(loaded.testbed, modes).labels
    kw = {} if args.amplitude is None else {"amplitude": args.amplitude}
    size = render_html.write_mode_viewer(loaded.model, modes, out, labels=labels,
                                         title=f"{Path(str(loaded.source)).name}: modes 1 to {n}",
                                         first_mode=args.mode, **kw)
    print(f"wrote {out}: modes 1 to {n} of {loaded.source}, mode {args.mode} selected "
          f"({size / 1e6:.1f} MB; open it in a browser, no network needed)")
    return 0
