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
``udf``, ``base``, ``accelerometers``, ``electrics``, ``filters``, ``daq``, ``damping``); the
lab's sections (``accelerometers``, ``electrics``, ``filters``, ``daq``) are those of
:class:`trussid.geometry.lab.LabSpec`, the one home of the lab's numbers, and
:attr:`Testbed.lab` hands them down as one value. All
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
from dataclasses import dataclass, field
from typing import Any, ClassVar

from trussid.geometry._params import Section, fail, param
from trussid.geometry.errors import ParameterError
from trussid.geometry.lab import (G0, AccelerometerParams, DaqParams, ElectricsParams,
                                  FilterParams, LabSpec, LAB_SECTIONS)

#: One inch [m] (exact).
INCH = 0.0254
#: One pound mass [kg] (exact).
POUND = 0.45359237
#: Number of struts; fixed by the topology (3 bipods of 2 struts).
N_STRUTS = 6
#: Accepted values of ``base.support``.
BASE_SUPPORTS = ("suspended", "clamped")


@dataclass(frozen=True)
class StrutParams(Section):
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

    length: float = param(36 * INCH, "m", "strut length between end points (thesis: 36 in)")
    outer_diameter: float = param(0.535 * INCH, "m", "tube outside diameter (calibrated: 0.535 in)")
    walls: tuple = param(
        tuple(t * INCH for t in (0.028, 0.035, 0.042, 0.049, 0.058, 0.065)), "m",
        "wall thickness of struts 0..5 (suggested: 0.028..0.065 in)", check="walls", kind=tuple,
    )
    youngs_modulus: float = param(68.9e9, "Pa", "tube Young's modulus (aluminium 6061-T6)")
    poisson_ratio: float = param(0.33, "-", "tube Poisson's ratio (aluminium 6061-T6)", check="poisson")
    density: float = param(2700.0, "kg/m^3", "tube density (aluminium 6061-T6)")
    base_rotational_stiffness: float = param(
        1000.0, "N m/rad", "rotational spring at the base end, inf = clamped (calibrated: 1000)",
        check="positive_or_inf")
    top_rotational_stiffness: float = param(
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
class AdapterParams(Section):
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

    side: float = param(1.0 * INCH, "m", "side of the square block (suggested: 1.0 in)")
    length: float = param(2.0 * INCH, "m", "block length along the strut (calibrated: 2.0 in)")
    youngs_modulus: float = param(68.9e9, "Pa", "block Young's modulus (aluminium 6061-T6)")
    poisson_ratio: float = param(0.33, "-", "block Poisson's ratio (aluminium 6061-T6)", check="poisson")
    density: float = param(2700.0, "kg/m^3", "block density (aluminium 6061-T6)")


@dataclass(frozen=True)
class PztParams(Section):
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

    width: float = param(1.00 * INCH, "m", "wafer width (thesis: 1.00 in)")
    length: float = param(2.00 * INCH, "m", "wafer length along the strut (thesis: 2.00 in)")
    thickness: float = param(0.020 * INCH, "m", "wafer thickness (thesis: 0.020 in)")
    d31: float = param(-171e-12, "m/V", "piezoelectric constant d31 (PZT-5A)", check="real")
    youngs_modulus: float = param(61e9, "Pa", "short-circuit Young's modulus 1/s11E (PZT-5A)")
    density: float = param(7750.0, "kg/m^3", "density (PZT-5A)")
    relative_permittivity: float = param(1700.0, "-", "relative permittivity eps33T/eps0 (PZT-5A)")
    wafers_per_strut: int = param(2, "-", "wafers per strut on opposite adapter faces (thesis: 2)",
                               check="count", kind=int)

    def _check_section(self) -> None:
        if self.wafers_per_strut not in (2, 4):
            fail("pzt.wafers_per_strut", f"{self.wafers_per_strut} must be 2 or 4 (opposite pairs of faces)")

    @property
    def wafer_capacitance(self) -> float:
        """Parallel-plate capacitance of one wafer, eps0 eps_r W L / T [F]."""
        eps0 = 8.8541878128e-12
        return eps0 * self.relative_permittivity * self.width * self.length / self.thickness


@dataclass(frozen=True)
class UdfParams(Section):
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

    side: float = param(12 * INCH, "m", "side of the triangle of top vertices (thesis: 12 in)")
    height: float = param(6 * INCH, "m", "prism height between triangle centrelines (suggested: 6 in)")
    member_size: float = param(1.2 * INCH, "m", "side of the square steel bars (suggested: 1.2 in)")
    mass: float = param(35 * POUND, "kg", "total UDF mass (thesis: 35 lb)")
    density: float = param(7850.0, "kg/m^3", "steel density of the solid before scaling to mass")
    youngs_modulus: float = param(200e9, "Pa", "steel Young's modulus")
    poisson_ratio: float = param(0.29, "-", "steel Poisson's ratio", check="poisson")

    def _check_section(self) -> None:
        if self.member_size >= self.side / 2:
            fail("udf.member_size", f"{self.member_size:.4g} m must be less than half the side "
                  f"({self.side / 2:.4g} m)")


@dataclass(frozen=True)
class BaseParams(Section):
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

    diameter: float = param(30 * INCH, "m", "plate diameter (thesis: 30 in)")
    mass: float = param(105 * POUND, "kg", "plate mass (thesis: 105 lb)")
    density: float = param(2700.0, "kg/m^3", "plate density (aluminium); fixes the thickness")
    support: str = param("suspended", "-", "'suspended' on bungees (thesis) or 'clamped'",
                      check="choice:" + "|".join(BASE_SUPPORTS), kind=str)
    bungee_count: int = param(3, "-", "number of bungee cords (suggested: 3)", check="count", kind=int)
    bungee_radius: float = param(13.5 * INCH, "m", "radius of bungee attachments (suggested: 13.5 in)")
    bungee_vertical_stiffness: float = param(900.0, "N/m", "axial stiffness of each cord (suggested)")
    bungee_lateral_stiffness: float = param(250.0, "N/m", "lateral stiffness of each cord (suggested)")

    @property
    def thickness(self) -> float:
        """Plate thickness implied by mass, density and diameter [m]."""
        return self.mass / (self.density * math.pi * (0.5 * self.diameter) ** 2)

    def _check_section(self) -> None:
        if self.bungee_radius >= 0.5 * self.diameter:
            fail("base.bungee_radius", f"{self.bungee_radius:.4g} m must be inside the plate "
                  f"(radius {0.5 * self.diameter:.4g} m)")


@dataclass(frozen=True)
class DampingParams(Section):
    """Structural damping.

    Attributes
    ----------
    modal_ratio : float
        Modal damping ratio of every mode [-]. Thesis: about 0.25 % of critical.
    """

    section: ClassVar[str] = "damping"

    modal_ratio: float = param(0.0025, "-", "modal damping ratio (thesis: 0.25 %)", check="fraction")


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
                fail(name, f"must be a {cls.__name__}, got {type(getattr(self, name)).__name__}")
        s, a, p, b = self.struts, self.adapter, self.pzt, self.base
        if len(s.walls) != N_STRUTS:
            fail("struts.walls", f"must hold {N_STRUTS} wall thicknesses (one per strut), got {len(s.walls)}")
        r = s.outer_radius
        for i, t in enumerate(s.walls):
            if not (0.0 < t < r):
                raise ParameterError(f"strut {i} wall thickness {t:.4f} m must be in (0, {r:.5f} m) "
                                     f"(struts.walls[{i}])")
        run = self.strut_run
        if s.length <= run:
            fail("struts.length", f"{s.length:.4g} m must exceed the strut's horizontal run "
                  f"{run:.4g} m (set by udf.side)")
        if a.length >= s.length:
            fail("adapter.length", f"{a.length:.4g} m must be shorter than the strut ({s.length:.4g} m)")
        if a.side <= s.outer_diameter:
            fail("adapter.side", f"{a.side:.4g} m must exceed the tube outside diameter "
                  f"({s.outer_diameter:.4g} m) that it is bored to")
        if p.width > a.side:
            fail("pzt.width", f"{p.width:.4g} m must fit on the adapter face ({a.side:.4g} m)")
        if p.length > a.length:
            fail("pzt.length", f"{p.length:.4g} m must fit on the adapter ({a.length:.4g} m)")
        if self.base_radius >= 0.5 * b.diameter:
            fail("base.diameter", f"{b.diameter:.4g} m must exceed the base-point circle "
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

    # -- the lab ----------------------------------------------------------------------------
    @property
    def lab(self) -> LabSpec:
        """The lab around the testbed (its sensor, electronics, filter and converter
        sections) as one :class:`~trussid.geometry.lab.LabSpec`."""
        return LabSpec(**{name: getattr(self, name) for name in LAB_SECTIONS})

    def with_lab(self, lab: LabSpec) -> "Testbed":
        """A copy in the lab ``lab`` (its four sections replace the testbed's).

        Examples
        --------
        >>> from trussid.geometry.lab import LabSpec
        >>> lab = LabSpec.from_dict({"daq": {"sample_rate": 3200.0, "bits": 16}})
        >>> Testbed().with_lab(lab).daq.sample_rate
        3200.0
        """
        if not isinstance(lab, LabSpec):
            raise ParameterError(f"lab must be a LabSpec, got {type(lab).__name__}")
        return dataclasses.replace(self, **{name: getattr(lab, name) for name in LAB_SECTIONS})
