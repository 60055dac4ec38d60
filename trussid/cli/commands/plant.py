"""``trussid plant [MODEL] --out PLANT.npz``: the control-ready plant of a testbed, or of any
NASTRAN deck with ``--io IO.toml`` (actuators and sensors, :mod:`trussid.fem.iospec`).

The plant runs from the D/A command volts of each actuator channel, through the smoothing
filter, the power amplifier and the PZT actuators, to the accelerometer volts, discretised
by zero-order hold at the sample rate. PLANT.npz holds the discrete plant (``A, B, C, D, dt``
and names, as every model file), the continuous one beside it (``c_A`` ...) and the lab it
was made with (``lab_json``: converters, chain, sample rate), which ``trussid closed-loop``
and ``trussid simulate`` use for its converters.
"""

from __future__ import annotations

from pathlib import Path


from trussid._util.errors import UserError
from trussid._util.jsonio import dumps


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "plant", help="build a state-space plant: the testbed's (PZT volts in, accelerometer volts "
        "out) or a deck's with --io",
        description="Build the control-ready plant of a testbed: modes by finite elements, PZT "
        "strain actuators (3 channels, each driving the two struts that share a top vertex), "
        "accelerometers at the UDF corners, the lab's smoothing filter, amplifier and converters, "
        "discretised by zero-order hold. MODEL is a testbed parameter file (.toml) or omitted for "
        "the default testbed. For any other frame, give a NASTRAN deck and --io IO.toml, which "
        "lists force/moment actuators at nodes, PZT strain actuators over elements and "
        "displacement/velocity/acceleration sensors at nodes (format: trussid.fem.iospec; "
        "example: examples/decks/frame_io.toml); that plant is in the deck's units, without "
        "the testbed's lab chain.")
    p.add_argument("model", nargs="?", metavar="MODEL",
                   help="testbed parameter file (.toml), or a NASTRAN deck with --io")
    p.add_argument("--io", metavar="IO.toml", default=None,
                   help="actuators and sensors of a NASTRAN deck (required for a deck)")
    p.add_argument("--out", required=True, metavar="PLANT.npz", help="output model file (.npz)")
    p.add_argument("--fs", type=float, default=None, metavar="HZ", help="sample rate (default: the testbed lab's, [daq] sample_rate)")
    p.add_argument("--modes", type=int, default=None, metavar="N", help="modes kept (default: all below the Nyquist frequency)")
    p.add_argument("--damping", type=float, default=None, metavar="Z",
                   help="modal damping ratio (default: the testbed's, 0.0025; with --io the "
                   "file's [plant] damping, else 0.02)")
    p.add_argument("--plot", default=None, metavar="BODE.png", help="also write a Bode plot")
    p.add_argument("--json", action="store_true", help="print a JSON summary instead of text")
    p.add_argument("--conventions", choices=("nx", "msc"), default=None,
                   help="with --io: the NASTRAN build whose element conventions the deck follows "
                   "where builds differ (PBARL/PBEAML ROD shear factor: nx 0.9, msc 6/7); default nx")
    p.set_defaults(func=run)


def run(args) -> int:
    from trussid._util.files import check_parent
    from trussid.cli.loaders import testbed_spec
    from trussid.geometry.lab import lab_record
    from trussid.plid.modelfile import save_model
    from trussid.testbed.plant import plant_summary, testbed_plant

    out = Path(args.out)
    if out.suffix.lower() != ".npz":
        raise UserError(f"--out {args.out}: the plant is written as a model file (.npz)")
    if args.plot is not None and Path(args.plot).suffix.lower() != ".png":
        raise UserError(f"--plot {args.plot}: the Bode plot is written as PNG")
    check_parent(out, "--out")
    if args.plot is not None:
        check_parent(args.plot, "--plot")
    if args.modes is not None and args.modes < 1:
        raise UserError(f"--modes must be at least 1, got {args.modes}")
    if args.damping is not None and not (0 <= args.damping < 1):
        raise UserError(f"--damping must be in [0, 1), got {args.damping}")
    if args.fs is not None and not args.fs > 0:
        raise UserError(f"--fs must be positive, got {args.fs}")
    if args.io is not None:
        return run_io(args, out)
    if args.conventions is not None:
        raise UserError("--conventions applies to a NASTRAN deck given with --io IO.toml, not to a testbed")
    if args.model is not None and Path(args.model).suffix.lower() != ".toml":
        raise UserError(f"{args.model}: a plant needs actuators and sensors: give them with "
                        "--io IO.toml for a NASTRAN deck, or a testbed parameter file (.toml), "
                        "or no MODEL for the default testbed")
    tb = testbed_spec(args.model)
    source = "default testbed" if args.model is None else str(args.model)
    plant = testbed_plant(tb, n_modes=args.modes, damping=args.damping, sample_rate=args.fs)
    ch = plant.chain
    # audit B35: a 100 Hz plant silently kept a band-shaping low-pass it cannot represent.
    # The smoothing filter is not checked: it smooths the D/A's staircase, whose images lie
    # above Nyquist, so its corner is there by design (the thesis lab's 1300 Hz at 1600 Hz;
    # warning about it made the default `trussid plant` warn about itself, issue 30 D7).
    if ch.lowpass_cutoff >= 0.5 * ch.sample_rate:
        import sys

        print(f"trussid plant: warning: at {ch.sample_rate:g} Hz the corner of the low-pass "
              f"({ch.lowpass_cutoff:g} Hz) lies above the Nyquist frequency "
              f"({0.5 * ch.sample_rate:g} Hz): the discrete plant cannot show it",
              file=sys.stderr)
    # the plant's lab goes with it: trussid closed-loop runs its converters, not defaults
    save_model(out, plant.discrete, continuous=plant.continuous,
               extra={"mode_frequencies_hz": plant.modes.frequencies_hz, **lab_record(plant.lab)})
    if args.plot:
        from trussid.plots import plant_bode_figure, save_figure

        fs = plant.chain.sample_rate
        save_figure(plant_bode_figure(
            plant.discrete, f"Testbed plant: D/A volts to accelerometer volts, ZOH at {fs:g} Hz"),
            args.plot, dpi=120)
    s = plant_summary(plant)
    s["model"] = source
    s["out"] = str(out)
    if args.json:
        print(dumps(s), end="")
        return 0
    print(f"plant of the {source}: {len(s['inputs'])} inputs ({', '.join(s['inputs'])}), "
          f"{len(s['outputs'])} outputs ({', '.join(s['outputs'])}), {s['states']} states, "
          f"ZOH at {s['sample_rate_hz']:g} Hz")
    print(f"modes kept: {s['modes_kept']} (up to {s['mode_frequencies_hz'][-1]:.1f} Hz)")
    print(f"actuator capacitance from the wafer data: {s['actuator_capacitance_f'] * 1e6:.4f} uF "
          f"(thesis: {s['actuator_capacitance_thesis_f'] * 1e6:.3f} uF)")
    print(f"strictly proper: {s['strictly_proper']}; stable: {s['stable']}")
    print("\n   pole  frequency [Hz]   damping [%]")
    for k, pl in enumerate(s["poles"], 1):
        print(f"  {k:5d}  {pl['frequency_hz']:14.2f}  {100 * pl['damping']:12.3f}")
    print("\npeak gain over 1 Hz .. Nyquist [V/V] (rows: outputs, columns: inputs)")
    print("          " + "".join(f"{n:>12s}" for n in s["inputs"]))
    for name, row in zip(s["outputs"], s["peak_gain_v_per_v"]):
        print(f"  {name:8s}" + "".join(f"{g:12.4g}" for g in row))
    print(f"\nwrote {out}" + (f" and {args.plot}" if args.plot else ""))
    return 0


def run_io(args, out: Path) -> int:
    """``trussid plant DECK --io IO.toml``: the generic plant of any deck (fem.iospec)."""
    import control
    import numpy as np

    from trussid.cli.loaders import BULK_SUFFIXES, deck_structure
    from trussid.fem.iospec import io_plant, read_io
    from trussid.plid.modelfile import save_model

    if args.model is None or Path(args.model).suffix.lower() not in BULK_SUFFIXES:
        raise UserError(f"--io needs a NASTRAN deck ({', '.join(BULK_SUFFIXES)}) as MODEL, got "
                        f"{args.model or 'none'}")
    spec = read_io(args.io)
    if args.plot and (args.fs or spec.fs) is None:
        raise UserError("--plot draws the discrete plant: give a sample rate (--fs HZ or "
                        f"[plant] fs in {args.io})")
    loaded = deck_structure(Path(args.model), args.conventions)
    sc, sd, modes, n = io_plant(loaded.model, spec, n_modes=args.modes, damping=args.damping,
                                fs=args.fs, autospc=loaded.autospc)
    main = sd if sd is not None else sc
    save_model(out, main, continuous=sc if sd is not None else None,
               extra={"mode_frequencies_hz": np.asarray(modes.frequencies_hz[:n])})
    if args.plot:
        from trussid.plots import plant_bode_figure, save_figure

        save_figure(plant_bode_figure(
            sd, f"Plant of {Path(args.model).name} with {Path(args.io).name}"), args.plot, dpi=120)
    f = np.asarray(modes.frequencies_hz[:n])
    poles = control.poles(main)
    stable = bool(np.all(np.abs(poles) < 1) if sd is not None else np.all(np.real(poles) < 0))
    inputs, outputs = list(main.input_labels), list(main.output_labels)
    fs = args.fs or spec.fs
    damping = args.damping if args.damping is not None else (spec.damping or 0.02)
    if args.json:
        print(dumps({"model": str(args.model), "io": str(args.io), "out": str(out),
                     "inputs": inputs, "outputs": outputs, "states": int(main.nstates),
                     "sample_rate_hz": fs, "modes_kept": n, "mode_frequencies_hz": f.tolist(),
                     "damping": damping, "stable": stable,
                     "conventions": loaded.info.conventions, "notes": loaded.notes}), end="")
        return 0
    rate = (f"ZOH at {fs:g} Hz" if sd is not None
            else "continuous only (give --fs or [plant] fs for a discrete plant)")
    print(f"plant of {args.model} with {args.io}: {len(inputs)} input(s) "
          f"({', '.join(inputs)}), {len(outputs)} output(s) "
          f"({', '.join(outputs)}), {int(main.nstates)} states, {rate}")
    print(f"modes kept: {n} ({f[0]:.4g} to {f[-1]:.4g} Hz), damping {damping:g}; "
          f"units: the deck's")
    for note in loaded.notes:
        print(note)
    print(f"wrote {out}" + (f" and {args.plot}" if args.plot else ""))
    return 0
