"""The campaign's structure: the default testbed or any NASTRAN deck with an IO file, its
lab, and the experiment derived from it.

``trussid demo`` runs one campaign (:mod:`trussid.campaign.demo`) on a
:class:`CampaignPlant`: the true discrete plant, its modes, and the lab numbers the
experiments need (sample rate, converters, sensor noise). The testbed's come from its
parameter file (:mod:`trussid.geometry.spec`); a deck's from the IO file
(:mod:`trussid.fem.iospec`: actuators, sensors, ``[plant]`` sample rate and damping) and
a LAB file (:func:`read_lab`).

A minimal lab reader lives here until the project's single lab specification lands (issue
22): a LAB file is TOML with one ``[lab]`` table::

    [lab]
    fs = 2000.0            # sample rate [Hz] (default: the IO file's [plant] fs, else 1000)
    bits = 12              # converter resolution (D/A and A/D)
    full_scale = 10.0      # converter range +- [command and output units]
    sensor_noise = 1e-3    # sensor noise RMS [output units], one number or one per sensor;
                           # default: 60 dB under each output in the all-channel record
    damping = 0.01         # modal damping ratio (default: the IO file's, else 0.02)

The commands and outputs of a deck's plant are in the IO file's units (N, V, m/s^2 ...):
the converters see those numbers as volts, as if each channel had a unit-gain amplifier or
conditioner (the IO file's ``gain`` and ``sensitivity`` set the real ones).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from trussid._util.errors import UserError
from trussid.fem.iospec import io_plant, read_io
from trussid.fem.modal import Modes
from trussid.fem.nastran import read_bdf
from trussid.testbed.plant import testbed_plant

#: Keys of a LAB file's [lab] table.
LAB_KEYS = {"fs", "bits", "full_scale", "sensor_noise", "damping"}
#: Sensor noise under each output's RMS in the all-channel record when the lab gives none.
DEFAULT_SNR_DB = 60.0


@dataclass(frozen=True)
class Lab:
    """The lab numbers a campaign needs.

    Attributes
    ----------
    fs : float
        Sample rate [Hz].
    bits : int
        Converter resolution.
    full_scale : float
        Converter range (+-) in command and output units [V].
    sensor_noise : float, tuple of float or None
        Sensor noise RMS in output units; None: :data:`DEFAULT_SNR_DB` under each output.
    damping : float
        Modal damping ratio of a deck's plant.
    source : str
        Where the numbers came from (for the report).
    """

    fs: float = 1000.0
    bits: int = 12
    full_scale: float = 10.0
    sensor_noise: object = None
    damping: float = 0.02
    source: str = "defaults"


def read_lab(path, io_spec=None) -> Lab:
    """A :class:`Lab` from a LAB file (module docstring), the IO file's ``[plant]`` table
    filling what it leaves out, then the defaults. ``path`` None: the IO file and defaults.
    Every mistake is a :class:`UserError` naming the file and key."""
    lab = Lab()
    src = []
    if io_spec is not None:
        if io_spec.fs is not None:
            lab = replace(lab, fs=float(io_spec.fs))
        if io_spec.damping is not None:
            lab = replace(lab, damping=float(io_spec.damping))
        src.append(f"{io_spec.source} [plant]")
    if path is not None:
        path = Path(path)
        try:
            table = tomllib.loads(path.read_text())
        except FileNotFoundError:
            raise UserError(f"--lab {path}: no such file") from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise UserError(f"{path}: not valid TOML: {exc}") from None
        extra = set(table) - {"lab"}
        if extra or "lab" not in table:
            raise UserError(f"{path}: a LAB file has one [lab] table"
                            + (f" (found {', '.join(sorted(extra))})" if extra else ""))
        t = table["lab"]
        unknown = set(t) - LAB_KEYS
        if unknown:
            raise UserError(f"{path}: [lab] unknown key '{sorted(unknown)[0]}' (allowed: "
                            f"{', '.join(sorted(LAB_KEYS))})")
        kw = {}
        for key in ("fs", "full_scale"):
            if key in t:
                kw[key] = _positive(t[key], f"{path}: [lab] {key}")
        if "bits" in t:
            b = t["bits"]
            if not (isinstance(b, int) and not isinstance(b, bool) and 2 <= b <= 32):
                raise UserError(f"{path}: [lab] bits must be a whole number in 2-32, got {b!r}")
            kw["bits"] = b
        if "damping" in t:
            d = t["damping"]
            if not (isinstance(d, (int, float)) and 0 <= d < 1):
                raise UserError(f"{path}: [lab] damping must be in [0, 1), got {d!r}")
            kw["damping"] = float(d)
        if "sensor_noise" in t:
            v = t["sensor_noise"]
            vals = v if isinstance(v, list) else [v]
            kw["sensor_noise"] = tuple(_positive(x, f"{path}: [lab] sensor_noise", zero=True)
                                       for x in vals)
        lab = replace(lab, **kw)
        src.append(str(path))
    return replace(lab, source=", ".join(src) or "defaults")


def _positive(x, where, zero=False) -> float:
    ok = isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
    if not ok or x < 0 or (x == 0 and not zero):
        raise UserError(f"{where} must be a {'non-negative' if zero else 'positive'} number, "
                        f"got {x!r}")
    return float(x)


@dataclass
class CampaignPlant:
    """The structure a campaign runs on.

    Attributes
    ----------
    discrete : control.StateSpace
        The true plant (commands to sensor outputs) at the lab's sample rate.
    modes : object
        Its modes (``frequencies_hz``).
    lab : Lab
    description : str
        One line for the report ("the default testbed", "deck truss.bdf with io.toml").
    testbed : trussid.geometry.spec.Testbed or None
        The testbed parameters (its perturbed truths, its report details), or None.
    tp : object
        The testbed plant (:class:`trussid.testbed.plant.TestbedPlant`) or None.
    """

    discrete: object
    modes: object
    lab: Lab
    description: str
    testbed: object = None
    tp: object = None


def testbed_campaign_plant(tb=None) -> CampaignPlant:
    """The default testbed (or ``tb``) at its lab's rate, converters and noise."""
    tp = testbed_plant(tb)
    t = tp.tbm.testbed
    lab = Lab(fs=1.0 / tp.discrete.dt, bits=t.daq.bits, full_scale=t.daq.full_scale,
              damping=t.damping.modal_ratio, source="the testbed's parameters")
    return CampaignPlant(tp.discrete, tp.modes, lab, "the default testbed", testbed=t, tp=tp)


def deck_campaign_plant(deck, io, lab_path=None, *, n_modes=None) -> CampaignPlant:
    """A NASTRAN deck's plant with the IO file's actuators and sensors, at the lab's rate.

    Every mode below the Nyquist frequency is kept (``n_modes`` to keep fewer).
    """
    model, info = read_bdf(deck)
    spec = read_io(io)
    lab = read_lab(lab_path, spec)
    _, sd, modes, n = io_plant(model, spec, n_modes=n_modes, damping=lab.damping, fs=lab.fs,
                               autospc=info.autospc)
    if n < len(modes.frequencies_hz):
        modes = replace_frequencies(modes, n)
    desc = f"deck {Path(deck).name} with {Path(io).name}"
    return CampaignPlant(sd, modes, lab, desc)


def replace_frequencies(modes, n):
    """``modes`` cut to the first ``n`` (only what the campaign reads)."""
    return Modes(modes.frequencies_hz[:n], modes.omega[:n], modes.shapes[:, :n],
                 modes.shapes_full[:, :n], modes.node_ids, modes.xyz, modes.n_dof, modes.method)
