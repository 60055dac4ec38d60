"""The one dense generalised symmetric eigen solver of the library, and its size limit.

Below :mod:`trussid.fem.modal`, :mod:`trussid.fem.reduction` (Craig-Bampton's
fixed-interface modes) and the testbed's wall sweeps, which all call it: it needs only
numpy and scipy, so the modules that assemble systems can use it without a cycle.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

__all__ = ["DENSE_MAX_DOF", "dense_modes"]

#: Above this many reduced DOFs ``method="auto"`` (and the testbed's wall sweeps,
#: :func:`trussid.testbed.walls.wall_modes`) switch from dense LAPACK to shift-invert
#: (unless more than a third of the modes are wanted): dense costs O(n^3) whatever the
#: sparsity. The one threshold of the library, at the measured crossover
#: (``benchmarks/bench_dense_crossover.py``, benchmarks/results/dense_crossover.md: CPU
#: for 30 modes of the testbed, one BLAS thread, load ~7 on 2 cores): at 318 DOFs dense and
#: shift-invert tie (solve_modes 22.0 / 22.1 ms, a wall-sweep design 14.9 / 14.2 ms), at 390
#: shift-invert wins the full solution (34.1 / 23.0 ms) and ties the sweep (18.1 / 19.0),
#: at 462 it wins both (37.9 / 17.6, 32.1 / 26.2).
DENSE_MAX_DOF = 350


def dense_modes(K: np.ndarray, M: np.ndarray, n_modes: int | None = None, *, sigma: float = 0.0,
                max_frequency_hz: float | None = None, driver: str = "evr",
                overwrite: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Lowest eigenpairs of a dense reduced pair ``K x = lambda M x``: the one dense solver.

    LAPACK's accuracy is absolute, ``eps`` times the largest eigenvalue of the problem it
    is given. Solved directly, ``K x = lambda M x`` thus gives the lowest modes only
    ``eps * lambda_max / lambda`` relative accuracy, poor when the spectrum spans many
    decades (fine meshes, stiff axial members). So the lowest modes are taken from the
    *inverted* problem ``M x = mu (K - sigma M) x``, ``mu = 1 / (lambda - sigma)``, whose
    error ``eps * mu_max`` falls on the highest modes instead; a singular ``M`` (massless
    DOFs: ``mu = 0``) needs no special treatment.

    Parameters
    ----------
    K, M : (n, n) float
        Symmetric stiffness [N/m] and mass [kg] matrices on the reduced DOFs;
        ``K - sigma M`` must be positive definite, ``M`` positive semi-definite.
    n_modes : int, optional
        Number of lowest modes, found by index (LAPACK's subset driver). Required unless
        ``max_frequency_hz`` is given.
    sigma : float
        Shift [rad^2/s^2] below the lowest eigenvalue (0 when ``K`` is positive definite).
    max_frequency_hz : float, optional
        Instead of a count: every mode at or below this frequency [Hz], found by value
        (which costs LAPACK no more than a count).
    driver : {"evr", "gvx", "gvd", "gv"}
        "evr": Cholesky factor of ``K - sigma M``, LAPACK's reduction to a standard problem
        (``dsygst``) and the MRRR subset solver (``dsyevr``): as fast as "gvx" or faster
        (CPU per solution on the 318-DOF testbed: 11.7 vs 13.2 ms for 20 modes, 11.3 vs
        11.1 ms for 30, medians of 10 alternations under load). "gvx": LAPACK's generalised
        subset driver (bisection and inverse iteration). "gvd"/"gv" compute every pair and
        are sliced (faster when most are wanted).
    overwrite : bool
        Let LAPACK overwrite ``K`` and ``M`` (saves two n x n copies in sweeps).

    Returns
    -------
    lam : (k,) float
        Eigenvalues [rad^2/s^2], ascending.
    X : (n, k) float
        Eigenvectors, ``X.T @ M @ X = I``.

    Raises
    ------
    numpy.linalg.LinAlgError
        ``K - sigma M`` is not positive definite.
    ValueError
        Neither ``n_modes`` nor ``max_frequency_hz``, or an unknown driver.

    Examples
    --------
    Two masses of 1 kg on springs of 1 N/m in a chain from a wall: ``lambda = (3 -+ sqrt 5) / 2``.

    >>> import numpy as np
    >>> lam, X = dense_modes(np.array([[2.0, -1.0], [-1.0, 1.0]]), np.eye(2), 2)
    >>> print(f"{lam[0]:.6f} {lam[1]:.6f} {(3 - np.sqrt(5)) / 2:.6f} {(3 + np.sqrt(5)) / 2:.6f}")
    0.381966 2.618034 0.381966 2.618034
    """
    if driver not in ("evr", "gvx", "gvd", "gv"):
        raise ValueError(f"driver must be 'evr', 'gvx', 'gvd' or 'gv', got {driver!r}")
    n = len(K)
    B = K - sigma * M if sigma else K
    kw = dict(overwrite_a=overwrite, overwrite_b=overwrite or bool(sigma), check_finite=False)
    if max_frequency_hz is not None:
        lam_max = (2.0 * np.pi * float(max_frequency_hz)) ** 2
        if lam_max <= sigma:
            return np.zeros(0), np.zeros((n, 0))
        mu_min = 1.0 / (lam_max - sigma)
        subset = dict(subset_by_value=[mu_min, np.inf])
    else:
        if n_modes is None:
            raise ValueError("dense_modes needs n_modes or max_frequency_hz")
        k = min(int(n_modes), n)
        subset = dict(subset_by_index=[n - k, n - 1])
    if driver == "evr":
        mu, X = _evr(M, B, subset, overwrite)
    elif driver == "gvx":
        mu, X = la.eigh(M, B, driver="gvx", **subset, **kw)
    else:
        mu, X = la.eigh(M, B, driver=driver, **kw)
        keep = mu >= mu_min if max_frequency_hz is not None else np.arange(n) >= n - k
        mu, X = mu[keep], X[:, keep]
    # LAPACK normalises X^T (K - sigma M) X = I; then X^T M X = diag(mu): mass-normalise.
    X = X / np.sqrt(np.maximum(mu, np.finfo(float).tiny))
    return sigma + 1.0 / mu[::-1], X[:, ::-1]


def _evr(A, B, subset: dict, overwrite: bool):
    """Subset of ``A x = mu B x`` (B positive definite) as LAPACK's generalised drivers do
    it, but with the MRRR standard solver: scipy's ``eigh`` offers MRRR ("evr") only for
    standard problems, so the reduction (``L = chol(B)``, ``C = L^-1 A L^-T`` by ``dsygst``,
    ``x = L^-T y``) is written out here. Eigenvectors come out ``B``-normalised."""
    L = la.cholesky(B, lower=True, overwrite_a=overwrite, check_finite=False)
    C, info = la.lapack.dsygst(A if overwrite else A.copy(), L, itype=1, lower=1)
    if info != 0:
        raise la.LinAlgError(f"dsygst failed (info {info})")
    mu, Y = la.eigh(C, driver="evr", lower=True, overwrite_a=True, check_finite=False, **subset)
    return mu, la.solve_triangular(L, Y, lower=True, trans="T", overwrite_b=True, check_finite=False)
