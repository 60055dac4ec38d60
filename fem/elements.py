"""Element matrices of the 2-node 3-D frame element, for all elements at once.

Local DOF order per element (12): ``u, v, w, rx, ry, rz`` at end A, then the same at end B,
in the element's local axes: x from A to B, y in the plane of x and the orientation vector
(NASTRAN's v vector), z = x cross y. ``Iy`` (about local y) governs bending in the x-z plane
(displacement w), ``Iz`` bending in the x-y plane (displacement v).

Bending uses the shear-deformable (Timoshenko) cubic element of Przemieniecki, *Theory of
Matrix Structural Analysis* (1968), with ``phi = 12 E I / (G As L^2)``; ``phi = 0`` (Euler-
Bernoulli, or an infinite shear area) gives the classical Hermite cubic. The consistent mass
is the matching Przemieniecki matrix: translational inertia, plus rotary inertia of the
section (``rho I``) in the Timoshenko theory only, so the Euler-Bernoulli element
reproduces classical (Bernoulli-Euler) beam theory, which neglects rotary inertia.

The lumped mass puts half of each element's translational mass (structural + non-structural)
at each end, in all three directions, with *no* rotary inertia. This is NASTRAN's lumped
mass for CBAR/CBEAM/CROD (its default, ``PARAM,COUPMASS`` absent), so decks read with it
reproduce NASTRAN's frequencies; the massless rotations are handled by the modal solver
(static condensation in the dense path, a semi-definite mass in shift-invert).

Rod elements (CROD/CONROD) carry axial and torsional stiffness only; their mass is
translational (consistent: linear interpolation in all three directions; lumped: halves).

These are hand-written rather than taken from a library because no maintained Python
library exposes vectorised 3-D frame element matrices; OpenSeesPy (used as the benchmark
comparator) assembles internally and gives no array access.
"""

from __future__ import annotations

import numpy as np

from trussid.fem.errors import ModelError

__all__ = ["local_axes", "frame_matrices", "to_global", "check_beam_properties", "XY_PLANE", "XZ_PLANE",
           "XZ_SIGN"]

#: Local DOF indices of the x-y bending plane (v, rz at A; v, rz at B) ...
XY_PLANE = np.array([1, 5, 7, 11])
#: ... and of the x-z plane (w, ry at A; w, ry at B).
XZ_PLANE = np.array([2, 4, 8, 10])
#: In the x-z plane a positive rotation ry is -dw/dx: flip the rotation signs.
XZ_SIGN = np.array([1.0, -1.0, 1.0, -1.0])


def local_axes(xyz_a: np.ndarray, xyz_b: np.ndarray, orient: np.ndarray,
               ids: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Element lengths and rotation matrices from end coordinates and orientation vectors.

    Parameters
    ----------
    xyz_a, xyz_b : (n, 3) float
        Coordinates of ends A and B, global axes [m].
    orient : (n, 3) float
        Orientation vectors (NASTRAN v vector), global axes.
    ids : (n,) int, optional
        Element ids, for error messages.

    Returns
    -------
    L : (n,) float
        Lengths [m].
    R : (n, 3, 3) float
        Rows are the local x, y, z axes in global coordinates (``local = R @ global``).

    Raises
    ------
    ModelError
        Naming the first element of zero length or whose orientation vector is zero or
        parallel to its axis.
    """
    ids = np.arange(len(xyz_a)) if ids is None else np.asarray(ids)
    d = np.asarray(xyz_b, float) - np.asarray(xyz_a, float)
    L = np.linalg.norm(d, axis=1)
    scale = np.maximum(np.linalg.norm(xyz_a, axis=1), np.linalg.norm(xyz_b, axis=1))
    bad = ~(L > 1e-12 * np.maximum(scale, 1e-300))
    if bad.any():
        raise ModelError(f"element {ids[bad][0]}: zero length (its two nodes coincide)")
    ex = d / L[:, None]
    v = np.asarray(orient, float)
    vn = np.linalg.norm(v, axis=1)
    # The part of v normal to the axis fixes local y; if it is (numerically) nothing, v is
    # parallel to the element and the section's orientation is undefined.
    vy = v - np.einsum("ij,ij->i", v, ex)[:, None] * ex
    vyn = np.linalg.norm(vy, axis=1)
    bad = ~(vyn > 1e-6 * vn)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        what = "is zero" if not vn[i] > 0 else "is parallel to the element axis"
        raise ModelError(f"element {ids[i]}: orientation vector {v[i].tolist()} {what}")
    ey = vy / vyn[:, None]
    ez = np.cross(ex, ey)
    return L, np.stack([ex, ey, ez], axis=1)


def _bending_block(L, phi):
    """Stiffness pattern of one bending plane, (n, 4, 4), to be scaled by E I."""
    c = 1.0 / ((1.0 + phi) * L**3)
    k = np.empty((len(L), 4, 4))
    a, b, p = 12.0, 6.0 * L, phi
    k[:, 0, 0] = k[:, 2, 2] = a
    k[:, 0, 2] = k[:, 2, 0] = -a
    k[:, 0, 1] = k[:, 1, 0] = k[:, 0, 3] = k[:, 3, 0] = b
    k[:, 1, 2] = k[:, 2, 1] = k[:, 2, 3] = k[:, 3, 2] = -b
    k[:, 1, 1] = k[:, 3, 3] = (4.0 + p) * L**2
    k[:, 1, 3] = k[:, 3, 1] = (2.0 - p) * L**2
    return k * c[:, None, None]


def _translational_mass_block(L, phi):
    """Translational consistent mass of one bending plane, (n, 4, 4), per unit mass/length."""
    p = phi
    m = np.empty((len(L), 4, 4))
    m11 = 13 / 35 + 7 * p / 10 + p**2 / 3
    m12 = (11 / 210 + 11 * p / 120 + p**2 / 24) * L
    m13 = 9 / 70 + 3 * p / 10 + p**2 / 6
    m14 = -(13 / 420 + 3 * p / 40 + p**2 / 24) * L
    m22 = (1 / 105 + p / 60 + p**2 / 120) * L**2
    m24 = -(1 / 140 + p / 60 + p**2 / 120) * L**2
    m[:, 0, 0] = m[:, 2, 2] = m11
    m[:, 0, 1] = m[:, 1, 0] = m12
    m[:, 2, 3] = m[:, 3, 2] = -m12
    m[:, 0, 2] = m[:, 2, 0] = m13
    m[:, 0, 3] = m[:, 3, 0] = m14
    m[:, 1, 2] = m[:, 2, 1] = -m14
    m[:, 1, 1] = m[:, 3, 3] = m22
    m[:, 1, 3] = m[:, 3, 1] = m24
    return m * (L / (1.0 + p) ** 2)[:, None, None]


def _rotary_mass_block(L, phi):
    """Rotary-inertia consistent mass of one bending plane, (n, 4, 4), per unit rho*I."""
    p = phi
    m = np.empty((len(L), 4, 4))
    r12 = (1 / 10 - p / 2) * L
    m[:, 0, 0] = m[:, 2, 2] = 6 / 5
    m[:, 0, 2] = m[:, 2, 0] = -6 / 5
    m[:, 0, 1] = m[:, 1, 0] = m[:, 0, 3] = m[:, 3, 0] = r12
    m[:, 1, 2] = m[:, 2, 1] = m[:, 2, 3] = m[:, 3, 2] = -r12
    m[:, 1, 1] = m[:, 3, 3] = (2 / 15 + p / 6 + p**2 / 3) * L**2
    m[:, 1, 3] = m[:, 3, 1] = (-1 / 30 - p / 6 + p**2 / 6) * L**2
    return m / (((1.0 + p) ** 2) * L)[:, None, None]


def _put(mat, idx, block):
    mat[:, idx[:, None], idx[None, :]] += block


def frame_matrices(L, A, Iy, Iz, J, E, G, rho, *, nsm=0.0, Asy=np.inf, Asz=np.inf, rod=False,
                   R=None, theory: str = "euler-bernoulli", mass: str = "consistent"
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass matrices of ``n`` frame elements, (n, 12, 12) each.

    Parameters
    ----------
    L : (n,) float
        Lengths [m].
    A, Iy, Iz, J : (n,) float
        Area [m^2], second moments about local y and z, torsion constant [m^4].
    E, G, rho : (n,) float
        Young's and shear moduli [Pa], density [kg/m^3].
    nsm : float or (n,) float
        Non-structural mass per length [kg/m]: translational inertia only.
    Asy, Asz : float or (n,) float
        Shear areas along local y and z [m^2] (Timoshenko); ``inf`` = no shear deformation.
    rod : bool or (n,) bool
        Axial and torsional stiffness only, translational mass only.
    R : (n, 3, 3) float, optional
        Rotation matrices from :func:`local_axes`; when given the matrices are returned in
        global axes, otherwise in local axes.
    theory : {"euler-bernoulli", "timoshenko"}
        Timoshenko adds shear flexibility and rotary inertia.
    mass : {"consistent", "lumped"}

    Returns
    -------
    K : (n, 12, 12) float
        Stiffness [N/m, N, N m/rad].
    M : (n, 12, 12) float
        Mass [kg, kg m, kg m^2].
    """
    L = np.asarray(L, float)
    n = len(L)
    A, Iy, Iz, J, E, G, rho, nsm, Asy, Asz = (np.broadcast_to(np.asarray(v, float), (n,))
                                               for v in (A, Iy, Iz, J, E, G, rho, nsm, Asy, Asz))
    rod = np.broadcast_to(np.asarray(rod, bool), (n,))
    beam = (~rod).astype(float)[:, None, None]
    if rod.any():
        # A rod's bending properties are meaningless (often 0 or NaN from a deck): neutralise
        # them so that no 0/0 or NaN * 0 reaches the rod's matrices.
        Iy, Iz = np.where(rod, 0.0, Iy), np.where(rod, 0.0, Iz)
        Asy, Asz = np.where(rod, np.inf, Asy), np.where(rod, np.inf, Asz)
    timo = theory == "timoshenko"
    if theory not in ("euler-bernoulli", "timoshenko"):
        raise ModelError(f"unknown beam theory {theory!r}")
    if mass not in ("consistent", "lumped"):
        raise ModelError(f"unknown mass formulation {mass!r}")

    # phi = 12 E I / (G As L^2); As = inf gives exactly 0, and Euler-Bernoulli forces 0.
    if timo:
        phi_y = 12.0 * E * Iz / (G * Asy * L**2)  # shear along y, x-y plane
        phi_z = 12.0 * E * Iy / (G * Asz * L**2)  # shear along z, x-z plane
    else:
        phi_y = phi_z = np.zeros(n)

    K = np.zeros((n, 12, 12))
    ax = (E * A / L)[:, None, None] * np.array([[1.0, -1.0], [-1.0, 1.0]])
    _put(K, np.array([0, 6]), ax)
    tor = (G * J / L)[:, None, None] * np.array([[1.0, -1.0], [-1.0, 1.0]])
    _put(K, np.array([3, 9]), tor)
    sgn = np.outer(XZ_SIGN, XZ_SIGN)
    _put(K, XY_PLANE, beam * E[:, None, None] * Iz[:, None, None] * _bending_block(L, phi_y))
    _put(K, XZ_PLANE, beam * E[:, None, None] * Iy[:, None, None] * _bending_block(L, phi_z) * sgn)

    m_len = rho * A + nsm  # translational mass per length [kg/m]
    M = np.zeros((n, 12, 12))
    if mass == "lumped":
        half = 0.5 * m_len * L
        for k in (0, 1, 2, 6, 7, 8):
            M[:, k, k] = half
    else:
        lin = (m_len * L / 6.0)[:, None, None] * np.array([[2.0, 1.0], [1.0, 2.0]])
        _put(M, np.array([0, 6]), lin)
        # Rods: translations interpolated linearly in all three directions.
        rodf = rod.astype(float)[:, None, None]
        _put(M, np.array([1, 7]), rodf * lin)
        _put(M, np.array([2, 8]), rodf * lin)
        # Beams: torsional inertia of the section (polar moment Iy + Iz) ...
        tor_m = (rho * (Iy + Iz) * L / 6.0)[:, None, None] * np.array([[2.0, 1.0], [1.0, 2.0]])
        _put(M, np.array([3, 9]), beam * tor_m)
        # ... and the cubic (Timoshenko-consistent) translational inertia of each plane.
        _put(M, XY_PLANE, beam * m_len[:, None, None] * _translational_mass_block(L, phi_y))
        _put(M, XZ_PLANE, beam * m_len[:, None, None] * _translational_mass_block(L, phi_z) * sgn)
        if timo:
            _put(M, XY_PLANE, beam * (rho * Iz)[:, None, None] * _rotary_mass_block(L, phi_y))
            _put(M, XZ_PLANE, beam * (rho * Iy)[:, None, None] * _rotary_mass_block(L, phi_z) * sgn)

    if R is not None:
        K = to_global(K, R)
        M = to_global(M, R)
    return K, M


def to_global(mat: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Rotate (n, 12, 12) local element matrices to global axes: ``Lambda^T mat Lambda``.

    ``Lambda`` is block-diagonal with four copies of ``R`` (rows = local axes). Done as two
    batched (48 x 3) @ (3 x 3) products, which is ~20x faster than an equivalent einsum.
    """
    n = len(mat)
    right = (mat.reshape(n, 48, 3) @ R).reshape(n, 12, 12)  # mat Lambda
    # Lambda^T (mat Lambda) = ((mat Lambda)^T Lambda)^T
    return (right.transpose(0, 2, 1).reshape(n, 48, 3) @ R).reshape(n, 12, 12).transpose(0, 2, 1)


def check_beam_properties(beams, theory: str = "euler-bernoulli") -> None:
    """Raise :class:`ModelError` naming the first element with a non-physical property.

    :class:`~trussid.fem.Section` and :class:`~trussid.fem.Material` validate themselves;
    per-element arrays (:class:`~trussid.fem.SectionArrays`, e.g. from the NASTRAN reader)
    may hold zeros that are legal for some elements and theories only, so their values are
    checked here, per element.
    """
    checks = [("E", beams.E), ("G", beams.G), ("A", beams.A)]
    frame = ~np.asarray(beams.rod, bool)
    for key, value in checks:
        value = np.asarray(value, float)
        bad = ~(np.isfinite(value) & (value > 0))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ModelError(f"element {beams.ids[i]} ({beams.labels[i]}): {key} must be positive "
                             f"and finite, got {float(value[i])!r}")
    # Zero density (a massless element: all mass in point masses, as in aeroelastic stick
    # models), zero second moments and J = 0 (NASTRAN's default: no torsional stiffness)
    # are legal: they leave DOFs without mass or stiffness, which AUTOSPC, the modal solver
    # (massless DOFs) or the mechanism check handle, each with its own message.
    for key, value in (("rho", beams.rho), ("Iy", np.where(frame, beams.Iy, 1.0)),
                       ("Iz", np.where(frame, beams.Iz, 1.0))):
        value = np.asarray(value, float)
        bad = ~(np.isfinite(value) & (value >= 0))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ModelError(f"element {beams.ids[i]} ({beams.labels[i]}): {key} must be >= 0 "
                             f"and finite, got {float(value[i])!r}")
    all_j = np.asarray(beams.J, float)
    bad = ~(np.isfinite(all_j) & (all_j >= 0))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ModelError(f"element {beams.ids[i]} ({beams.labels[i]}): J must be >= 0, got {float(all_j[i])!r}")
    nsm = np.asarray(beams.nsm, float)
    bad = ~(np.isfinite(nsm) & (nsm >= 0))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ModelError(f"element {beams.ids[i]} ({beams.labels[i]}): non-structural mass must be >= 0, "
                         f"got {float(nsm[i])!r}")
    if theory == "timoshenko":
        for key in ("Asy", "Asz"):
            value = np.asarray(getattr(beams, key), float)
            bad = frame & ~(value > 0)  # inf allowed (no shear deformation)
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise ModelError(f"element {beams.ids[i]} ({beams.labels[i]}): {key} must be positive "
                                 f"(inf for no shear deformation), got {float(value[i])!r}")
