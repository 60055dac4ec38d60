"""Mode-shape scenes: the deformed geometry of a mode as meshes, before any drawing.

The structure as solids: every beam a tube whose radius is the equivalent radius of its
section, deformed with the cubic Hermite shape functions of a frame element from the end
translations and rotations (bending modes look curved between nodes); rigid bodies thin
tubes from master to slaves; point masses small spheres; supports dark cubes; and optional
*decorations* (:class:`Decoration`: arbitrary solids that ride on one node's rigid motion).
The deformed shape carries its displacement magnitude relative to its maximum
(:data:`SCALAR_NAME`) for colouring over a faint ghost of the undeformed structure.

Mode numbers are 1-based throughout (mode 1 is the lowest), as on the command line.

:func:`mode_scene` builds a mode's :class:`ModeScene` (tests read the colours and the
deflections off its meshes); the offscreen renderer (:mod:`trussid.fem.render`) and the
HTML viewer (:mod:`trussid.fem.render_html`) draw from the same numerics here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from trussid.fem.errors import RenderError
from trussid.fem.model import Model

__all__ = ["DEFAULT_AMPLITUDE", "GHOST_COLOR", "GHOST_OPACITY", "SUPPORT_COLOR",
           "SCALAR_NAME", "Decoration", "FIXED_PART_COLOUR", "decorations_from_solids",
           "hermite_beam_displacements", "equivalent_radius", "check_mode_number",
           "node_displacements", "ModeScene", "mode_scene", "default_cmap"]

#: Default drawn amplitude: the largest displacement is this fraction of the diagonal of the
#: model's bounding box.
DEFAULT_AMPLITUDE = 0.08
GHOST_COLOR = "#9a9a9a"
GHOST_OPACITY = 0.22
SUPPORT_COLOR = "#3b3b3b"
SCALAR_NAME = "displacement / max"


# --------------------------------------------------------------------------- inputs
@dataclass(frozen=True)
class Decoration:
    """A solid drawn with the structure and moved by one node's rigid-body motion.

    Parameters
    ----------
    mesh : trimesh.Trimesh or pyvista.DataSet
        The solid in its undeformed position, global coordinates [m].
    color : colour-like, optional
        Its own colour (e.g. PZT wafers); ``None`` colours it by displacement magnitude like
        the beams.
    node : int, optional
        Id of the node whose translation and (small) rotation carry the solid:
        ``u(x) = u_node + theta_node x (x - x_node)``. ``None``: the solid does not move
        (a clamped base plate).
    opacity : float
        0-1.
    name : str
        For error messages and the scene's dictionary of meshes.
    """

    mesh: Any
    color: Any = None
    node: int | None = None
    opacity: float = 1.0
    name: str = ""


def _as_decoration(item) -> Decoration:
    if isinstance(item, Decoration):
        return item
    if isinstance(item, dict):
        return Decoration(**item)
    return Decoration(*item)  # (mesh, colour, node[, opacity[, name]])


#: Colour of parts that do not move (attached to no node).
FIXED_PART_COLOUR = "#8a8a8a"


def decorations_from_solids(solids, attach, *, colours=None, skip=("tube",)) -> list[Decoration]:
    """Decorations from named solids, e.g. the testbed's (:mod:`trussid.testbed.render`).

    Parameters
    ----------
    solids : iterable
        Objects with ``name`` and ``mesh`` attributes or ``(name, mesh)``
        pairs; meshes in global coordinates [m].
    attach : mapping or callable
        Solid name -> id of the node whose rigid motion carries it, or ``None`` for a part
        that does not move. A mapping must name every solid that is not skipped.
    colours : mapping, optional
        Word of the name -> colour (``None``: by displacement); default: every part by
        displacement. Parts attached to no node and without a colour are grey.
    skip : sequence of str
        Solids whose name contains one of these words are left out (strut tubes: the
        beams are already drawn as tubes of their real radius).

    Returns
    -------
    list of Decoration
    """
    colours = {} if colours is None else colours
    out = []
    for solid in solids:
        name, mesh = (solid.name, solid.mesh) if hasattr(solid, "mesh") else solid
        words = name.lower().split()
        if any(w in words for w in skip):
            continue
        if callable(attach):
            node = attach(name)
        else:
            if name not in attach:
                raise RenderError(f"solid {name!r}: no node given to attach it to")
            node = attach[name]
        colour = next((c for word, c in colours.items() if word in words), None)
        if colour is None and node is None:
            colour = FIXED_PART_COLOUR
        out.append(Decoration(mesh, colour, None if node is None else int(node), name=name))
    return out


# --------------------------------------------------------------------------- numerics
def hermite_beam_displacements(x_a, x_b, u_a, u_b, xi, rod=None):
    """Displacements along frame elements from their end translations and rotations.

    Transverse displacement uses the cubic Hermite shape functions of an Euler-Bernoulli
    beam (exact for end-loaded beams); the axial part is linear. The slope of the
    transverse displacement at an end is ``theta x e`` for end rotation ``theta`` and unit
    axis ``e``, so no local axes are needed. Rods (``rod`` True) are interpolated linearly.

    Parameters
    ----------
    x_a, x_b : (n, 3) float
        End coordinates [m].
    u_a, u_b : (n, 6) float
        End displacements (ux, uy, uz, rx, ry, rz) [m, rad].
    xi : (s,) float
        Sample positions along each element, 0 (end A) to 1 (end B).
    rod : (n,) bool, optional

    Returns
    -------
    x : (n, s, 3) float
        Undeformed sample points [m].
    u : (n, s, 3) float
        Their displacements [m].
    """
    x_a, x_b = np.asarray(x_a, float), np.asarray(x_b, float)
    u_a, u_b = np.asarray(u_a, float), np.asarray(u_b, float)
    xi = np.asarray(xi, float)
    d = x_b - x_a
    length = np.linalg.norm(d, axis=1)
    e = d / np.where(length > 0, length, 1.0)[:, None]
    s = xi[None, :, None]
    x = x_a[:, None, :] + s * d[:, None, :]
    linear = (1 - s) * u_a[:, None, :3] + s * u_b[:, None, :3]
    h1 = 1 - 3 * s**2 + 2 * s**3
    h2 = s - 2 * s**2 + s**3
    h3 = 3 * s**2 - 2 * s**3
    h4 = -(s**2) + s**3
    L = length[:, None, None]
    slope_a = np.cross(u_a[:, 3:], e)[:, None, :]
    slope_b = np.cross(u_b[:, 3:], e)[:, None, :]
    w = h1 * u_a[:, None, :3] + h2 * L * slope_a + h3 * u_b[:, None, :3] + h4 * L * slope_b
    ee = e[:, None, :]
    u = np.sum(linear * ee, axis=2, keepdims=True) * ee + w - np.sum(w * ee, axis=2, keepdims=True) * ee
    if rod is not None:
        rod = np.asarray(rod, bool)
        u[rod] = linear[rod]
    return x, u


def equivalent_radius(A, Iy, Iz, J=None, rod=None):
    """Outer radius of the round tube with the section's area and mean second moment.

    For a tube or a solid circle this is exactly its outer radius: with
    ``I = pi (ro^4 - ri^4) / 4`` and ``A = pi (ro^2 - ri^2)``, ``ro^2 = (4 I / A + A / pi) / 2``.
    Other shapes get the tube that has the same A and I. Rods (no bending stiffness, their
    I is a placeholder) use the polar moment instead, ``I = J / 2``.

    Parameters
    ----------
    A, Iy, Iz : array-like
        [m^2, m^4, m^4].
    J : array-like, optional
        Torsion constant [m^4], used for rods.
    rod : array-like of bool, optional

    Returns
    -------
    r : ndarray [m]
    """
    A = np.asarray(A, float)
    inertia = 0.5 * (np.asarray(Iy, float) + np.asarray(Iz, float))
    if J is not None and rod is not None:
        inertia = np.where(np.asarray(rod, bool), 0.5 * np.asarray(J, float), inertia)
    with np.errstate(divide="ignore", invalid="ignore"):
        r2 = 0.5 * (4 * inertia / A + A / math.pi)
        r = np.sqrt(r2)
        fallback = np.sqrt(np.abs(A) / math.pi)
    return np.where(np.isfinite(r) & (r > 0), r, fallback)


def node_displacements(model: Model, modes, mode: int) -> np.ndarray:
    """(n_nodes, 6) shape of ``mode`` (1-based) in the model's node order, sign-normalised."""
    shapes = np.asarray(modes.shapes_full, float)
    n_modes = shapes.shape[1]
    check_mode_number(mode, n_modes)
    mode_ids = np.asarray(modes.node_ids, np.int64)
    if shapes.shape[0] != 6 * len(mode_ids):
        raise RenderError(f"shapes_full has {shapes.shape[0]} rows, expected 6 x {len(mode_ids)} nodes")
    order = np.argsort(mode_ids, kind="stable")
    sorted_ids = mode_ids[order]
    ids = model.node_ids
    pos = np.minimum(np.searchsorted(sorted_ids, ids), max(len(sorted_ids) - 1, 0))
    found = sorted_ids[pos] == ids if len(sorted_ids) else np.zeros(len(ids), bool)
    if not found.all():
        raise RenderError(f"node {ids[~found][0]} of the model has no entry in the mode shapes")
    rows = order[pos]
    u = shapes[:, mode - 1].reshape(-1, 6)[rows]
    # Eigenvectors have an arbitrary sign: make the largest translation positive so a
    # picture does not flip between solver runs.
    flat = u[:, :3].ravel()
    if flat.size and flat[np.argmax(np.abs(flat))] < 0:
        u = -u
    return u


def check_mode_number(mode, n_modes: int) -> None:
    """Raise :class:`RenderError` unless ``mode`` is an integer in 1..``n_modes``."""
    if isinstance(mode, bool) or not isinstance(mode, (int, np.integer)):
        raise RenderError(f"mode number must be an integer, got {mode!r}")
    if n_modes < 1:
        raise RenderError("there are no modes to render")
    if not 1 <= mode <= n_modes:
        raise RenderError(f"mode {mode} is out of range: valid mode numbers are 1 to {n_modes}")


def _mode_title(modes, mode: int, label: str | None, labels: Sequence[str] | None) -> str:
    if label is None:
        seq = labels if labels is not None else getattr(modes, "labels", None)
        if seq is not None and len(seq) >= mode:
            label = seq[mode - 1]
    freq = float(np.asarray(modes.frequencies_hz)[mode - 1])
    title = f"Mode {mode}: {freq:.4g} Hz"
    return f"{title}  {label}" if label else title


# --------------------------------------------------------------------------- geometry
def _polylines(points: np.ndarray):
    """PolyData of ``n`` polylines from points (n, s, 3)."""
    import pyvista as pv  # deferred: VTK takes ~1 s to load; only drawing needs it

    n, s, _ = points.shape
    idx = np.arange(n * s).reshape(n, s)
    lines = np.column_stack([np.full(n, s), idx]).ravel()
    return pv.PolyData(points.reshape(-1, 3), lines=lines)


def _tubes(points: np.ndarray, radius: np.ndarray, data: dict[str, np.ndarray], n_sides: int):
    """Tubes along polylines (n, s, 3) with per-line radius; ``data`` per line or per point."""
    poly = _polylines(points)
    n, s, _ = points.shape
    poly.point_data["radius"] = np.repeat(radius, s)
    for key, value in data.items():
        value = np.asarray(value)
        poly.point_data[key] = np.repeat(value, s) if value.shape == (n,) else value.reshape(n * s)
    poly.point_data["sample"] = np.arange(n * s)
    return poly.tube(scalars="radius", absolute=True, n_sides=n_sides, capping=True)


def _with_normals(mesh):
    """Triangulated surface with point normals split at sharp edges (flat faces stay flat).

    Done once on the undeformed solid: solids move rigidly, and the small rotations drawn
    do not visibly change the shading.
    """
    surf = mesh.extract_surface() if not hasattr(mesh, "faces") else mesh
    return surf.triangulate().compute_normals(split_vertices=True, feature_angle=30.0,
                                              auto_orient_normals=False, consistent_normals=False)


def _replicate(template, centres: np.ndarray, sizes: np.ndarray):
    """One copy of ``template`` (unit size, at the origin) per centre, scaled, merged."""
    import pyvista as pv  # deferred: VTK takes ~1 s to load; only drawing needs it

    tpl = template.triangulate()
    p = np.asarray(tpl.points)
    faces = np.asarray(tpl.faces).reshape(-1, 4)[:, 1:]
    k = len(centres)
    pts = centres[:, None, :] + sizes[:, None, None] * p[None]
    f = faces[None] + (np.arange(k) * len(p))[:, None, None]
    f = np.concatenate([np.full((k, len(faces), 1), 3), f], axis=2).ravel()
    return pv.PolyData(pts.reshape(-1, 3), faces=f)


@dataclass
class _Part:
    """A drawable piece: undeformed points and their unit-scale displacements."""

    name: str
    kind: str  # "tubes" | "solid"
    x0: np.ndarray
    u: np.ndarray
    color: Any = None
    opacity: float = 1.0
    ghost: bool = True
    radius: np.ndarray | None = None
    data: dict[str, np.ndarray] = field(default_factory=dict)
    template: Any = None  # PolyData whose points are x0 (solids)


@dataclass
class ModeScene:
    """The drawable geometry of one mode, deformable by any factor of the drawn amplitude.

    Attributes
    ----------
    parts : list
        The pieces (beam tubes, rigid links, masses, supports, decorations).
    scale : float
        Multiplier applied to the (mass-normalised) mode shape for the drawn deformation.
    u_max : float
        Largest drawn displacement at ``factor=1`` [m]; colours are ``|u| / u_max``.
    diagonal : float
        Diagonal of the undeformed bounding box [m].
    title : str
    n_sides : int
        Facets around each tube.
    """

    parts: list[_Part]
    scale: float
    u_max: float
    diagonal: float
    title: str
    n_sides: int = 16

    def meshes(self, factor: float = 1.0) -> dict[str, Any]:
        """Deformed meshes at ``factor`` times the drawn amplitude.

        Each mesh carries the point array ``"|u| / max"`` (displacement magnitude over the
        largest displacement of the mode at ``factor=1``); tubes also carry ``"sample"``,
        the index of the centreline point each surface point belongs to (row-major over
        the part's ``x0``), and beam tubes ``"beam_id"``, the element id of every point.
        """
        return {p.name: self._mesh(p, factor) for p in self.parts}

    def ghost_meshes(self) -> dict[str, Any]:
        """The undeformed meshes of the moving parts."""
        return {p.name: self._mesh(p, 0.0) for p in self.parts if p.ghost}

    def _mesh(self, part: _Part, factor: float):
        u = factor * part.u
        mag = np.linalg.norm(u, axis=-1) / self.u_max if self.u_max > 0 else np.zeros(u.shape[:-1])
        if part.kind == "tubes":
            return _tubes(part.x0 + u, part.radius, {SCALAR_NAME: mag, **part.data}, self.n_sides)
        mesh = part.template.copy()
        mesh.points = part.x0 + u
        mesh.point_data[SCALAR_NAME] = mag
        return mesh

    def bounds(self) -> tuple[float, ...]:
        """Bounds covering the ghost and both extremes of the motion."""
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        for p in self.parts:
            x = p.x0.reshape(-1, 3)
            u = np.abs(p.u.reshape(-1, 3))
            pad = 0.0 if p.radius is None else float(np.max(p.radius))
            lo = np.minimum(lo, (x - u).min(axis=0) - pad)
            hi = np.maximum(hi, (x + u).max(axis=0) + pad)
        return (lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])


def mode_scene(model: Model, modes, mode: int = 1, *, scale: float | None = None,
               amplitude: float = DEFAULT_AMPLITUDE, decorations: Sequence = (),
               label: str | None = None, labels: Sequence[str] | None = None,
               n_samples: int = 9, n_sides: int = 16, show_supports: bool = True) -> ModeScene:
    """Build the deformable geometry of ``mode`` (1-based) without rendering it.

    Parameters
    ----------
    model : fem.Model
    modes : Modes-like
        ``shapes_full`` (6 n_nodes, n_modes), ``frequencies_hz`` (n_modes,), ``node_ids``
        (n_nodes,); optional ``labels``.
    mode : int
        1-based mode number.
    scale : float, optional
        Multiplier on the mode shape for drawing (model units per shape unit). Default:
        chosen so the largest displacement is ``amplitude`` times the bounding-box diagonal.
    amplitude : float
        Used when ``scale`` is None.
    decorations : sequence of Decoration or (mesh, colour, node) tuples
    label : str, optional
        Text after mode number and frequency in the title; default ``labels[mode - 1]``,
        then ``modes.labels[mode - 1]`` when present.
    labels : sequence of str, optional
        One text per mode (``label`` of mode ``mode`` when ``label`` is not given).
    n_samples : int
        Points per beam element for the Hermite interpolation (>= 2).
    n_sides : int
        Facets around each tube.
    show_supports : bool
        Draw supported nodes as small dark cubes.
    """
    # Long: one scene assembled part by part (beams, springs, masses, rigid bodies,
    # decorations), each part a few lines over the same displacement field.
    import pyvista as pv  # deferred: VTK takes ~1 s to load; only drawing needs it

    if n_samples < 2:
        raise RenderError(f"n_samples must be at least 2, got {n_samples}")
    if not (scale is None or (np.isfinite(scale) and scale >= 0)):
        raise RenderError(f"scale must be a finite number >= 0, got {scale!r}")
    if not (np.isfinite(amplitude) and amplitude >= 0):
        raise RenderError(f"amplitude must be a finite number >= 0, got {amplitude!r}")
    u_nodes = node_displacements(model, modes, mode)
    title = _mode_title(modes, mode, label, labels)
    xyz = model.xyz
    decorations = [_as_decoration(d) for d in decorations]
    dec_meshes = [pv.wrap(d.mesh) if not isinstance(d.mesh, pv.DataSet) else d.mesh for d in decorations]
    extent_pts = [xyz] + [np.asarray(m.points) for m in dec_meshes]
    allpts = np.concatenate(extent_pts) if extent_pts else np.zeros((1, 3))
    diagonal = float(np.linalg.norm(allpts.max(axis=0) - allpts.min(axis=0))) or 1.0

    beams = model.beams
    parts: list[_Part] = []
    xi = np.linspace(0.0, 1.0, n_samples)
    radii = np.zeros(0)
    if len(beams):
        ends = model.index_of(beams.nodes, what=lambda k: f"beam {beams.ids[k // 2]}")
        x, u = hermite_beam_displacements(xyz[ends[:, 0]], xyz[ends[:, 1]], u_nodes[ends[:, 0]],
                                          u_nodes[ends[:, 1]], xi, rod=beams.rod)
        radii = equivalent_radius(beams.A, beams.Iy, beams.Iz, beams.J, beams.rod)
        # A section whose properties are not a solid's (a deck's placeholder I, a stiffened
        # dummy member) would hide the model: such tubes fall back to the area's circle,
        # and the thinnest stay visible.
        too_big = radii > 0.05 * diagonal
        radii[too_big] = np.sqrt(beams.A[too_big] / math.pi)
        radii = np.clip(radii, 1e-3 * diagonal, 0.05 * diagonal)
        parts.append(_Part("beams", "tubes", x, u, radius=radii,
                           data={"beam_id": beams.ids.astype(np.int64)}))
    typical = float(np.median(radii)) if radii.size else 4e-3 * diagonal

    links = [(rb.master, s) for rb in model.rigid_bodies for s in rb.slaves]
    if links:
        ln = model.index_of(np.array(links, np.int64), what="a rigid body")
        # Linear interpolation is exact for a rigid link: u(x) = u_m + theta_m x (x - x_m).
        x, u = hermite_beam_displacements(xyz[ln[:, 0]], xyz[ln[:, 1]], u_nodes[ln[:, 0]],
                                          u_nodes[ln[:, 1]], np.array([0.0, 1.0]),
                                          rod=np.ones(len(ln), bool))
        parts.append(_Part("links", "tubes", x, u, radius=np.full(len(ln), 0.45 * typical)))

    pm = model.point_masses
    has_mass = pm.mass > 0  # inertia-only entries (rotary inertia top-ups) are not objects
    if has_mass.any():
        idx = model.index_of(pm.nodes[has_mass], what="a point mass")
        centres = xyz[idx] + pm.offset[has_mass]
        tpl = _replicate(pv.Sphere(radius=1.0, theta_resolution=16, phi_resolution=12),
                         centres, np.full(len(idx), 1.8 * typical))
        per = tpl.n_points // len(idx)
        tpl.point_data["Normals"] = (np.asarray(tpl.points) - np.repeat(centres, per, axis=0)) / (1.8 * typical)
        node_of_point = np.repeat(idx, per)
        parts.append(_Part("masses", "solid", np.asarray(tpl.points),
                           _rigid_motion(u_nodes[node_of_point], xyz[node_of_point], np.asarray(tpl.points)),
                           template=tpl))

    if show_supports and model.has_supports:
        fixed = np.flatnonzero(model.fixed_mask().any(axis=1))
        if fixed.size:
            tpl = _with_normals(_replicate(pv.Cube(x_length=1, y_length=1, z_length=1), xyz[fixed],
                                           np.full(fixed.size, 3.0 * typical)))
            parts.append(_Part("supports", "solid", np.asarray(tpl.points), np.zeros((tpl.n_points, 3)),
                               color=SUPPORT_COLOR, ghost=False, template=tpl))

    for k, (dec, mesh) in enumerate(zip(decorations, dec_meshes)):
        mesh = _with_normals(mesh)
        pts = np.asarray(mesh.points, float)
        name = f"decoration {k}: {dec.name}" if dec.name else f"decoration {k}"
        if dec.node is None:
            u = np.zeros_like(pts)
        else:
            i = int(model.index_of(np.array([dec.node]), what=name)[0])
            u = _rigid_motion(np.broadcast_to(u_nodes[i], (len(pts), 6)), xyz[i], pts)
        parts.append(_Part(name, "solid", pts, u, color=dec.color, opacity=float(dec.opacity),
                           ghost=dec.node is not None, template=mesh))

    if not parts:
        raise RenderError("the model has nothing to draw (no beams, rigid bodies, masses or decorations)")
    u_max_unit = max((float(np.linalg.norm(p.u, axis=-1).max()) if p.u.size else 0.0) for p in parts)
    if scale is None:
        scale = amplitude * diagonal / u_max_unit if u_max_unit > 0 else 0.0
    for p in parts:
        p.u = scale * p.u
    return ModeScene(parts, float(scale), scale * u_max_unit, diagonal, title, n_sides)


def _rigid_motion(u6: np.ndarray, x_node: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Small rigid motion of points ``x`` (k, 3) with node displacement ``u6`` (k, 6) at ``x_node``."""
    return u6[..., :3] + np.cross(u6[..., 3:], x - x_node)


def default_cmap():
    """Turbo without its darkest tenth, so parts at rest read as blue, not black."""
    import matplotlib  # deferred: ~0.6 s to load; only a drawing needs the colour map
    from matplotlib.colors import ListedColormap  # (as above)

    return ListedColormap(matplotlib.colormaps["turbo"](np.linspace(0.1, 1.0, 256)), name="turbo_light")
