"""Eigenvalue sensitivities of the testbed to each strut's wall thickness (analytic).

For a mass-normalised mode ``phi_j`` with eigenvalue ``lam_j = omega_j^2`` (distinct),

    d lam_j / d t_i = phi_j^T (dK/dt_i - lam_j dM/dt_i) phi_j        (Fox & Kapoor 1968)

The testbed's Euler-Bernoulli frame matrices are linear in the element properties
``(E A, E Iy, E Iz, G J)`` and ``(rho A + nsm, rho (Iy + Iz))``, and every one of those of
strut ``i`` (tube elements, and the tube's share of the composite adapter elements) is
linear in the tube's area ``A_t`` and second moment ``I_t`` (``J_t = 2 I_t``); see
:mod:`trussid.testbed.model`. Hence

    dK/dt_i = A_t'(t_i) dK/dA_t,i + I_t'(t_i) dK/dI_t,i     (and the same for M)

with ``A_t' = 2 pi (r - t)``, ``I_t' = pi (r - t)^3`` and the ``dK/dA_t`` ... matrices the
element matrices evaluated with unit properties (:func:`trussid.testbed.walls.wall_basis`). Nothing
is differenced numerically.

The formula holds for distinct eigenvalues; for a repeated one the derivative of an
individual eigenvalue is not defined (only of the cluster). The walls all differ, so the
testbed's modes are distinct (tests/fem/test_testbed.py); :func:`wall_sensitivities` warns
when two computed frequencies are closer than :data:`CLOSE`.
"""

from __future__ import annotations

import warnings

import numpy as np

from trussid.testbed.model import tube_property_derivatives
from trussid.testbed.walls import WallBasis, wall_basis, wall_modes

#: Relative frequency separation below which a pair of modes is reported as repeated.
CLOSE = 1e-7


def eigenvalue_sensitivities(basis: WallBasis, walls, lam, shapes) -> np.ndarray:
    """``d lam_j / d t_i`` [rad^2/s^2 per m] for mass-normalised reduced ``shapes``.

    Parameters
    ----------
    basis : WallBasis
    walls : (6,) float
        Wall thicknesses at which ``lam`` and ``shapes`` were computed [m].
    lam : (k,) float
        Eigenvalues ``omega^2`` [rad^2/s^2].
    shapes : (n, k) float
        Mass-normalised eigenvectors on the basis's reduced DOFs.

    Returns
    -------
    (k, 6) float
    """
    w = basis.check_walls(walls)
    dA, dI = tube_property_derivatives(basis.r_out, w)
    X = np.asarray(shapes, float)
    if basis.rows.size == basis.n**2:
        # A dense (Ritz-reduced) basis: the pattern sum below would take products over all
        # r^2 entries per mode (20 ms a call at r = 120); dense products take ~1 ms.
        r = basis.n
        qKA, qKI, qMA, qMI = (np.einsum("rk,irc,ck->ik", X, np.asarray(B).reshape(-1, r, r), X,
                                        optimize=True)
                              for B in (basis.KA, basis.KI, basis.MA, basis.MI))
    else:
        # phi^T B phi for every basis matrix B and mode at once: sum over the pattern of
        # B_rc phi_r phi_c.
        P = X[basis.rows] * X[basis.cols]  # (nnz, k)
        qKA, qKI, qMA, qMI = basis.KA @ P, basis.KI @ P, basis.MA @ P, basis.MI @ P  # (6, k)
    lam = np.asarray(lam, float)[None, :]
    d = dA[:, None] * (qKA - lam * qMA) + dI[:, None] * (qKI - lam * qMI)
    return d.T


def wall_sensitivities(basis: WallBasis, walls, n_modes: int = 30) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [Hz] and their derivatives ``d f_j / d t_i`` [Hz/m] at ``walls``.

    Parameters
    ----------
    basis : WallBasis
        From :func:`trussid.testbed.walls.wall_basis`.
    walls : (6,) float
        Wall thicknesses [m].
    n_modes : int

    Returns
    -------
    frequencies_hz : (k,) float
    dfdt : (k, 6) float
        ``d f / d lam = 1 / (8 pi^2 f)``.
    """
    f, X = wall_modes(basis, walls, n_modes)
    lam = (2.0 * np.pi * f) ** 2
    close = np.flatnonzero(np.diff(f) <= CLOSE * np.maximum(f[1:], 1e-300))
    if len(close):
        j = int(close[0])
        warnings.warn(f"modes {j + 1} and {j + 2} have (nearly) equal frequencies {f[j]:.8g} Hz: their "
                      f"individual sensitivities are not defined", RuntimeWarning, stacklevel=2)
    dlam = eigenvalue_sensitivities(basis, walls, lam, X)
    return f, dlam / (8.0 * np.pi**2 * np.maximum(f, 1e-300))[:, None]


def testbed_sensitivities(tbm, n_modes: int = 30) -> tuple[np.ndarray, np.ndarray]:
    """:func:`wall_sensitivities` of a built testbed at its own walls."""
    basis = wall_basis(tbm)
    return wall_sensitivities(basis, basis.walls_ref, n_modes)


__all__ = ["eigenvalue_sensitivities", "wall_sensitivities", "testbed_sensitivities", "CLOSE"]
