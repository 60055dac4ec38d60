"""The model side: a Ritz-reduced wall basis for the global search, and the model's modes,
wall sensitivities and sensor shapes at given walls."""

from __future__ import annotations

import numpy as np

from trussid.fem.modal import dense_modes
from trussid.testbed.walls import WallBasis, wall_matrices, wall_modes
from trussid.testbed.sensitivity import eigenvalue_sensitivities

__all__ = ["reduced_wall_basis", "ModelModes"]


def reduced_wall_basis(basis: WallBasis, n_vectors: int = 40, designs=(1.0, 0.85, 1.15)):
    """A Ritz-reduced copy of a :class:`trussid.testbed.walls.WallBasis`.

    The reduced DOFs are the amplitudes of ``V``: the lowest ``n_vectors`` modes of the
    model at each of ``designs`` (all walls scaled by the factor), orthonormalised; the
    basis is projected on them by :meth:`WallBasis.projected`, so the public
    :func:`trussid.testbed.walls.wall_modes` and
    :func:`trussid.testbed.sensitivity.eigenvalue_sensitivities` work on it unchanged. The
    basis stays affine in the tube properties, hence exact in how the walls enter; its only
    error is the Ritz error of the fixed subspace. Modes at the scaled designs are included
    because a strut's bending shape changes with its wall (its share of the adapter mass and
    stiffness): with the nominal modes alone the error was 4e-4 relative on the lowest 24
    modes of the calibrated testbed for walls within +-15 %, with the three designs 3e-7.

    Returns
    -------
    reduced : trussid.testbed.walls.WallBasis
    V : (n, r) float
        The projection (reduced shapes ``q`` expand to ``V q``).
    """
    k = min(int(n_vectors), basis.n)
    cols = []
    for d in designs:
        w = np.clip(np.asarray(basis.walls_ref) * d, 0.02 * basis.r_out, 0.98 * basis.r_out)
        K, M = wall_matrices(basis, w)
        cols.append(dense_modes(K, M, k, overwrite=True)[1])
    U, sv, _ = np.linalg.svd(np.hstack(cols), full_matrices=False)
    V = U[:, sv > 1e-10 * sv[0]]  # drop (numerically) repeated directions
    return basis.projected(V), V


class ModelModes:
    """Frequencies [Hz], wall sensitivities ``df/dt`` [Hz/m] and sensor shapes of a (full
    or reduced) wall basis at given walls, with a one-entry cache (the residual and its
    Jacobian ask at the same walls) and a count of the eigen-solutions.

    Parameters
    ----------
    basis : WallBasis
    n_modes : int
        Lowest modes computed.
    sensor_rows : (p, n) float, optional
        Sensor outputs per DOF of ``basis`` (shapes are then ``sensor_rows @ X``).
    """

    def __init__(self, basis: WallBasis, n_modes: int, sensor_rows: np.ndarray | None):
        self.basis, self.n_modes, self.rows = basis, n_modes, sensor_rows
        self._key, self._val = None, None
        self.evaluations = 0

    def __call__(self, walls):
        """``(f, dfdt, shapes)`` at ``walls`` (shapes None without sensors)."""
        w = np.asarray(walls, float)
        key = w.tobytes()
        if key != self._key:
            f, X = wall_modes(self.basis, w, self.n_modes)
            lam = (2 * np.pi * f) ** 2
            dfdt = eigenvalue_sensitivities(self.basis, w, lam, X) / (
                8 * np.pi**2 * np.maximum(f, 1e-300))[:, None]
            shapes = None if self.rows is None else self.rows @ X
            self._key, self._val = key, (f, dfdt, shapes)
            self.evaluations += 1
        return self._val
