"""Solid models of the testbed's parts (trimesh) and their mass properties.

Meshes are built only on request (they cost milliseconds, the layout microseconds). Round
parts are inscribed polygons of ``sections`` sides: a circle's area comes out short by about
``(2 pi / sections)^2 / 6`` and its polar moment by twice that (1.0e-4 and 2.0e-4 at the
default 256 sides; 128 sides would leave a tube's axial inertia 8e-4 short).

The upper delta frame (UDF) is a steel triangular prism frame of square bars: a lower and an
upper equilateral triangle of ``udf.side`` (bar centrelines) joined by three vertical posts
of ``udf.height``. Its real drawings are lost, so :func:`udf_rigid_body` keeps the frame's
shape (centre of gravity, inertia) and scales its density so the mass is exactly
``udf.mass`` (35 lb): inertia about the centre of gravity scales with the mass for a uniform
density.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import trimesh

from trussid.geometry.errors import ParameterError
from trussid.geometry.layout import Layout, testbed_layout
from trussid.geometry.spec import Testbed

#: Default number of sides of round parts; enough for 1e-3 mass properties (module docstring).
SECTIONS = 256


@dataclass(frozen=True)
class MassProperties:
    """Mass [kg], centre of gravity (3,) [m] and inertia tensor (3, 3) about it [kg m^2]."""

    mass: float
    cg: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class Solid:
    """One part: its name (e.g. ``"strut 3 tube"``), closed mesh [m] and density [kg/m^3]."""

    name: str
    mesh: trimesh.Trimesh
    density: float

    def mass_properties(self) -> MassProperties:
        """Mass properties of this part at its density."""
        return mass_properties(self.mesh, self.density, name=self.name)


def mass_properties(mesh: trimesh.Trimesh, density: float, name: str = "mesh") -> MassProperties:
    """Mass, centre of gravity and inertia tensor about the centre of gravity of a closed mesh.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        A watertight mesh [m].
    density : float
        Uniform density [kg/m^3].
    name : str
        Used in the error message.

    Returns
    -------
    MassProperties
        ``inertia`` is in the mesh's axes, about the centre of gravity.
    """
    if not mesh.is_watertight:
        raise ParameterError(f"solid {name!r} is not closed: no mass properties")
    props = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    props.density = float(density)
    mp = props.mass_properties
    return MassProperties(mass=float(mp.mass), cg=np.asarray(mp.center_mass, dtype=float),
                          inertia=np.asarray(mp.inertia, dtype=float))


# -- primitives along a local z axis, then placed ------------------------------------------
def _placement(frame_rows: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Homogeneous transform taking local (x', y', z') = (strut y, strut z, strut axis)."""
    T = np.eye(4)
    x, y, z = frame_rows  # strut axis, strut y, strut z
    T[:3, 0], T[:3, 1], T[:3, 2] = y, z, x
    T[:3, 3] = origin
    return T


def tube_mesh(r_outer: float, r_inner: float, length: float, sections: int = SECTIONS) -> trimesh.Trimesh:
    """A tube along z, centred at the origin [m]."""
    return trimesh.creation.annulus(r_min=r_inner, r_max=r_outer, height=length, sections=sections)


def bored_block_mesh(side: float, length: float, bore_radius: float, sections: int = SECTIONS) -> trimesh.Trimesh:
    """A square block along z, centred at the origin, with a central round bore [m]."""
    block = trimesh.creation.box(extents=(side, side, length))
    # The cutter is longer than the block so that no coplanar faces confuse the boolean.
    bore = trimesh.creation.cylinder(radius=bore_radius, height=1.5 * length, sections=sections)
    return trimesh.boolean.difference([block, bore], engine="manifold")


def strut_solids(tb: Testbed, layout: Layout | None = None, sections: int = SECTIONS) -> list:
    """Tube, adapter block and wafers of every strut, placed in the global frame.

    Returns
    -------
    list of Solid
        Per strut i: ``"strut i tube"``, ``"strut i adapter"``, ``"strut i wafer j"``.
    """
    layout = testbed_layout(tb) if layout is None else layout
    s, a, p = tb.struts, tb.adapter, tb.pzt
    block = bored_block_mesh(a.side, a.length, s.outer_radius, sections)
    wafer = trimesh.creation.box(extents=(p.thickness, p.width, p.length))  # local x' = face normal
    offset = 0.5 * (a.side + p.thickness)
    # Wafer j's face: local +y', -y', +x', -x' (strut -> +y, -y, +z, -z per layout docs).
    face_turns = [(0.0, offset), (np.pi, offset), (0.5 * np.pi, offset), (1.5 * np.pi, offset)]
    frames = layout.strut_frames()
    solids = []
    for i in range(6):
        T_mid = _placement(frames[i], layout.adapter_centre[i])
        tube = tube_mesh(s.outer_radius, s.inner_radii[i], s.length, sections)
        solids.append(Solid(f"strut {i} tube", tube.apply_transform(T_mid), s.density))
        solids.append(Solid(f"strut {i} adapter", block.copy().apply_transform(T_mid), a.density))
        for j in range(p.wafers_per_strut):
            angle, d = face_turns[j]
            R = trimesh.transformations.rotation_matrix(angle, [0.0, 0.0, 1.0])
            local = R @ trimesh.transformations.translation_matrix([d, 0.0, 0.0])
            # Local x' is strut y (see _placement), so the first wafer sits on the +y face.
            solids.append(Solid(f"strut {i} wafer {j}", wafer.copy().apply_transform(T_mid @ local), p.density))
    return solids


def udf_frame_mesh_local(side: float, height: float, member_size: float) -> trimesh.Trimesh:
    """The UDF prism frame with its lower-triangle centroid at the origin [m].

    Corners at azimuths 60, 180, 300 degrees (the top vertices' directions), radius
    ``side / sqrt(3)``; lower bar centrelines at z = 0, upper at z = ``height``; posts span
    both bars' depth so the corners are closed.
    """
    k = np.arange(3)
    az = np.radians(60.0 + 120.0 * k)
    rc = side / np.sqrt(3.0)
    corners = np.column_stack([rc * np.cos(az), rc * np.sin(az), np.zeros(3)])
    a = member_size
    bars = []
    for z in (0.0, height):
        for i in range(3):
            p0, p1 = corners[i], corners[(i + 1) % 3]
            direction = (p1 - p0) / side
            bar = trimesh.creation.box(extents=(side, a, a))  # along local x
            T = np.eye(4)
            T[:3, 0] = direction
            T[:3, 1] = np.cross([0.0, 0.0, 1.0], direction)
            T[:3, 2] = [0.0, 0.0, 1.0]
            T[:3, 3] = 0.5 * (p0 + p1) + [0.0, 0.0, z]
            bars.append(bar.apply_transform(T))
    for i in range(3):
        post = trimesh.creation.box(extents=(a, a, height + a))
        R = trimesh.transformations.rotation_matrix(az[i], [0.0, 0.0, 1.0])  # a face towards the centre
        R[:3, 3] = corners[i] + [0.0, 0.0, 0.5 * height]
        bars.append(post.apply_transform(R))
    return trimesh.boolean.union(bars, engine="manifold")


def udf_solid(tb: Testbed, layout: Layout | None = None) -> Solid:
    """The UDF frame in place, with its density scaled so its mass is ``udf.mass``."""
    layout = testbed_layout(tb) if layout is None else layout
    u = tb.udf
    mesh = udf_frame_mesh_local(u.side, u.height, u.member_size)
    mesh.apply_translation([0.0, 0.0, layout.top_vertices[0, 2]])
    return Solid("udf", mesh, u.mass / mesh.volume)


@functools.lru_cache(maxsize=64)
def _udf_local_properties(side: float, height: float, member_size: float) -> tuple:
    # Memoised pure function: design sweeps vary walls, not the UDF, and the boolean union
    # costs milliseconds.
    mesh = udf_frame_mesh_local(side, height, member_size)
    mp = mass_properties(mesh, 1.0, name="udf")
    mp.cg.flags.writeable = False  # cached: shared by every caller
    mp.inertia.flags.writeable = False
    return mp.mass, mp.cg, mp.inertia  # at unit density: mass = volume


def udf_rigid_body(tb: Testbed) -> tuple:
    """Mass [kg], centre of gravity (3,) [m] and inertia (3, 3) about it [kg m^2] of the UDF.

    Taken from the steel-frame solid (:func:`udf_frame_mesh_local`) with its uniform density
    scaled so that the mass is exactly ``tb.udf.mass``. Global frame of the layout.
    """
    u = tb.udf
    volume, cg, inertia = _udf_local_properties(u.side, u.height, u.member_size)
    cg = cg + np.array([0.0, 0.0, tb.strut_height])
    return u.mass, cg, inertia * (u.mass / volume)


def base_solid(tb: Testbed, layout: Layout | None = None, sections: int = SECTIONS) -> Solid:
    """The base plate disc (top face at z = 0) at the aluminium density."""
    layout = testbed_layout(tb) if layout is None else layout
    disc = trimesh.creation.cylinder(radius=0.5 * tb.base.diameter, height=tb.base.thickness,
                                     sections=sections)
    disc.apply_translation(layout.base_centre)
    return Solid("base", disc, tb.base.density)


def base_rigid_body(tb: Testbed, sections: int = SECTIONS) -> tuple:
    """Mass [kg], centre of gravity [m] and inertia about it [kg m^2] of the base plate.

    From the disc solid, with the density scaled so that the mass is exactly ``base.mass``
    (the polygonal disc is a hair smaller than the circle).
    """
    mp = base_solid(tb, sections=sections).mass_properties()
    return tb.base.mass, mp.cg, mp.inertia * (tb.base.mass / mp.mass)


def testbed_solids(tb: Testbed, sections: int = SECTIONS) -> list:
    """Every solid part of the testbed in the global frame: struts, adapters, wafers, UDF, base."""
    layout = testbed_layout(tb)
    return strut_solids(tb, layout, sections) + [udf_solid(tb, layout), base_solid(tb, layout, sections)]
