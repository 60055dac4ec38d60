"""The finite-element model of the reference testbed (the builder).

:func:`build_testbed` turns a :class:`trussid.geometry.spec.Testbed` into a :class:`trussid.fem.Model`
plus a :class:`TestbedMap` that says which nodes, elements and springs are what (so the
plant can put PZT loads on the adapter elements and sensors on the accelerometer nodes, and
the renderer can attach solids to nodes).

Model (see ``docs/testbed.md``)
--------------------------------------
- **Struts**: 2-node frame elements along each strut (:mod:`trussid.geometry.layout` numbering and
  local axes: element local ``y`` is the strut's ``y``, horizontal and normal to its bipod
  plane). Grid points at both ends of the adapter; ``elements_per_segment`` elements on each
  bare tube segment; the adapter is one element, or three when the wafers are shorter than
  the block (block only / block + wafers / block only), so that the wafer-covered part has
  its own end nodes for the induced-strain loads.
- **Adapter section**: the tube, the bored block and the wafers act as one composite
  section (perfect bond, plane sections). The Model stores one ``E``, ``G`` per element, so
  the sums are mapped onto it with the tube's ``E_ref``, ``G_ref``::

      A   = sum(E_i A_i) / E_ref        Iy = sum(E_i Iy_i) / E_ref     Iz = sum(E_i Iz_i) / E_ref
      J   = sum(G_i J_i) / G_ref        (wafers: no torsional stiffness, W T^3/3 is negligible)
      rho = rho_tube                    nsm = sum(rho_i A_i) - rho A  (true mass per length)

  The element's torsional inertia ``rho (Iy + Iz)`` is then exact for the tube and an
  aluminium block; what the denser wafers add beyond it, ``sum rho_i Ip_i - rho (Iy + Iz)``
  (``Ip`` polar moment), is lumped as rotary inertia about the strut axis at the ends of
  the wafer elements (half each). (A single density cannot carry both: the wafers' mass
  sits farther out than their stiffness-weighted area.)

  Wafers on the ``+-y`` faces (and ``+-z`` when four) add their own second moments plus the
  parallel-axis terms ``A_w d^2`` with ``d = side / 2 + T / 2``. Bare tube elements use the
  tube's own properties, which the same formulas give. Every stiffness and mass property
  of a strut element is then *linear* in the tube's area ``A_t`` and second moment ``I_t``
  (``J_t = 2 I_t``), which :func:`wall_basis` exploits.
- **Strut ends**: clamped (``inf`` rotational stiffness), or flexures: the end node then
  follows its attachment in translation only (a rigid link of components 1-3) and is held in
  rotation by a spring in the strut's local frame: the given stiffness about local ``y`` and
  ``z`` (bending), and :data:`TORSION_RIGID_FACTOR` times ``G J / L`` about the
  axis (flexures are torsionally stiff; a penalty, since links are in global components;
  scaled on a solid rod of the tube's diameter so that it does not depend on the walls).
- **UDF**: one rigid body, master node at its centre of gravity, mass and inertia from
  :func:`trussid.geometry.solids.udf_rigid_body`; slaves: the strut top ends and the three
  accelerometer nodes, which carry the accelerometer masses as point masses.
- **Base**: ``"clamped"``: strut base ends supported. ``"suspended"``: the plate as a rigid
  body (:func:`trussid.geometry.solids.base_rigid_body`, master at its centre of gravity) whose
  bungee attachment nodes hang on grounded springs (vertical and lateral stiffness per
  cord, global axes).

Node and element numbering
--------------------------
Strut ``i`` (0..5) owns node and beam ids ``STRUT_ID_STRIDE (i + 1) + j`` (1000 (i + 1) +
j), ``j`` along the strut from its base end (``j = 0``) to its top end; each strut has its
own end nodes (coincident with its neighbour's at a base point or top vertex). UDF master
:data:`UDF_MASTER` (10), accelerometers :data:`ACCELEROMETER_NODES` (11, 12, 13); base
master :data:`BASE_MASTER` (20), bungee nodes from :data:`FIRST_BUNGEE_NODE` (21).
Springs: bungees from :data:`FIRST_BUNGEE_SPRING` (8000), top flexures
:data:`FIRST_TOP_FLEXURE_SPRING` + i (9100 + i), base flexures
:data:`FIRST_BASE_FLEXURE_SPRING` + i (9200 + i). Rigid bodies: :class:`Body` (1 UDF, 2 base,
3/4 translation links of top/base flexure ends). What each strut element is:
:class:`StrutPart`.

The wall sweeps on this model (:class:`WallBasis`, :func:`wall_modes`,
:func:`design_at_walls`) and its eigen solution (:func:`solve_testbed_modes`) are
:mod:`trussid.testbed.walls`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from enum import IntEnum

import numpy as np

from trussid.fem.errors import ModelError
from trussid.fem.model import Model
from trussid.fem.sections import Section
from trussid.geometry.layout import testbed_layout
from trussid.geometry.solids import base_rigid_body, udf_rigid_body
from trussid.geometry.spec import Testbed

#: Default number of frame elements on each bare tube segment (base-adapter, adapter-top).
#: Chosen by a mesh study (tests/fem/test_testbed.py): doubling it moves no frequency below
#: 400 Hz by more than 0.1 %.
ELEMENTS_PER_SEGMENT = 4
#: Wafers shorter than the adapter by less than this fraction of its length are taken to
#: cover it all (a lip of a few micrometres would be a needlessly stiff element).
MIN_LIP = 0.01
#: Torsional stiffness of a flexure, as a multiple of ``G J / L`` of a solid rod of the
#: tube's outside diameter (a wall-independent scale).
TORSION_RIGID_FACTOR = 1.0e3

#: The testbed's six struts (two per bipod, three bipods).
N_STRUTS = 6
#: Strut ``i`` owns node and beam ids ``STRUT_ID_STRIDE * (i + 1) + j``, ``j`` from its base
#: end: room for 999 nodes per strut, and ``id // STRUT_ID_STRIDE - 1`` is the strut.
STRUT_ID_STRIDE = 1000
#: Master node of the UDF rigid body (at its centre of gravity).
UDF_MASTER = 10
#: The three accelerometer nodes (slaves of the UDF), ``k`` above strut junction ``k``.
ACCELEROMETER_NODES = (11, 12, 13)
#: Master node of the suspended base plate's rigid body.
BASE_MASTER = 20
#: Bungee attachment nodes are ``FIRST_BUNGEE_NODE + j``, their springs ``FIRST_BUNGEE_SPRING + j``.
FIRST_BUNGEE_NODE = 21
FIRST_BUNGEE_SPRING = 8000
#: Flexure springs of strut ``i``: ``FIRST_TOP_FLEXURE_SPRING + i`` at its top end,
#: ``FIRST_BASE_FLEXURE_SPRING + i`` at its base end.
FIRST_TOP_FLEXURE_SPRING = 9100
FIRST_BASE_FLEXURE_SPRING = 9200


class Body(IntEnum):
    """Rigid-body ids of the testbed model."""

    UDF = 1
    BASE = 2
    TOP_LINKS = 3    # translation links of the top flexure ends
    BASE_LINKS = 4   # translation links of the base flexure ends


class StrutPart(IntEnum):
    """What a strut element is: the section it carries (:func:`strut_stations`)."""

    TUBE = 0             # bare tube
    ADAPTER = 1          # adapter block on the tube, no wafers
    ADAPTER_WAFERS = 2   # adapter block with the PZT wafers bonded on


def strut_ids(n_nodes: int) -> np.ndarray:
    """Node ids ``(N_STRUTS, n_nodes)`` of the struts; element ``j`` of a strut takes the id
    of its node ``j`` (its base-side end)."""
    return (STRUT_ID_STRIDE * (np.arange(N_STRUTS)[:, None] + 1) + np.arange(n_nodes)[None, :]).astype(np.int64)


@dataclass(frozen=True)
class CompositeSection:
    """Sums over the parts of a composite strut section, in the strut's local axes.

    Attributes
    ----------
    EA : float
        Axial stiffness [N].
    EIy, EIz : float
        Bending stiffnesses [N m^2].
    GJ : float
        Torsional stiffness [N m^2].
    rhoA : float
        Mass per length [kg/m].
    rhoIp : float
        Polar mass moment per length [kg m].
    """

    EA: float = 0.0
    EIy: float = 0.0
    EIz: float = 0.0
    GJ: float = 0.0
    rhoA: float = 0.0
    rhoIp: float = 0.0

    def __add__(self, other: "CompositeSection") -> "CompositeSection":
        return CompositeSection(*(getattr(self, f.name) + getattr(other, f.name) for f in fields(self)))


@dataclass(frozen=True)
class StrutSectionArrays:
    """Per-element arrays of one strut as the Model stores them (see the module docstring).

    Attributes
    ----------
    A, Iy, Iz, J : (n,) float
        Section area [m^2], second moments [m^4] and torsion constant [m^4].
    E, G, rho : (n,) float
        The tube's moduli [Pa] and density [kg/m^3].
    nsm : (n,) float
        Non-structural mass per length [kg/m].
    ip_missing : (n,) float
        Torsional mass moment per length the element cannot carry [kg m].
    """

    A: np.ndarray
    Iy: np.ndarray
    Iz: np.ndarray
    J: np.ndarray
    E: np.ndarray
    G: np.ndarray
    rho: np.ndarray
    nsm: np.ndarray
    ip_missing: np.ndarray


@dataclass(frozen=True)
class TestbedMap:
    """What the nodes, elements and springs of a testbed model are (ids, not indices).

    Attributes
    ----------
    strut_nodes : (6, n) int
        Node ids of each strut, in order from its base end to its top end.
    strut_elements : (6, n - 1) int
        Beam element ids of each strut in the same order (element ``j`` joins nodes ``j``
        and ``j + 1``).
    strut_s : (n,) float
        Distance of each strut node from the strut's base end [m] (same for all struts).
    adapter_elements : (6, m) int
        Elements of each strut's adapter block (1 or 3).
    adapter_nodes : (6, 2) int
        Node ids at the two ends of each adapter (base side first).
    wafer_elements : (6, w) int
        Elements covered by the PZT wafers (the induced-strain loads act over these).
    wafer_nodes : (6, 2) int
        Node ids at the two ends of the wafer-covered length.
    strut_base_nodes, strut_top_nodes : (6,) int
        Each strut's end nodes (``strut_nodes[:, 0]`` and ``strut_nodes[:, -1]``).
    udf_master : int
        Master node of the UDF rigid body (at its centre of gravity).
    accelerometer_nodes : (3,) int
        Accelerometer nodes (slaves of the UDF), ``k`` above strut junction ``k``.
    accelerometer_directions : (3, 3) float
        Unit sensing direction of each accelerometer, global axes.
    base_master : int or None
        Master node of the base rigid body when the base is suspended, else None.
    bungee_nodes : (b,) int
        Bungee attachment nodes (empty when clamped).
    bungee_springs : (b,) int
        Spring ids of the bungees.
    flexure_springs : (6, 2) int
        Spring ids of each strut's (base, top) flexure; -1 where the end is clamped.
    channel_struts : (3, 2) int
        The two struts driven by actuator channel ``k`` (they meet at top vertex ``k``).
    strut_frames : (6, 3, 3) float
        Rows: each strut's local x (base to top), y, z axes (global coordinates).
    udf_body, base_body : int
        Rigid-body ids (``base_body`` is -1 when clamped).
    """

    strut_nodes: np.ndarray
    strut_elements: np.ndarray
    strut_s: np.ndarray
    adapter_elements: np.ndarray
    adapter_nodes: np.ndarray
    wafer_elements: np.ndarray
    wafer_nodes: np.ndarray
    strut_base_nodes: np.ndarray
    strut_top_nodes: np.ndarray
    udf_master: int
    accelerometer_nodes: np.ndarray
    accelerometer_directions: np.ndarray
    base_master: int | None
    bungee_nodes: np.ndarray
    bungee_springs: np.ndarray
    flexure_springs: np.ndarray
    channel_struts: np.ndarray
    strut_frames: np.ndarray
    udf_body: int
    base_body: int

    def strut_of_element(self, element_ids) -> np.ndarray:
        """Strut number (0..5) of beam element ids (-1 for non-strut ids)."""
        ids = np.asarray(element_ids)
        k = ids // STRUT_ID_STRIDE - 1
        return np.where((k >= 0) & (k < N_STRUTS), k, -1)


@dataclass
class TestbedModel:
    """The testbed's FE model, its map, and the parameters it was built from.

    Attributes
    ----------
    model : fem.Model
    map : TestbedMap
    testbed : trussid.geometry.Testbed
    elements_per_segment : int
    """

    model: Model
    map: TestbedMap
    testbed: object
    elements_per_segment: int


# ----------------------------------------------------------------------------- sections
def tube_properties(r_out: float, t) -> tuple[np.ndarray, np.ndarray]:
    """Area ``A_t`` [m^2] and second moment ``I_t`` [m^4] of round tubes (``J_t = 2 I_t``)."""
    t = np.asarray(t, float)
    ri = r_out - t
    return math.pi * (r_out**2 - ri**2), 0.25 * math.pi * (r_out**4 - ri**4)


def tube_property_derivatives(r_out: float, t) -> tuple[np.ndarray, np.ndarray]:
    """``dA_t/dt`` [m] and ``dI_t/dt`` [m^3] of round tubes of wall ``t``."""
    ri = r_out - np.asarray(t, float)
    return 2.0 * math.pi * ri, math.pi * ri**3


def adapter_constant_properties(tb, with_wafers: bool) -> CompositeSection:
    """The adapter's constant (non-tube) contributions to the composite section.

    Parameters
    ----------
    tb : trussid.geometry.Testbed
    with_wafers : bool
        Include the PZT wafers.

    Returns
    -------
    CompositeSection
        The sums over the block (and the wafers when ``with_wafers``).
    """
    s, a, p = tb.struts, tb.adapter, tb.pzt
    blk = Section.square_with_bore(a.side, s.outer_radius, name="adapter block")
    Gb = a.youngs_modulus / (2.0 * (1.0 + a.poisson_ratio))
    out = CompositeSection(EA=a.youngs_modulus * blk.A, EIy=a.youngs_modulus * blk.Iy,
                           EIz=a.youngs_modulus * blk.Iz, GJ=Gb * blk.J, rhoA=a.density * blk.A,
                           rhoIp=a.density * (blk.Iy + blk.Iz))
    if with_wafers:
        W, T = p.width, p.thickness
        Aw = W * T
        d = 0.5 * a.side + 0.5 * T
        # One pair on the +-y faces: plate normal along y, width along z.
        iz_pair = 2.0 * (W * T**3 / 12.0 + Aw * d**2)   # about z: bending with v (along y)
        iy_pair = 2.0 * (T * W**3 / 12.0)                # about y: centroids on the y axis
        n_pairs = p.wafers_per_strut // 2
        Iz = iz_pair + (iy_pair if n_pairs == 2 else 0.0)
        Iy = iy_pair + (iz_pair if n_pairs == 2 else 0.0)
        Aws = p.wafers_per_strut * Aw
        out = out + CompositeSection(EA=p.youngs_modulus * Aws, EIy=p.youngs_modulus * Iy,
                                     EIz=p.youngs_modulus * Iz, rhoA=p.density * Aws,
                                     rhoIp=p.density * (Iy + Iz))
    return out


def _strut_section_arrays(tb, kinds: np.ndarray, wall: float) -> StrutSectionArrays:
    """Per-element Model arrays for one strut of elements ``kinds`` (:class:`StrutPart`)
    and wall ``wall`` [m]. See the module docstring for the mapping."""
    s = tb.struts
    E, G, rho = s.youngs_modulus, s.youngs_modulus / (2.0 * (1.0 + s.poisson_ratio)), s.density
    At, It = (float(v) for v in tube_properties(s.outer_radius, wall))
    parts = {StrutPart.TUBE: CompositeSection(), StrutPart.ADAPTER: adapter_constant_properties(tb, False),
             StrutPart.ADAPTER_WAFERS: adapter_constant_properties(tb, True)}
    # per element, each sum of the parts of its kind
    c = CompositeSection(*(np.array([getattr(parts[StrutPart(kind)], f.name) for kind in kinds])
                           for f in fields(CompositeSection)))
    A, Iy, Iz, J = At + c.EA / E, It + c.EIy / E, It + c.EIz / E, 2 * It + c.GJ / G
    # rho = the tube's density: the tube's own mass terms stay exact (and linear in A_t, I_t);
    # the rest of the mass per length goes to nsm, the rest of the polar moment to point
    # inertias (ip_missing).
    nsm = c.rhoA - rho * c.EA / E
    ip_missing = c.rhoIp - rho * (c.EIy + c.EIz) / E
    if (nsm < -1e-9 * np.maximum(c.rhoA, 1e-300)).any():
        raise ModelError("adapter: the block and wafers are stiffer for their mass than the tube "
                         f"(E/rho above {E / rho:.4g} m^2/s^2); this composite section cannot be "
                         "represented with the tube's density (adapter.density, pzt.density)")
    n = len(kinds)
    return StrutSectionArrays(A=A, Iy=Iy, Iz=Iz, J=J, E=np.full(n, E), G=np.full(n, G), rho=np.full(n, rho),
                              nsm=np.maximum(nsm, 0.0), ip_missing=ip_missing)


# ----------------------------------------------------------------------------- mesh
def strut_stations(tb, elements_per_segment: int = ELEMENTS_PER_SEGMENT) -> tuple[np.ndarray, np.ndarray]:
    """Node positions along a strut [m] and the kind of each element.

    Returns
    -------
    s : (n,) float
        Distances of the nodes from the base end.
    kinds : (n - 1,) int
        :class:`StrutPart` of each element.
    """
    if int(elements_per_segment) != elements_per_segment or elements_per_segment < 1:
        raise ModelError(f"elements_per_segment must be a positive integer, got {elements_per_segment!r}")
    n = int(elements_per_segment)
    L, La, Lw = tb.struts.length, tb.adapter.length, tb.pzt.length
    a0, a1 = 0.5 * (L - La), 0.5 * (L + La)
    seg1 = np.linspace(0.0, a0, n + 1)
    seg2 = np.linspace(a1, L, n + 1)
    if La - Lw > MIN_LIP * La:
        w0, w1 = 0.5 * (L - Lw), 0.5 * (L + Lw)
        adapter = np.array([w0, w1])
        akinds = [StrutPart.ADAPTER, StrutPart.ADAPTER_WAFERS, StrutPart.ADAPTER]
    else:
        adapter = np.zeros(0)
        akinds = [StrutPart.ADAPTER_WAFERS]
    s = np.concatenate([seg1, adapter, seg2])
    kinds = np.array([StrutPart.TUBE] * n + akinds + [StrutPart.TUBE] * n, dtype=int)
    return s, kinds


def build_testbed(tb=None, elements_per_segment: int = ELEMENTS_PER_SEGMENT,
                  beam_theory: str = "euler-bernoulli", mass: str = "consistent") -> TestbedModel:
    """The FE model of testbed ``tb`` (default: the default :class:`~trussid.geometry.spec.Testbed`).

    Parameters
    ----------
    tb : trussid.geometry.Testbed, optional
    elements_per_segment : int
        Frame elements on each bare tube segment.
    beam_theory, mass : str
        Passed to :class:`trussid.fem.Model`.

    Returns
    -------
    TestbedModel
    """
    # Long: the testbed is built in the order it is assembled in the lab (struts, adapters,
    # flexures, UDF, base, bungees, sensors), each step adding to the same model and map.
    tb = Testbed() if tb is None else tb
    lay = testbed_layout(tb)
    s, kinds = strut_stations(tb, elements_per_segment)
    n_nodes, n_el = len(s), len(kinds)
    model = Model(beam_theory=beam_theory, mass=mass, name="testbed")
    frames = lay.strut_frames()

    strut_nodes = strut_ids(n_nodes)
    strut_elements = strut_nodes[:, :-1].copy()
    xyz = lay.strut_start[:, None, :] + s[None, :, None] * lay.strut_axis[:, None, :]
    model.add_nodes(strut_nodes.ravel(), xyz.reshape(-1, 3))
    names = {StrutPart.TUBE: "tube", StrutPart.ADAPTER: "adapter", StrutPart.ADAPTER_WAFERS: "adapter+wafers"}
    for i in range(N_STRUTS):
        props = _strut_section_arrays(tb, kinds, tb.struts.walls[i])
        for kind in StrutPart:
            sel = np.flatnonzero(kinds == kind)
            if not len(sel):
                continue
            sec = dict(A=props.A[sel], Iy=props.Iy[sel], Iz=props.Iz[sel], J=props.J[sel], Asy=np.inf, Asz=np.inf)
            mat = dict(E=props.E[sel], G=props.G[sel], rho=props.rho[sel])
            model.add_beams(strut_elements[i, sel], np.column_stack([strut_nodes[i, sel], strut_nodes[i, sel + 1]]),
                            sec, mat, orient=lay.strut_y[i], nsm=props.nsm[sel], label=f"strut {i} {names[kind]}")
        lumped = props.ip_missing * np.diff(s)  # kg m^2 per element
        # (lumped beam mass has no rotary inertia at all: nothing to complete then)
        el = np.flatnonzero(lumped > 0) if mass == "consistent" else np.zeros(0, int)
        if len(el):
            axis = lay.strut_axis[i]
            half = 0.5 * lumped[el]
            model.add_point_masses(np.r_[strut_nodes[i, el], strut_nodes[i, el + 1]], 0.0,
                                   inertia=np.r_[half, half][:, None, None] * np.outer(axis, axis))
    adapter_idx = np.flatnonzero(kinds != StrutPart.TUBE)
    wafer_idx = np.flatnonzero(kinds == StrutPart.ADAPTER_WAFERS)

    # UDF rigid body and accelerometers.
    m_udf, cg_udf, i_udf = udf_rigid_body(tb)
    model.add_node(UDF_MASTER, cg_udf)
    acc_nodes = np.array(ACCELEROMETER_NODES)
    model.add_nodes(acc_nodes, lay.accelerometer_points)
    model.add_point_masses(acc_nodes, tb.accelerometers.mass)

    top, base = strut_nodes[:, -1], strut_nodes[:, 0]
    k_top, k_base = tb.struts.top_rotational_stiffness, tb.struts.base_rotational_stiffness
    flex = np.full((N_STRUTS, 2), -1, dtype=np.int64)
    G = tb.struts.youngs_modulus / (2.0 * (1.0 + tb.struts.poisson_ratio))
    # Scaled on a solid rod of the tube's outside diameter: independent of the walls, so
    # that wall sweeps (wall_basis) leave it unchanged.
    k_tor = TORSION_RIGID_FACTOR * G * 0.5 * math.pi * tb.struts.outer_radius**4 / tb.struts.length

    def rot_spring(k):  # stiffness in the strut frame: torsion about x, bending about y and z
        return [0.0, 0.0, 0.0, k_tor, k, k]

    udf_slaves = list(acc_nodes)
    if math.isinf(k_top):
        udf_slaves += list(top)
    else:
        model.add_rigid_body(Body.TOP_LINKS, UDF_MASTER, top, dofs="123", label="top flexure links")
        flex[:, 1] = FIRST_TOP_FLEXURE_SPRING + np.arange(N_STRUTS)
        model.add_springs(flex[:, 1], np.column_stack([top, np.full(N_STRUTS, UDF_MASTER)]), rot_spring(k_top),
                          frame=frames)
    model.add_rigid_body(Body.UDF, UDF_MASTER, udf_slaves, mass=m_udf, cg=cg_udf, inertia=i_udf, label="UDF")

    bungee_nodes = np.zeros(0, np.int64)
    bungee_springs = np.zeros(0, np.int64)
    base_master, base_body = None, -1
    if tb.base.support == "suspended":
        m_b, cg_b, i_b = base_rigid_body(tb)
        base_master, base_body = BASE_MASTER, int(Body.BASE)
        model.add_node(BASE_MASTER, cg_b)
        bungee_nodes = FIRST_BUNGEE_NODE + np.arange(tb.base.bungee_count)
        model.add_nodes(bungee_nodes, lay.bungee_points)
        bungee_springs = FIRST_BUNGEE_SPRING + np.arange(tb.base.bungee_count)
        kl, kv = tb.base.bungee_lateral_stiffness, tb.base.bungee_vertical_stiffness
        model.add_springs(bungee_springs, bungee_nodes, [kl, kl, kv, 0.0, 0.0, 0.0])
        base_slaves = list(bungee_nodes)
        if math.isinf(k_base):
            base_slaves += list(base)
        else:
            model.add_rigid_body(Body.BASE_LINKS, BASE_MASTER, base, dofs="123", label="base flexure links")
            flex[:, 0] = FIRST_BASE_FLEXURE_SPRING + np.arange(N_STRUTS)
            model.add_springs(flex[:, 0], np.column_stack([base, np.full(N_STRUTS, BASE_MASTER)]),
                              rot_spring(k_base), frame=frames)
        model.add_rigid_body(Body.BASE, BASE_MASTER, base_slaves, mass=m_b, cg=cg_b, inertia=i_b, label="base")
    else:
        if math.isinf(k_base):
            model.fix(base, "123456")
        else:
            model.fix(base, "123")
            flex[:, 0] = FIRST_BASE_FLEXURE_SPRING + np.arange(N_STRUTS)
            model.add_springs(flex[:, 0], base, rot_spring(k_base), frame=frames)

    tmap = TestbedMap(
        strut_nodes=strut_nodes, strut_elements=strut_elements, strut_s=s,
        adapter_elements=strut_elements[:, adapter_idx], adapter_nodes=np.column_stack(
            [strut_nodes[:, adapter_idx[0]], strut_nodes[:, adapter_idx[-1] + 1]]),
        wafer_elements=strut_elements[:, wafer_idx], wafer_nodes=np.column_stack(
            [strut_nodes[:, wafer_idx[0]], strut_nodes[:, wafer_idx[-1] + 1]]),
        strut_base_nodes=base.copy(), strut_top_nodes=top.copy(), udf_master=UDF_MASTER,
        accelerometer_nodes=acc_nodes, accelerometer_directions=np.array(lay.accelerometer_axes),
        base_master=base_master, bungee_nodes=bungee_nodes, bungee_springs=bungee_springs,
        flexure_springs=flex, channel_struts=np.array(lay.channel_struts), strut_frames=np.array(frames),
        udf_body=int(Body.UDF), base_body=base_body,
    )
    return TestbedModel(model=model, map=tmap, testbed=tb, elements_per_segment=int(elements_per_segment))


__all__ = ["TestbedMap", "TestbedModel", "build_testbed", "strut_stations", "tube_properties",
           "tube_property_derivatives", "adapter_constant_properties", "ELEMENTS_PER_SEGMENT",
           "TORSION_RIGID_FACTOR", "N_STRUTS", "STRUT_ID_STRIDE", "UDF_MASTER", "ACCELEROMETER_NODES",
           "BASE_MASTER", "FIRST_BUNGEE_NODE", "FIRST_BUNGEE_SPRING", "FIRST_TOP_FLEXURE_SPRING",
           "FIRST_BASE_FLEXURE_SPRING", "Body", "StrutPart", "strut_ids", "CompositeSection",
           "StrutSectionArrays"]
