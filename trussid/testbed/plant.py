"""The testbed's control-ready plant: actuator channels in (D/A volts), accelerometers out.

Composes :mod:`trussid.testbed.model` (model and map), :mod:`trussid.fem.actuators` (PZT induced strain),
:mod:`trussid.fem.sensors`, :mod:`trussid.fem.plant` (modal superposition) and :mod:`trussid.testbed.chain` (filters,
amplifier, converters, ZOH discretisation), with every number taken from the
:class:`trussid.geometry.spec.Testbed` parameters.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from trussid.fem.actuators import Wafer, strain_actuator_loads
from trussid.fem.assembly import assemble
from trussid.fem.errors import ModelError
from trussid.fem.plant import modal_plant, residual_flexibility
from trussid.fem.sensors import Sensor
from trussid.geometry.lab import LabSpec
from trussid.geometry.spec import Testbed
from trussid.testbed.chain import LabChain, lab_plant
from trussid.testbed.model import TestbedModel, build_testbed
from trussid.testbed.walls import solve_testbed_modes

@dataclass
class TestbedPlant:
    """A testbed plant and what it was made from.

    Attributes
    ----------
    continuous, discrete : control.StateSpace
        Command volts (per channel, at the D/A) to accelerometer volts, with the lab chain;
        the discrete one at the sample rate (ZOH).
    structure : control.StateSpace
        PZT volts to accelerometer volts (the structure alone, continuous).
    modes : fem.modal.Modes
        The modes kept.
    loads : (6 n_nodes, n_channels) float
        Nodal loads per PZT volt of each channel [N/V, N m/V].
    capacitance : float
        Capacitance of one actuator from the wafer data [F] (wafers in parallel).
    chain : LabChain
    tbm : TestbedModel
    lab : LabSpec
        The lab the plant was made with, at the plant's sample rate: the converters of its
        records and closed loops (:func:`trussid.campaign.control.LoopSettings.for_lab`).
    """

    continuous: control.StateSpace
    discrete: control.StateSpace
    structure: control.StateSpace
    modes: object
    loads: np.ndarray
    capacitance: float
    chain: LabChain
    tbm: TestbedModel
    lab: LabSpec


def wafer_of(tb) -> Wafer:
    """The PZT wafer described by the testbed parameters."""
    p = tb.pzt
    return Wafer(width=p.width, length=p.length, thickness=p.thickness, youngs_modulus=p.youngs_modulus,
                 d31=p.d31, relative_permittivity=p.relative_permittivity)


def lab_chain_of(tb, sample_rate: float | None = None) -> LabChain:
    """The electronics described by the testbed's lab (:attr:`Testbed.lab`)."""
    return LabChain.from_lab(tb.lab, sample_rate)


def channel_loads(tbm: TestbedModel, channels=None, arrangement: str = "extension") -> np.ndarray:
    """Nodal loads per volt of each actuator channel.

    Parameters
    ----------
    tbm : TestbedModel
    channels : sequence of sequences of int, optional
        Struts driven by each channel (default: the testbed's, the two struts that share
        each top vertex), all driven in unison.
    arrangement : {"extension", "bending"}
        Wafers in phase (the testbed's) or in anti-phase.

    Returns
    -------
    (6 n_nodes, n_channels) float
    """
    tb, mp = tbm.testbed, tbm.map
    channels = mp.channel_struts if channels is None else channels
    wafer = wafer_of(tb)
    offset = 0.5 * tb.adapter.side + 0.5 * tb.pzt.thickness
    n_struts = mp.wafer_elements.shape[0]
    cols = []
    for c, struts in enumerate(channels):
        f = 0.0
        for s in np.atleast_1d(struts):
            if not 0 <= int(s) < n_struts:
                raise ModelError(f"actuator channel {c + 1}: strut {s} does not exist (struts are 0..{n_struts - 1})")
            elements = mp.wafer_elements[int(s)]
            elements = elements[elements >= 0]
            if elements.size == 0:
                raise ModelError(f"actuator channel {c + 1}: strut {s} has no adapter with PZT wafers")
            f = f + strain_actuator_loads(tbm.model, elements, wafer, offset, face_axis="y",
                                          arrangement=arrangement, n_wafers=tb.pzt.wafers_per_strut)
        cols.append(f)
    return np.column_stack(cols)


def accelerometers(tbm: TestbedModel, quantity: str = "acceleration") -> list[Sensor]:
    """The testbed's sensors (accelerometers at the UDF corners, by default vertical).

    Acceleration outputs are in volts at the A/D input: accelerometer sensitivity times the
    signal conditioner's gain (``tb.accelerometers.conditioning_gain``).
    """
    tb, mp = tbm.testbed, tbm.map
    sens = tb.accelerometers.sensitivity * tb.accelerometers.conditioning_gain
    if quantity != "acceleration":
        sens = 1.0  # displacement/velocity outputs for analysis are in SI units
    return [Sensor(int(n), tuple(d), quantity, sens, name=f"acc{k + 1}")
            for k, (n, d) in enumerate(zip(mp.accelerometer_nodes, mp.accelerometer_directions))]


#: Names of the six axes of a wrench (force then moment, global axes).
WRENCH_AXES = ("fx", "fy", "fz", "mx", "my", "mz")


def node_load(tbm: TestbedModel, node: int, axis: str) -> np.ndarray:
    """Nodal load vector of a unit force [N] or moment [N m] at ``node`` along ``axis``
    (one of ``fx fy fz mx my mz``, global axes), for :func:`testbed_plant`'s disturbances."""
    if axis not in WRENCH_AXES:
        raise ModelError(f"load axis must be one of {', '.join(WRENCH_AXES)}, got {axis!r}")
    ids = np.asarray(tbm.model.node_ids)
    hit = np.flatnonzero(ids == int(node))
    if hit.size == 0:
        raise ModelError(f"disturbance load: unknown node {node}")
    f = np.zeros(6 * ids.size)
    f[6 * int(hit[0]) + WRENCH_AXES.index(axis)] = 1.0
    return f


def udf_wrench(tbm: TestbedModel, axes=WRENCH_AXES) -> dict:
    """Disturbances ``udf_<axis>``: a unit force or moment on the UDF at its centre of
    gravity (the master node of its rigid body)."""
    return {f"udf_{a}": node_load(tbm, tbm.map.udf_master, a) for a in axes}


def udf_motion(tbm: TestbedModel, quantity: str = "acceleration") -> list[Sensor]:
    """Performance outputs ``udf_<x|y|z>``: the UDF's centre of gravity along the global
    axes [SI units: m, m/s or m/s^2]."""
    return [Sensor(int(tbm.map.udf_master), tuple(d), quantity, 1.0, name=f"udf_{a}")
            for a, d in zip("xyz", np.eye(3))]


def strut_sensors(tbm: TestbedModel, quantity: str = "acceleration",
                  sensitivity: float = 1.0) -> list[Sensor]:
    """One lateral sensor per strut, at the strut node nearest mid-span, along the strut's
    local ``y`` (horizontal, normal to its bipod plane: the plane the anti-phase wafers on
    the ``+-y`` faces bend). Massless (a non-contact probe, or an accelerometer light
    enough to neglect): the model is unchanged. Output names ``strut0`` ... ``strut5``."""
    mp = tbm.map
    mid = int(np.argmin(np.abs(mp.strut_s - 0.5 * mp.strut_s[-1])))
    return [Sensor(int(mp.strut_nodes[i, mid]), tuple(mp.strut_frames[i, 1]), quantity, sensitivity,
                   name=f"strut{i}") for i in range(mp.strut_nodes.shape[0])]


def testbed_plant(design: Testbed | TestbedModel | None = None, *, n_modes: int | None = None,
                  damping=None, sample_rate: float | None = None,
                  quantity: str = "acceleration", chain: LabChain | None = None,
                  static_correction: bool = False,
                  arrangement: str = "extension", sensors: str = "udf",
                  disturbances: dict | None = None, performance: list[Sensor] | None = None
                  ) -> TestbedPlant:
    """Build the testbed plant.

    Parameters
    ----------
    design : Testbed or TestbedModel, optional
        The testbed's parameters, or its FE model already built
        (:func:`trussid.testbed.model.build_testbed`); default: the default testbed. The
        lab chain comes from its lab (``design.lab``, or ``design.testbed.lab``).
    n_modes : int, optional
        Modes kept; default all below the Nyquist frequency.
    damping : float or sequence, optional
        Modal damping ratio(s) [-]; default ``tb.damping.modal_ratio``.
    sample_rate : float, optional
        [Hz]; default ``tb.daq.sample_rate``.
    quantity : {"acceleration", "velocity", "displacement"}
        What the sensors measure (the lab's are accelerometers).
    chain : LabChain, optional
        Electronics; default from ``tb``.
    static_correction : bool
        Add the truncated modes' static displacement (displacement outputs; clamped base).
    arrangement : {"extension", "bending"}
        ``"extension"``: the lab's three channels, each driving the two struts that share a
        top vertex in extension (inputs ``ch1..ch3``). ``"bending"``: the experiment used
        for model updating, all six struts' wafer pairs in anti-phase from one channel
        (input ``bend``), which makes the strut bending modes strong.
    sensors : {"udf", "struts"}
        ``"udf"``: the lab's accelerometers at the UDF vertices; ``"struts"``: one lateral
        sensor per strut (:func:`strut_sensors`), whose shapes say which strut moves.
    disturbances : dict of str -> (6 n_nodes,) float, optional
        Extra named inputs after the actuator channels: nodal loads per unit disturbance
        (:func:`node_load`, :func:`udf_wrench`). They act on the structure directly, not
        through the electronics.
    performance : list of fem.sensors.Sensor, optional
        Extra named outputs after the accelerometers (e.g. :func:`udf_motion`).

    Returns
    -------
    TestbedPlant

    Examples
    --------
    The default testbed at the lab's 1600 Hz: three actuator channels to three accelerometers,
    the six suspension modes below 1 Hz, then the first strut modes near 50 Hz:

    >>> import numpy as np
    >>> from trussid.testbed.plant import testbed_plant
    >>> plant = testbed_plant()
    >>> G = plant.discrete
    >>> G.input_labels, G.output_labels, G.dt
    (['ch1', 'ch2', 'ch3'], ['acc1', 'acc2', 'acc3'], 0.000625)
    >>> print(np.round(plant.modes.frequencies_hz[6:9], 1))
    [50.4 50.5 53. ]
    """
    if arrangement not in ("extension", "bending"):
        raise ModelError(f"arrangement must be 'extension' or 'bending', got {arrangement!r}")
    if sensors not in ("udf", "struts"):
        raise ModelError(f"sensors must be 'udf' or 'struts', got {sensors!r}")
    if isinstance(design, TestbedModel):
        tbm = design
    elif design is None or isinstance(design, Testbed):
        tbm = build_testbed(design)
    else:
        raise ModelError(f"testbed_plant needs a Testbed or a TestbedModel, got "
                         f"{type(design).__name__}")
    tb = tbm.testbed
    chain = chain or lab_chain_of(tb, sample_rate)
    system = assemble(tbm.model)
    if n_modes is None:
        modes = solve_testbed_modes(tbm, system=system, max_frequency_hz=0.5 * chain.sample_rate)
        if len(modes.omega) == 0:
            raise ModelError(f"no mode lies below the Nyquist frequency {0.5 * chain.sample_rate:g} Hz")
    else:
        if int(n_modes) < 1:
            raise ModelError(f"n_modes must be >= 1, got {n_modes}")
        modes = solve_testbed_modes(tbm, n_modes=int(n_modes), system=system)
    keep = len(modes.omega)
    if arrangement == "bending":
        F = channel_loads(tbm, channels=[list(range(tbm.map.strut_nodes.shape[0]))],
                          arrangement="bending")
        names = ["bend"]
    else:
        F = channel_loads(tbm)
        names = [f"ch{k + 1}" for k in range(F.shape[1])]
    out = accelerometers(tbm, quantity) if sensors == "udf" else strut_sensors(tbm, quantity)
    zeta = tb.damping.modal_ratio if damping is None else damping
    if static_correction:
        cols = [F] + [np.asarray(v, dtype=float).reshape(-1, 1) for v in (disturbances or {}).values()]
        resid = residual_flexibility(system, modes, np.hstack(cols), keep)
    else:
        resid = None
    structure = modal_plant(modes, F, out, zeta, n_modes=keep, residual_flexibility=resid,
                            input_names=names, disturbances=disturbances, performance=performance)
    cont, disc = lab_plant(structure, chain, max_mode_hz=float(modes.frequencies_hz[keep - 1]),
                           n_commands=F.shape[1])
    wafer = wafer_of(tb)
    return TestbedPlant(continuous=cont, discrete=disc, structure=structure,
                        modes=modes, loads=F,
                        capacitance=tb.pzt.wafers_per_strut * wafer.capacitance, chain=chain, tbm=tbm,
                        lab=tb.lab.at_rate(chain.sample_rate))


def plant_summary(plant: TestbedPlant) -> dict:
    """Poles (frequency [Hz], damping), channel peak gains [V/V] and electrical facts.

    Poles of the continuous plant, one per complex pair, from :func:`control.damp`, sorted
    by frequency; peak gains of the discrete plant over 1 Hz to Nyquist.
    """
    wn, zeta, poles = control.damp(plant.continuous, doprint=False)
    keep = np.imag(poles) >= 0
    order = np.argsort(wn[keep], kind="stable")
    wn, zeta = wn[keep][order], zeta[keep][order]
    fs = plant.chain.sample_rate
    f = np.linspace(1.0, 0.5 * fs, 4000)
    H = plant.discrete(np.exp(2j * np.pi * f / fs))  # (p, m, nf)
    return {
        "inputs": list(plant.discrete.input_labels),
        "outputs": list(plant.discrete.output_labels),
        "states": int(plant.discrete.nstates),
        "sample_rate_hz": fs,
        "modes_kept": len(plant.modes.frequencies_hz),
        "mode_frequencies_hz": [float(x) for x in plant.modes.frequencies_hz],
        "poles": [{"frequency_hz": float(w / (2 * np.pi)), "damping": float(z)}
                  for w, z in zip(wn, zeta)],
        "peak_gain_v_per_v": np.abs(H).max(axis=2).tolist(),
        "actuator_capacitance_f": plant.capacitance,
        "actuator_capacitance_thesis_f": plant.tbm.testbed.electrics.actuator_capacitance,
        "strictly_proper": bool(np.all(plant.discrete.D == 0)),
        "stable": bool(np.all(np.abs(control.poles(plant.discrete)) < 1)),
    }
