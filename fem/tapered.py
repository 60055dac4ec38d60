"""Frame elements whose section varies along the element (NASTRAN tapered PBEAM/PBEAML).

The section is given as a function of ``xi = x / L`` on the segments between stations
(PBEAM: properties linear between stations; PBEAML: dimensions linear, the properties
following from them). The element is integrated along its length, not subdivided:

- stiffness by the flexibility method, which is exact for a straight element loaded at its
  ends: the end-B flexibility of the element clamped at end A is integrated (axial
  ``int dx / E A``, torsion ``int dx / G J``, bending ``int (L - x)^k / E I`` for k = 0, 1, 2,
  shear ``int dx / G A_s``), inverted, and completed to 12 x 12 by equilibrium. For a
  uniform section it is the textbook element of :func:`trussid.fem.elements.frame_matrices`
  (Euler-Bernoulli or Timoshenko);
- mass with the uniform element's shape functions weighted by the varying mass per length
  (consistent: linear axial and torsion, cubic Hermite bending without rotary inertia, as
  NASTRAN's coupled CBEAM mass; lumped: the mass and the torsional inertia split between
  the ends as a linearly varying load is, ``int m (1 - xi)`` and ``int m xi``).

Integrals are Gauss-Legendre on each segment between stations (:data:`GAUSS_POINTS` per
segment; the integrands are smooth there), so a kink at a station is integrated exactly.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from trussid.fem.elements import XY_PLANE, XZ_PLANE, XZ_SIGN
from trussid.fem.errors import ModelError
from trussid.fem.properties import SectionArrays

__all__ = ["GAUSS_POINTS", "tapered_frame_matrices"]

#: Gauss-Legendre points per segment between stations. The error of an n-point rule on
#: ``1 / I(xi)`` with I linear from I_a to I_b falls like ``((r - 1) / (r + 1))^(2 n)``,
#: r = I_b / I_a: 24 points give 1e-14 at r = 2 and 5e-11 at r = 8 (a PBEAML whose depth
#: doubles has I ratio 8).
GAUSS_POINTS = 24


def _gauss(breaks: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights on [0, 1], ``n`` per segment of ``breaks``."""
    t, w = np.polynomial.legendre.leggauss(n)
    a, b = breaks[:-1, None], breaks[1:, None]
    xi = (0.5 * (b - a) * (t + 1.0) + a).ravel()
    wt = (0.5 * (b - a) * w).ravel()
    return xi, wt


def tapered_frame_matrices(L, breaks, section_at: Callable[[np.ndarray], SectionArrays], E: float, G: float,
                           rho: float, *, nsm_at: Callable[[np.ndarray], np.ndarray] | None = None,
                           theory: str = "euler-bernoulli", mass: str = "consistent",
                           torsion_lumped: bool = True, label: str = "tapered beam"
                           ) -> tuple[np.ndarray, np.ndarray]:
    """Local stiffness and mass of ``n`` elements sharing one tapered property, (n, 12, 12).

    Parameters
    ----------
    L : (n,) float
        Element lengths [m].
    breaks : (s,) float
        Stations as ``x / L`` from 0 to 1, ascending (the section may kink there).
    section_at : callable
        ``section_at(xi)`` for an array ``xi`` returns the section there as
        :class:`~trussid.fem.SectionArrays` (each field one value or one per ``xi``): ``A``,
        ``Iy``, ``Iz``, ``J`` [m^2, m^4], ``Asy``, ``Asz`` [m^2, inf for none], in element
        axes (``Iz`` bends in the x-y plane).
    E, G, rho : float
        Material [Pa, Pa, kg/m^3].
    nsm_at : callable, optional
        ``nsm_at(xi)``: non-structural mass per length at ``xi`` [kg/m]; default none.
    theory : {"euler-bernoulli", "timoshenko"}
        Timoshenko adds the shear flexibility ``int dx / G A_s``.
    mass : {"consistent", "lumped"}
    torsion_lumped : bool
        Lumped mass with the section's torsional inertia at the ends (NASTRAN's lumped
        CBEAM), or without (its CBAR).
    label : str
        For messages.

    Returns
    -------
    K, M : (n, 12, 12) float
        In element axes (DOFs ux, uy, uz, rx, ry, rz of end A, then end B).
    """
    L = np.atleast_1d(np.asarray(L, float))
    breaks = np.asarray(breaks, float)
    if breaks[0] != 0.0 or breaks[-1] != 1.0 or not (np.diff(breaks) > 0).all():
        raise ModelError(f"{label}: stations must ascend from x/L = 0 to 1, got {breaks.tolist()}")
    if theory not in ("euler-bernoulli", "timoshenko"):
        raise ModelError(f"unknown beam theory {theory!r}")
    xi, w = _gauss(breaks, GAUSS_POINTS)
    # checked at the stations too: a section vanishing at an end is positive at every
    # Gauss point, and its integrals diverge
    at = np.r_[breaks, xi]
    checked = section_at(at)
    for key in ("A", "Iy", "Iz"):
        value = getattr(checked, key)
        if not (np.isfinite(value) & (value > 0)).all():
            raise ModelError(f"{label}: {key} must be positive along the element")
    if not (np.isfinite(checked.J) & (checked.J >= 0)).all():
        raise ModelError(f"{label}: J must be >= 0 along the element")
    s = checked.per_element(len(at))  # the stations, then the Gauss points
    A, Iy, Iz, J, Asy, Asz = (getattr(s, k)[len(breaks):] for k in ("A", "Iy", "Iz", "J", "Asy", "Asz"))
    nsm = np.zeros(len(xi)) if nsm_at is None else np.broadcast_to(np.asarray(nsm_at(xi), float), xi.shape)
    n = len(L)
    K = np.zeros((n, 12, 12))

    def spring(i, j, k):
        K[:, i, i] += k
        K[:, j, j] += k
        K[:, i, j] -= k
        K[:, j, i] -= k

    spring(0, 6, E / (L * np.sum(w / A)))
    # J = 0 somewhere: no torsional stiffness (NASTRAN's default J is 0)
    spring(3, 9, 0.0 if (J == 0).any() else G / (L * np.sum(w / J)))
    timo = theory == "timoshenko"
    for idx, inertia, shear, sign in ((XY_PLANE, Iz, Asy, np.ones(4)), (XZ_PLANE, Iy, Asz, XZ_SIGN)):
        c = [np.sum(w * (1.0 - xi) ** k / inertia) for k in range(3)]
        shear_flex = np.sum(w / shear) if timo else 0.0
        # end-B flexibility of the element clamped at A, (deflection, rotation) per (force, moment)
        F = np.empty((n, 2, 2))
        F[:, 0, 0] = L**3 * c[2] / E + L * shear_flex / G
        F[:, 0, 1] = F[:, 1, 0] = L**2 * c[1] / E
        F[:, 1, 1] = L * c[0] / E
        Kbb = np.linalg.inv(F)
        H = np.zeros((n, 2, 2))          # end-A forces from end-B forces (equilibrium)
        H[:, 0, 0] = H[:, 1, 1] = -1.0
        H[:, 1, 0] = -L
        Hk = H @ Kbb
        blk = np.block([[Hk @ H.transpose(0, 2, 1), Hk], [Kbb @ H.transpose(0, 2, 1), Kbb]])
        K[:, idx[:, None], idx[None, :]] += blk * np.outer(sign, sign)

    M = _mass(L, xi, w, rho * A + nsm, rho * (Iy + Iz), mass, torsion_lumped)
    return 0.5 * (K + K.transpose(0, 2, 1)), M


def _mass(L: np.ndarray, xi: np.ndarray, w: np.ndarray, m: np.ndarray, polar: np.ndarray, mass: str,
          torsion_lumped: bool) -> np.ndarray:
    """(n, 12, 12) element-axes mass of elements of lengths ``L`` whose mass per length ``m``
    [kg/m] and torsional inertia per length ``polar`` [kg m] are sampled at the Gauss points
    ``xi`` (weights ``w``); see :func:`tapered_frame_matrices`."""
    n = len(L)
    M = np.zeros((n, 12, 12))
    if mass == "lumped":
        ends = (np.sum(w * m * (1.0 - xi)), np.sum(w * m * xi))
        for e, share in enumerate(ends):
            for k in (0, 1, 2):
                M[:, 6 * e + k, 6 * e + k] = share * L
        if torsion_lumped:
            M[:, 3, 3] = np.sum(w * polar * (1.0 - xi)) * L
            M[:, 9, 9] = np.sum(w * polar * xi) * L
    elif mass == "consistent":
        lin = np.stack([1.0 - xi, xi])                        # (2, g)
        axial = (lin * w * m) @ lin.T
        tors = (lin * w * polar) @ lin.T
        for i, j in ((0, 6), (3, 9)):
            blk = axial if i == 0 else tors
            idx = np.array([i, j])
            M[:, idx[:, None], idx[None, :]] += blk[None] * L[:, None, None]
        # cubic Hermite shapes for (v_A, theta_A, v_B, theta_B), the rotations per unit L
        N = np.stack([1 - 3 * xi**2 + 2 * xi**3, xi - 2 * xi**2 + xi**3, 3 * xi**2 - 2 * xi**3, -xi**2 + xi**3])
        unit = (N * w * m) @ N.T                                # int m N_i N_j dxi, rotations per L
        scale = np.stack([np.ones(n), L, np.ones(n), L], 1)     # (n, 4)
        bend = unit[None] * L[:, None, None] * scale[:, :, None] * scale[:, None, :]
        for idx, sign in ((XY_PLANE, np.ones(4)), (XZ_PLANE, XZ_SIGN)):
            M[:, idx[:, None], idx[None, :]] += bend * np.outer(sign, sign)
    else:
        raise ModelError(f"unknown mass formulation {mass!r}")
    return M
