"""The testbed parameter set: every number of the reference truss, named, in SI.

The reference structure is the piezo-actuated 3-D truss of Vallone (1997), "System
identification and control of a 3D truss structure using PLID and LQG" (the thesis, not distributed),
described in ``docs/testbed.md``. The thesis is in inches and pounds; every default
here is converted to SI (1 in = 0.0254 m, 1 lb = 0.45359237 kg) and tagged with its source:

- **thesis**: stated in the thesis text (section and figure given);
- **reconstructed**: follows from the thesis's statements by geometry (testbed.md);
- **suggested**: an unknown (NASTRAN deck and drawings are missing), given a documented
  starting value;
- **calibrated**: an unknown whose default was chosen so that the FE model
  (:mod:`trussid.testbed.model`) reproduces the thesis's measured bands (README, "Testbed
  calibration"): tube outside diameter, adapter length, strut-end rotational stiffness.

A :class:`Testbed` is a frozen dataclass of frozen sections (``struts``, ``adapter``, ``pzt``,
``udf``, ``base``, ``accelerometers``, ``electrics``, ``filters``, ``daq``, ``damping``). All
sections validate on construction and raise :class:`trussid.geometry.errors.ParameterError` naming
the parameter as ``section.field``. Use :meth:`Testbed.replace` (or
:func:`dataclasses.replace`) to change parameters and :meth:`Testbed.with_walls` to vary the
six wall thicknesses cheaply in design sweeps.

Strut numbering (shared with :mod:`trussid.geometry.layout`): struts are 0..5; struts ``2k`` and
``2k + 1`` meet at top vertex ``k`` and form actuator channel ``k``; ``struts.walls[i]`` is
the wall of strut ``i``.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass, field
from typing import Any, ClassVar

from trussid.geometry.errors import ParameterError

#: One inch [m] (exact).
INCH = 0.0254
#: One pound mass [kg] (exact).
POUND = 0.45359237
#: Standard gravity [m/s^2] (exact), to convert accelerometer sensitivities given per g.
G0 = 9.80665
#: Number of struts; fixed by the topology (3 bipods of 2 struts).
N_STRUTS = 6
#: Accepted values of ``base.support``.
BASE_SUPPORTS = ("suspended", "clamped")


def _p(default: Any, unit: str, doc: str, check: str = "positive", kind: type = float):
    """A parameter field: its unit, one-line documentation, validity check and type.

    ``check`` is one of ``positive`` (finite, > 0), ``positive_or_inf`` (> 0, inf allowed),
    ``real`` (finite), ``fraction`` (in [0, 1)), ``poisson`` (in (-1, 0.5)), ``count``
    (integer >= 1), ``choice:<a>|<b>`` or ``walls`` (validated by :class:`Testbed`).
    """
    return field(default=default, metadata={"unit": unit, "doc": doc, "check": check, "kind": kind})


def _fail(path: str, message: str) -> None:
    raise ParameterError(f"{path} {message}")


def _check_value(path: str, value: Any, kind: type, check: str) -> Any:
    """Validate one parameter value and return it normalised (ints to float, lists to tuples)."""
    if kind is float:
        if value is None and check == "positive_or_inf":
            value = math.inf  # None reads naturally as "no spring": a rigid (clamped) end
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            _fail(path, f"must be a number, got {type(value).__name__} {value!r}")
        value = float(value)
        if math.isnan(value):
            _fail(path, "must be a number, got NaN")
        if check == "positive" and not (math.isfinite(value) and value > 0):
            _fail(path, f"{value!r} must be positive and finite")
        elif check == "positive_or_inf" and not value > 0:
            _fail(path, f"{value!r} must be positive (inf means rigid)")
        elif check == "real" and not math.isfinite(value):
            _fail(path, f"{value!r} must be finite")
        elif check == "fraction" and not (0.0 <= value < 1.0):
            _fail(path, f"{value!r} must be in [0, 1)")
        elif check == "poisson" and not (-1.0 < value < 0.5):
            _fail(path, f"{value!r} must be in (-1, 0.5)")
    elif kind is int:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            _fail(path, f"must be an integer, got {type(value).__name__} {value!r}")
        value = int(value)
        if check == "count" and value < 1:
            _fail(path, f"{value} must be at least 1")
    elif kind is str:
        if not isinstance(value, str):
            _fail(path, f"must be a string, got {type(value).__name__} {value!r}")
        if check.startswith("choice:"):
            choices = check[len("choice:"):].split("|")
            if value not in choices:
                _fail(path, f"{value!r} must be one of {', '.join(map(repr, choices))}")
    elif kind is tuple:
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__"):
            _fail(path, f"must be a list of numbers, got {type(value).__name__} {value!r}")
        items = []
        for i, item in enumerate(value):
            if isinstance(item, bool) or not isinstance(item, numbers.Real):
                _fail(f"{path}[{i}]", f"must be a number, got {type(item).__name__} {item!r}")
            items.append(float(item))
        value = tuple(items)
    return value


class _Section:
    """Validation shared by all parameter sections (fields declared with :func:`_p`)."""

    section: ClassVar[str] = ""

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            meta = f.metadata
            value = _check_value(f"{self.section}.{f.name}", getattr(self, f.name), meta["kind"], meta["check"])
            object.__setattr__(self, f.name, value)  # frozen: normalise once at construction
        self._check_section()

    def _check_section(self) -> None:
        """Relations between fields of this section (override)."""


@dataclass(frozen=True)
class StrutParams(_Section):
    """The six aluminium tubes.

    Attributes
    ----------
    length : float
        Strut length between its end points [m]. Thesis: 3 ft = 36 in (sec. 2.2.1, Fig. 2.2.1-2).
    outer_diameter : float
        Tube outside diameter [m]. Calibrated: 0.535 in (suggested start 0.5 in), with the
        base flexures, to put the 12 first bending modes in 50-70 Hz and the 12 second
        bending modes in 200-250 Hz (README, "Testbed calibration").
    walls : tuple of 6 float
        Wall thickness of strut i [m]. Suggested: 0.028, 0.035, 0.042, 0.049, 0.058, 0.065 in
        (thesis: thinnest tubing available, each strut different to break the symmetry).
    youngs_modulus, poisson_ratio, density : float
        Tube material [Pa], [-], [kg/m^3]. Thesis: aluminium; suggested grade 6061-T6
        (68.9 GPa, 0.33, 2700 kg/m^3; ASM handbook values, as in ``trussid.fem.materials.ALUMINIUM``).
    base_rotational_stiffness, top_rotational_stiffness : float
        Rotational spring of each strut end in both bending directions [N m/rad]; ``inf`` (or
        ``None`` on construction) is a clamped end. Calibrated: base 1000 N m/rad (a flexure
        12-22 times the tubes' ``E I / L``), top clamped: with clamped ends the second
        bending modes of the thin walls and the first of the thick ones cannot both be in
        band (thesis Fig. 2.2.1-2 shows flexures; their stiffness is not given).
    """

    section: ClassVar[str] = "struts"

    length: float = _p(36 * INCH, "m", "strut length between end points (thesis: 36 in)")
    outer_diameter: float = _p(0.535 * INCH, "m", "tube outside diameter (calibrated: 0.535 in)")
    walls: tuple = _p(
        tuple(t * INCH for t in (0.028, 0.035, 0.042, 0.049, 0.058, 0.065)), "m",
        "wall thickness of struts 0..5 (suggested: 0.028..0.065 in)", check="walls", kind=tuple,
    )
    youngs_modulus: float = _p(68.9e9, "Pa", "tube Young's modulus (aluminium 6061-T6)")
    poisson_ratio: float = _p(0.33, "-", "tube Poisson's ratio (aluminium 6061-T6)", check="poisson")
    density: float = _p(2700.0, "kg/m^3", "tube density (aluminium 6061-T6)")
    base_rotational_stiffness: float = _p(
        1000.0, "N m/rad", "rotational spring at the base end, inf = clamped (calibrated: 1000)",
        check="positive_or_inf")
    top_rotational_stiffness: float = _p(
        math.inf, "N m/rad", "rotational spring at the top end, inf = clamped (calibrated: clamped)",
        check="positive_or_inf")

    @property
    def outer_radius(self) -> float:
        """Tube outside radius [m]."""
        return 0.5 * self.outer_diameter

    @property
    def inner_radii(self) -> tuple:
        """Inside radius of each strut [m]."""
        return tuple(self.outer_radius - t for t in self.walls)


@dataclass(frozen=True)
class AdapterParams(_Section):
    """The square actuator adapter block at each strut's mid-span, bored to the tube OD.

    Attributes
    ----------
    side : float
        Side of the square section [m]. Suggested: 1.0 in (carries the 1 in wide wafers).
    length : float
        Length along the strut [m]. Calibrated: 2.0 in, the wafers' length (suggested start
        2.5 in): the lightest adapter that carries the wafers gives the lowest ratio of
        third to first bending frequency.
    youngs_modulus, poisson_ratio, density : float
        Block material [Pa], [-], [kg/m^3]. Suggested: aluminium 6061-T6.

    The bore diameter is the strut's ``outer_diameter`` (thesis Fig. 2.2.1-3: epoxied to the
    tube), so it is not a separate parameter.
    """

    section: ClassVar[str] = "adapter"

    side: float = _p(1.0 * INCH, "m", "side of the square block (suggested: 1.0 in)")
    length: float = _p(2.0 * INCH, "m", "block length along the strut (calibrated: 2.0 in)")
    youngs_modulus: float = _p(68.9e9, "Pa", "block Young's modulus (aluminium 6061-T6)")
    poisson_ratio: float = _p(0.33, "-", "block Poisson's ratio (aluminium 6061-T6)", check="poisson")
    density: float = _p(2700.0, "kg/m^3", "block density (aluminium 6061-T6)")


@dataclass(frozen=True)
class PztParams(_Section):
    """The PZT strain-actuator wafers (thesis sec. 2.2.1 and appendix H2.3.2).

    Attributes
    ----------
    width, length, thickness : float
        Wafer size [m]. Thesis: 1.00 W x 2.00 L x 0.020 T in.
    d31 : float
        Transverse piezoelectric charge constant [m/V]. Suggested: PZT-5A, -171e-12 m/V.
    youngs_modulus : float
        Short-circuit modulus 1/s11E [Pa]. Suggested: PZT-5A, 61 GPa.
    density : float
        [kg/m^3]. Suggested: PZT-5A, 7750.
    relative_permittivity : float
        Constant-stress relative permittivity eps33T/eps0 [-]. Suggested: PZT-5A, 1700.
    wafers_per_strut : int
        Wafers bonded on opposite faces of each adapter [-]; 2 (thesis: "2 piezo-patches").
        Must be 2 or 4 (opposite pairs), so that equal drive gives no bending.

    Notes
    -----
    PZT-5A constants (d31 = -171 pm/V, s11E = 16.4 pm^2/N so E = 61 GPa, eps33T/eps0 = 1700,
    rho = 7750 kg/m^3) are those tabulated by Erturk & Inman, *Piezoelectric Energy
    Harvesting* (Wiley 2011), appendix E, table E.1. With them one wafer has a capacitance of
    eps0 * 1700 * W * L / T = 38 nF, two wafers in parallel 76 nF, against the 48 nF per
    actuator that the thesis reports (sec. 3.2); see :attr:`wafer_capacitance`.
    """

    section: ClassVar[str] = "pzt"

    width: float = _p(1.00 * INCH, "m", "wafer width (thesis: 1.00 in)")
    length: float = _p(2.00 * INCH, "m", "wafer length along the strut (thesis: 2.00 in)")
    thickness: float = _p(0.020 * INCH, "m", "wafer thickness (thesis: 0.020 in)")
    d31: float = _p(-171e-12, "m/V", "piezoelectric constant d31 (PZT-5A)", check="real")
    youngs_modulus: float = _p(61e9, "Pa", "short-circuit Young's modulus 1/s11E (PZT-5A)")
    density: float = _p(7750.0, "kg/m^3", "density (PZT-5A)")
    relative_permittivity: float = _p(1700.0, "-", "relative permittivity eps33T/eps0 (PZT-5A)")
    wafers_per_strut: int = _p(2, "-", "wafers per strut on opposite adapter faces (thesis: 2)",
                               check="count", kind=int)

    def _check_section(self) -> None:
        if self.wafers_per_strut not in (2, 4):
            _fail("pzt.wafers_per_strut", f"{self.wafers_per_strut} must be 2 or 4 (opposite pairs of faces)")

    @property
    def wafer_capacitance(self) -> float:
        """Parallel-plate capacitance of one wafer, eps0 eps_r W L / T [F]."""
        eps0 = 8.8541878128e-12
        return eps0 * self.relative_permittivity * self.width * self.length / self.thickness


@dataclass(frozen=True)
class UdfParams(_Section):
    """The upper delta frame (UDF): a steel triangular prism frame treated as a rigid body.

    Attributes
    ----------
    side : float
        Side of the equilateral triangle of top vertices [m]. Thesis: 12 in (sec. 2.2.1).
        It fixes the layout: the base-point circle radius is ``2 side / sqrt(3)``.
    height : float
        Height of the prism between the centrelines of its lower and upper triangles [m].
        Suggested: 6 in (keeps the testbed under the thesis's 4 ft).
    member_size : float
        Side of the square steel bars of the frame [m]. Suggested: 1.2 in, which gives a
        bare-steel frame of 35.09 lb; the solid is then scaled to exactly ``mass`` (a
        uniform density scale, see :func:`trussid.geometry.solids.udf_rigid_body`).
    mass : float
        Total mass [kg]. Thesis: 35 lb (Fig. 2.2.1-2).
    density : float
        Steel density of the solid before scaling [kg/m^3]. Suggested: 7850.
    youngs_modulus, poisson_ratio : float
        Steel [Pa], [-] (for a flexible UDF model; the thesis intends it rigid below 200 Hz).
    """

    section: ClassVar[str] = "udf"

    side: float = _p(12 * INCH, "m", "side of the triangle of top vertices (thesis: 12 in)")
    height: float = _p(6 * INCH, "m", "prism height between triangle centrelines (suggested: 6 in)")
    member_size: float = _p(1.2 * INCH, "m", "side of the square steel bars (suggested: 1.2 in)")
    mass: float = _p(35 * POUND, "kg", "total UDF mass (thesis: 35 lb)")
    density: float = _p(7850.0, "kg/m^3", "steel density of the solid before scaling to mass")
    youngs_modulus: float = _p(200e9, "Pa", "steel Young's modulus")
    poisson_ratio: float = _p(0.29, "-", "steel Poisson's ratio", check="poisson")

    def _check_section(self) -> None:
        if self.member_size >= self.side / 2:
            _fail("udf.member_size", f"{self.member_size:.4g} m must be less than half the side "
                  f"({self.side / 2:.4g} m)")


@dataclass(frozen=True)
class BaseParams(_Section):
    """The aluminium support plate and its bungee suspension.

    Attributes
    ----------
    diameter : float
        Plate diameter [m]. Thesis: 30 in (sec. 2.2.1).
    mass : float
        Plate mass [kg]. Thesis: 105 lb (Fig. 2.2.1-2).
    density : float
        Plate density [kg/m^3]; with ``mass`` and ``diameter`` it fixes the thickness
        (1.52 in by default). Thesis: aluminium; suggested 2700.
    support : str
        ``"suspended"`` (thesis: hangs from bungee cords) or ``"clamped"``.
    bungee_count : int
        Number of bungee cords, equally spaced [-]. Suggested: 3.
    bungee_radius : float
        Radius of the attachment points [m]. Suggested: 13.5 in (middle of the outer 3 in
        ring that the thesis reserves for the bungees).
    bungee_vertical_stiffness, bungee_lateral_stiffness : float
        Stiffness of each cord along and across its axis [N/m]. Suggested: 900 and 250 N/m,
        i.e. a vertical bounce near 1 Hz and a pendulum near 0.5 Hz for the ~68 kg testbed:
        suspension modes well below 5 Hz.
    """

    section: ClassVar[str] = "base"

    diameter: float = _p(30 * INCH, "m", "plate diameter (thesis: 30 in)")
    mass: float = _p(105 * POUND, "kg", "plate mass (thesis: 105 lb)")
    density: float = _p(2700.0, "kg/m^3", "plate density (aluminium); fixes the thickness")
    support: str = _p("suspended", "-", "'suspended' on bungees (thesis) or 'clamped'",
                      check="choice:" + "|".join(BASE_SUPPORTS), kind=str)
    bungee_count: int = _p(3, "-", "number of bungee cords (suggested: 3)", check="count", kind=int)
    bungee_radius: float = _p(13.5 * INCH, "m", "radius of bungee attachments (suggested: 13.5 in)")
    bungee_vertical_stiffness: float = _p(900.0, "N/m", "axial stiffness of each cord (suggested)")
    bungee_lateral_stiffness: float = _p(250.0, "N/m", "lateral stiffness of each cord (suggested)")

    @property
    def thickness(self) -> float:
        """Plate thickness implied by mass, density and diameter [m]."""
        return self.mass / (self.density * math.pi * (0.5 * self.diameter) ** 2)

    def _check_section(self) -> None:
        if self.bungee_radius >= 0.5 * self.diameter:
            _fail("base.bungee_radius", f"{self.bungee_radius:.4g} m must be inside the plate "
                  f"(radius {0.5 * self.diameter:.4g} m)")


@dataclass(frozen=True)
class AccelerometerParams(_Section):
    """The three vertical accelerometers at the UDF corners (thesis sec. 2.2).

    Attributes
    ----------
    mass : float
        Mass of each accelerometer [kg]. Suggested: 10 g.
    sensitivity : float
        [V/(m/s^2)]. Suggested: 100 mV/g = 0.1 / 9.80665.
    conditioning_gain : float
        Voltage gain of the signal conditioner (charge amplifier) between each
        accelerometer and the A/D [V/V]. Suggested: 2000. The thesis reached 46 dB one-step
        prediction with 12-bit +-10 V converters, so its sensor signals must have filled a
        good part of the A/D range; the bare 100 mV/g output of this structure is about
        1e-3 V RMS, under one 12-bit LSB (4.9 mV). 2000 was chosen on the demo's MIMO
        experiment (all three channels driven with independent 2.5 V RMS white noise,
        0-400 Hz, at the D/A): the conditioned outputs then have RMS of 0.17-0.30 of full
        scale (acc1 lowest, records of 8000-16000 samples) and the A/D clips rarely (9 of
        48000 samples in the identification record; ``trussid demo`` reports the counts).
        2500 put the MIMO record at 0.26-0.32 of full scale and clipped 1.4 % of one
        channel's samples: these lightly damped outputs reach 3-4 times their RMS. The
        plant's outputs are conditioned volts: sensitivity times this gain.
    """

    section: ClassVar[str] = "accelerometers"

    mass: float = _p(0.010, "kg", "mass of each accelerometer (suggested: 10 g)")
    sensitivity: float = _p(0.1 / G0, "V/(m/s^2)", "sensitivity (suggested: 100 mV/g)")
    conditioning_gain: float = _p(2000.0, "V/V", "signal-conditioner gain between accelerometer "
                                  "and A/D (suggested: 2000, fills about 1/4 of the 12-bit "
                                  "range in the demo)")


@dataclass(frozen=True)
class ElectricsParams(_Section):
    """Actuator electrics (thesis sec. 3.2).

    Attributes
    ----------
    actuator_capacitance : float
        Capacitance per actuator [F]. Thesis: 0.048 uF.
    amplifier_gain : float
        Power amplifier voltage gain [V/V]. Thesis: 10.
    max_pzt_voltage : float
        Largest safe voltage on the wafers [V]. Thesis: 100 V.
    dac_max_voltage : float
        D/A converter peak output [V]. Thesis: 10 V.
    """

    section: ClassVar[str] = "electrics"

    actuator_capacitance: float = _p(0.048e-6, "F", "capacitance per actuator (thesis: 0.048 uF)")
    amplifier_gain: float = _p(10.0, "V/V", "power amplifier gain (thesis: 10)")
    max_pzt_voltage: float = _p(100.0, "V", "maximum voltage on the PZT (thesis: 100 V)")
    dac_max_voltage: float = _p(10.0, "V", "D/A peak output (thesis: 10 V)")


@dataclass(frozen=True)
class FilterParams(_Section):
    """Command-path filters (thesis sec. 2.3): a Butterworth smoother, then a low-pass.

    Attributes
    ----------
    smoothing_order : int
        Butterworth order [-]. Thesis: 2 poles.
    smoothing_cutoff : float
        Butterworth cutoff [Hz]. Thesis: 1300 Hz.
    lowpass_order : int
        Low-pass order [-]. Thesis: 1 pole.
    lowpass_cutoff : float
        Low-pass cutoff [Hz]. Thesis: 120 Hz.
    """

    section: ClassVar[str] = "filters"

    smoothing_order: int = _p(2, "-", "Butterworth smoothing filter order (thesis: 2)", check="count", kind=int)
    smoothing_cutoff: float = _p(1300.0, "Hz", "Butterworth cutoff (thesis: 1300 Hz)")
    lowpass_order: int = _p(1, "-", "low-pass filter order (thesis: 1)", check="count", kind=int)
    lowpass_cutoff: float = _p(120.0, "Hz", "low-pass cutoff (thesis: 120 Hz)")


@dataclass(frozen=True)
class DaqParams(_Section):
    """Data acquisition (thesis sec. 2.3).

    Attributes
    ----------
    sample_rate : float
        [Hz]. Thesis: 1600 Hz.
    bits : int
        A/D and D/A resolution [-]. Thesis: 12 bit.
    full_scale : float
        Converter range is +-full_scale [V]. Thesis: 10 V.
    """

    section: ClassVar[str] = "daq"

    sample_rate: float = _p(1600.0, "Hz", "sample rate (thesis: 1600 Hz)")
    bits: int = _p(12, "-", "A/D and D/A resolution (thesis: 12 bit)", check="count", kind=int)
    full_scale: float = _p(10.0, "V", "converter range +-full_scale (thesis: 10 V)")


@dataclass(frozen=True)
class DampingParams(_Section):
    """Structural damping.

    Attributes
    ----------
    modal_ratio : float
        Modal damping ratio of every mode [-]. Thesis: about 0.25 % of critical.
    """

    section: ClassVar[str] = "damping"

    modal_ratio: float = _p(0.0025, "-", "modal damping ratio (thesis: 0.25 %)", check="fraction")


#: Section name -> section class, in file order.
SECTIONS: dict = {
    cls.section: cls
    for cls in (StrutParams, AdapterParams, PztParams, UdfParams, BaseParams, AccelerometerParams,
                ElectricsParams, FilterParams, DaqParams, DampingParams)
}


@dataclass(frozen=True)
class Testbed:
    """The complete parameter set of the reference testbed (SI units).

    Attributes
    ----------
    struts, adapter, pzt, udf, base, accelerometers, electrics, filters, daq, damping
        The sections; see each class for its parameters, units and sources.

    Raises
    ------
    ParameterError
        On construction, for any invalid parameter, naming it (``strut 3 wall thickness ...``,
        ``struts.length ...``).

    Notes
    -----
    Reconstructed geometry (testbed.md): base points on a circle of radius
    ``R_b = 2 udf.side / sqrt(3)`` (13.856 in), each top vertex above the midpoint of a chord
    of adjacent base points, so the horizontal run of each strut is ``R_b sin 60 deg`` (12 in)
    and the top vertices are at height ``sqrt(L^2 - run^2)`` (33.94 in) above the plate.
    """

    struts: StrutParams = field(default_factory=StrutParams)
    adapter: AdapterParams = field(default_factory=AdapterParams)
    pzt: PztParams = field(default_factory=PztParams)
    udf: UdfParams = field(default_factory=UdfParams)
    base: BaseParams = field(default_factory=BaseParams)
    accelerometers: AccelerometerParams = field(default_factory=AccelerometerParams)
    electrics: ElectricsParams = field(default_factory=ElectricsParams)
    filters: FilterParams = field(default_factory=FilterParams)
    daq: DaqParams = field(default_factory=DaqParams)
    damping: DampingParams = field(default_factory=DampingParams)

    def __post_init__(self) -> None:
        for name, cls in SECTIONS.items():
            if not isinstance(getattr(self, name), cls):
                _fail(name, f"must be a {cls.__name__}, got {type(getattr(self, name)).__name__}")
        s, a, p, b = self.struts, self.adapter, self.pzt, self.base
        if len(s.walls) != N_STRUTS:
            _fail("struts.walls", f"must hold {N_STRUTS} wall thicknesses (one per strut), got {len(s.walls)}")
        r = s.outer_radius
        for i, t in enumerate(s.walls):
            if not (0.0 < t < r):
                raise ParameterError(f"strut {i} wall thickness {t:.4f} m must be in (0, {r:.5f} m) "
                                     f"(struts.walls[{i}])")
        run = self.strut_run
        if s.length <= run:
            _fail("struts.length", f"{s.length:.4g} m must exceed the strut's horizontal run "
                  f"{run:.4g} m (set by udf.side)")
        if a.length >= s.length:
            _fail("adapter.length", f"{a.length:.4g} m must be shorter than the strut ({s.length:.4g} m)")
        if a.side <= s.outer_diameter:
            _fail("adapter.side", f"{a.side:.4g} m must exceed the tube outside diameter "
                  f"({s.outer_diameter:.4g} m) that it is bored to")
        if p.width > a.side:
            _fail("pzt.width", f"{p.width:.4g} m must fit on the adapter face ({a.side:.4g} m)")
        if p.length > a.length:
            _fail("pzt.length", f"{p.length:.4g} m must fit on the adapter ({a.length:.4g} m)")
        if self.base_radius >= 0.5 * b.diameter:
            _fail("base.diameter", f"{b.diameter:.4g} m must exceed the base-point circle "
                  f"(diameter {2 * self.base_radius:.4g} m)")

    # -- derived geometry -------------------------------------------------------------------
    @property
    def base_radius(self) -> float:
        """Radius R_b of the circle of base points, ``2 udf.side / sqrt(3)`` [m]."""
        return 2.0 * self.udf.side / math.sqrt(3.0)

    @property
    def strut_run(self) -> float:
        """Horizontal run of every strut, half the base-point chord ``R_b sin 60 deg`` [m]."""
        return self.base_radius * math.sin(math.radians(60.0))

    @property
    def strut_height(self) -> float:
        """Height of the top vertices above the plate's top face, ``sqrt(L^2 - run^2)`` [m]."""
        return math.sqrt(self.struts.length ** 2 - self.strut_run ** 2)

    # -- changing parameters ----------------------------------------------------------------
    def replace(self, **changes: Any) -> "Testbed":
        """A copy with whole sections replaced, or single parameters as ``section__field``.

        Examples
        --------
        >>> tb = Testbed().replace(struts__length=0.9, base__support="clamped")
        """
        sections: dict = {}
        fields: dict = {}
        for key, value in changes.items():
            if "__" in key:
                name, sub = key.split("__", 1)
                fields.setdefault(name, {})[sub] = value
            else:
                sections[key] = value
        for name in list(sections) + list(fields):
            if name not in SECTIONS:
                raise ParameterError(f"unknown testbed section {name!r}; valid: {', '.join(SECTIONS)}")
        for name, subs in fields.items():
            current = sections.get(name, getattr(self, name))
            valid = {f.name for f in dataclasses.fields(current)}
            for sub in subs:
                if sub not in valid:
                    raise ParameterError(f"unknown parameter {name}.{sub}; valid: {', '.join(sorted(valid))}")
            sections[name] = dataclasses.replace(current, **subs)
        return dataclasses.replace(self, **sections)

    def with_walls(self, walls) -> "Testbed":
        """A copy with the six strut wall thicknesses ``walls`` [m] (cheap: for design sweeps)."""
        return dataclasses.replace(self, struts=dataclasses.replace(self.struts, walls=walls))
