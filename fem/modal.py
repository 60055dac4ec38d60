"""Natural frequencies and mass-normalised mode shapes of an assembled system.

Small systems use LAPACK's dense generalised symmetric solver (``scipy.linalg.eigh``);
large ones shift-invert Lanczos (ARPACK via ``scipy.sparse.linalg.eigsh``) around a small
*negative* shift, so that ``K - sigma M`` is positive definite even for free-free models
(singular ``K``) and the rigid-body modes come out as ordinary, nearest eigenvalues.

DOFs without mass (the rotations under NASTRAN-style lumped mass, the torsion of rod-only
nodes) make ``M`` singular: the dense path condenses them statically (exact: they carry
no inertia), shift-invert accepts a semi-definite ``M`` as it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from trussid.fem.assembly import System, assemble
from trussid.fem.constraints import rigid_body_modes
from trussid.fem.eigen import DENSE_MAX_DOF, dense_modes
from trussid.fem.errors import ModelError
from trussid.fem.factor import SPDFactor, cholmod_available
from trussid._util.threads import blas_threads

__all__ = ["BLAS_THREADS", "DENSE_MAX_DOF", "Modes", "SINGULAR_PIVOT", "factor_stiffness",
           "default_shift", "eigenvalue_scale", "ZERO_EIGENVALUE", "solve_modes",
           "rigid_null_dimension"]

#: OpenBLAS threads used by the eigen and static solutions. The BLAS calls inside
#: SuperLU and ARPACK are small (supernodes of tens of columns, level-2 updates), so
#: threads only add synchronisation: measured on the shared 2-core machine under load,
#: 20 modes of the 2.8e4-DOF lattice took 9.6 s CPU / 38 s wall with 2 threads and
#: 5.4 s / 19 s with 1 (1.5e5-DOF boom: 5.1 s / 17.5 s vs 1.9 s / 6.6 s). Those figures
#: are SuperLU's; CHOLMOD's supernodal blocks (:mod:`trussid.fem.factor`) are BLAS-3 and
#: could use a second thread on an idle machine, not on this shared one.
BLAS_THREADS = 1



@dataclass
class Modes:
    """Normal modes, ascending in frequency.

    Attributes
    ----------
    frequencies_hz : (n,) float
        Natural frequencies [Hz]; rigid-body modes are exactly 0.
    omega : (n,) float
        Circular frequencies [rad/s].
    shapes : (n_red, n) float
        Mass-normalised shapes on the reduced DOFs (``shapes.T @ M @ shapes = I``).
    shapes_full : (6 n_nodes, n) float
        The same expanded to every node's six DOFs (supports zero, slaves expanded).
    node_ids : (n_nodes,) int
    xyz : (n_nodes, 3) float
    n_dof : int
        Reduced DOFs of the eigenproblem.
    method : str
        "dense" or "shift-invert".
    """

    frequencies_hz: np.ndarray
    omega: np.ndarray
    shapes: np.ndarray
    shapes_full: np.ndarray
    node_ids: np.ndarray
    xyz: np.ndarray
    n_dof: int
    method: str = "dense"

    def __len__(self) -> int:
        return len(self.frequencies_hz)


# ---------------------------------------------------------------------------- eigen solution
def _massless(M: sp.csr_matrix, dofs: np.ndarray) -> np.ndarray:
    """DOFs whose mass diagonal is zero relative to the largest of their kind."""
    d = np.abs(M.diagonal())
    out = np.zeros(len(d), bool)
    rot = (dofs % 6) >= 3
    for sel in (rot, ~rot):
        if sel.any():
            mx = d[sel].max()
            out[sel] = d[sel] <= 1e-12 * mx if mx > 0 else True
    return out


def _dense(system: System, k: int, sigma: float | None, max_frequency_hz: float | None = None):
    """Lowest ``k`` eigenpairs (or every one below ``max_frequency_hz``) by
    :func:`dense_modes`; returns ``(lambda, X, proven)``.

    The shift is 0 when K is proven positive definite, else a small negative one. When
    more than half of the modes are wanted, the upper part of the spectrum comes from the
    direct problem (massless DOFs condensed), stitched at ``sqrt(lambda_low lambda_high)``
    where the errors of the inverted and the direct problem cross.
    """
    n = system.n_dof
    proven = False
    if sigma is None:
        if system.has_supports and factor_stiffness(system)[0] is not None:
            sigma, proven = 0.0, True
        else:
            sigma = -default_shift(system)
    K = system.K.toarray()
    M = system.M.toarray()
    massless = _massless(system.M, system.dofs)
    try:
        if max_frequency_hz is not None:
            lam, X = dense_modes(K, M, sigma=sigma, max_frequency_hz=max_frequency_hz)
            if len(lam) <= n // 2:
                return lam, X, proven
            k = len(lam)  # most of the spectrum: stitched below, by count
        k = min(k, _n_mass(M, massless))
        k_low = k
        if k > n // 2:
            # Direct problem on the massive DOFs (static condensation of the massless ones).
            lam_hi, X_hi = _direct(K, M, massless, system)
            lo, hi = lam_hi[0] - sigma, lam_hi[-1] - sigma
            k_low = int(np.searchsorted(lam_hi - sigma, np.sqrt(max(lo, 0.0) * hi)))
            k_low = min(max(k_low, 1), k)
        lam, X = dense_modes(K, M, k_low, sigma=sigma)
    except la.LinAlgError:
        # K - sigma M is singular: a direction with neither stiffness nor mass.
        B = K - sigma * M
        diag = np.abs(np.diag(B))
        fac = SPDFactor(sp.csc_matrix(B) + sp.diags(1e-13 * np.where(diag > 0, diag, 1.0)), backend="superlu")
        j = int(np.argmin(fac.pivots() / np.where(diag > 0, diag, 1.0)))
        raise ModelError(f"mechanism: {system.dof_label(j)} has neither mass nor a stiffness "
                         f"that restrains it") from None
    if k_low < k:
        lam = np.r_[lam, lam_hi[k_low:k]]
        X = np.c_[X, X_hi[:, k_low:k]]
    return lam, X, proven


#: A direction of the diagonally scaled mass matrix (unit diagonal) whose mass is below
#: this is massless: round-off of a zero direction is ~1e-16, and the smallest genuine
#: rotary inertia of a thin tube relative to its own DOF's diagonal is far above 1e-10.
MASSLESS_DIRECTION = 1e-10


def _mass_basis(M, massless):
    """Basis of the massive DOFs split by mass: ``(m, S1, S0, s1)`` with ``m`` the DOFs with
    a mass diagonal, ``S1`` (len(m), r) spanning the directions that carry mass (``S1^T M
    S1 = diag(s1)``) and ``S0`` the massless *directions* among them.

    A CBAR's coupled mass has no torsional inertia: on an inclined bar the massless
    direction is the rotation about the bar's axis, which is no single DOF, so whole-DOF
    condensation (:func:`_massless`) leaves ``M`` singular on the remaining DOFs. Scaling
    ``M`` to a unit diagonal first makes the test relative to each DOF's own inertia
    (translations in kg, rotations in kg m^2).
    """
    m = np.flatnonzero(~massless)
    Mm = M[np.ix_(m, m)]
    d = 1.0 / np.sqrt(np.diag(Mm))
    s, U = la.eigh(Mm * d[:, None] * d[None, :])
    keep = s > MASSLESS_DIRECTION * s.max()
    S1, S0 = d[:, None] * U[:, keep], d[:, None] * U[:, ~keep]
    return m, S1, S0, s[keep]


def _n_mass(M, massless) -> int:
    """Number of directions that carry mass (the modes with a finite frequency).

    The eigen decomposition of :func:`_mass_basis` costs as much as the modes themselves;
    a Cholesky factor of the diagonally scaled mass less ``MASSLESS_DIRECTION`` times a
    Gershgorin bound of its largest eigenvalue (>= the threshold ``_mass_basis`` applies)
    proves, at a tenth of the cost, the usual case: every direction carries mass.
    """
    m = np.flatnonzero(~massless)
    Ms = M[np.ix_(m, m)] if len(m) < len(M) else M.copy()
    d = 1.0 / np.sqrt(np.diag(Ms))
    Ms *= np.outer(d, d)
    bound = float(np.abs(Ms).sum(axis=1).max())
    Ms[np.diag_indices_from(Ms)] -= MASSLESS_DIRECTION * bound
    try:
        la.cholesky(Ms, overwrite_a=True, check_finite=False)
        return len(m)
    except la.LinAlgError:
        return _mass_basis(M, massless)[1].shape[1]


def _direct(K, M, massless, system):
    """All eigenpairs of ``K x = lambda M x`` with mass, massless DOFs and massless
    directions condensed statically (exact: they carry no inertia)."""
    m, S1, S0, s1 = _mass_basis(M, massless)
    z = np.flatnonzero(massless)
    n = len(K)
    # coordinates: x = P1 a + P0 b, a the directions with mass, b the massless ones (whole
    # massless DOFs and massless directions among the others)
    P1 = np.zeros((n, S1.shape[1]))
    P1[m] = S1
    P0 = np.zeros((n, len(z) + S0.shape[1]))
    P0[z, np.arange(len(z))] = 1.0
    P0[m, len(z):] = S0
    if not P0.shape[1]:
        return la.eigh(K, M)
    K00 = P0.T @ K @ P0
    try:
        cf = la.cho_factor(0.5 * (K00 + K00.T))
    except la.LinAlgError:
        j = int(np.argmax(np.abs(P0 @ np.linalg.eigh(K00)[1][:, 0])))
        raise ModelError(f"mechanism: {system.dof_label(j)} has neither mass nor a stiffness "
                         f"that restrains it") from None
    KP1 = K @ P1
    G = -la.cho_solve(cf, P0.T @ KP1)
    T = P1 + P0 @ G                      # x of each massive coordinate, condensed
    Kc = T.T @ K @ T
    lam, a = la.eigh(0.5 * (Kc + Kc.T), np.diag(s1))
    return lam, T @ a


def _shift_invert(system: System, k: int, sigma: float | None, tol: float):
    """Lowest ``k`` eigenpairs by ARPACK shift-invert; returns ``(lambda, X, proven)``,
    ``proven`` when K was shown positive definite (no tiny pivot)."""
    K = system.K
    if sigma is None and system.has_supports:
        # A supported model should have a positive definite K: shifting at 0 gives the
        # best-separated inverted spectrum. Whether K really is definite is only checked
        # (from the factor's pivots, which cost a copy of U) if near-zero modes show up.
        try:
            fac = SPDFactor(K, groups=system.dofs // 6)
        except RuntimeError:  # exactly singular: a mechanism or free rigid-body motion
            fac = None
        if fac is not None:
            try:
                lam, X = _arpack(system, k, 0.0, fac, tol)
            except sla.ArpackError:  # a nearly singular K can break the Lanczos process
                lam = X = None
        if fac is not None and lam is not None:
            if not (lam < ZERO_EIGENVALUE * eigenvalue_scale(system)).any():
                return lam, X, True
            if fac.min_pivot_ratio() >= SINGULAR_PIVOT:
                return lam, X, True
            # Nearly singular: redo with a negative shift for accurate flexible modes; the
            # zero-frequency modes are then checked for rigid-body motion or a mechanism.
    if sigma is None:
        sigma = -default_shift(system)
    try:
        fac = SPDFactor(K - sigma * system.M, groups=system.dofs // 6)
    except RuntimeError as exc:  # exactly singular: only possible for sigma >= 0
        raise ModelError(f"K - sigma M is singular at sigma={sigma:g}: {exc}") from None
    lam, X = _arpack(system, k, sigma, fac, tol)
    return lam, X, False


def _arpack(system: System, k: int, sigma: float, fac: "SPDFactor", tol: float):
    op = sla.LinearOperator(system.K.shape, matvec=fac.solve, dtype=float)
    v0 = np.random.default_rng(0).standard_normal(system.n_dof)  # reproducible start
    # The Krylov space of (K - sigma M)^-1 M cannot exceed the rank of M: massless DOFs
    # (lumped rotations, rod nodes) would otherwise break ARPACK's default subspace size.
    n_mass = int((~_massless(system.M, system.dofs)).sum())
    k = min(k, n_mass - 1)
    ncv = min(n_mass, max(2 * k + 1, 20))
    lam, x = sla.eigsh(system.K, k=k, M=system.M, sigma=sigma, which="LM", OPinv=op, v0=v0, tol=tol,
                       ncv=ncv)
    order = np.argsort(lam)
    return lam[order], x[:, order]


#: A factorisation pivot below this fraction of its diagonal entry means K is singular
#: there (NASTRAN's MAXRATIO test, with a stricter threshold than its default 1e7).
SINGULAR_PIVOT = 1e-10


def factor_stiffness(system: System):
    """Factorise ``K``; return ``(factor, None)`` if it is positive definite, else
    ``(None, j)`` with ``j`` the reduced DOF of the smallest relative pivot."""
    diag = system.K.diagonal()
    scale = np.where(diag > 0, diag, 1.0)
    try:
        fac = SPDFactor(system.K, groups=system.dofs // 6)
    except RuntimeError:
        # An exactly zero pivot: SuperLU does not say where. A diagonal perturbation far
        # below the test threshold makes the factorisation succeed and the pivot visible.
        fac = SPDFactor(system.K + sp.diags(1e-3 * SINGULAR_PIVOT * scale), groups=system.dofs // 6,
                        backend="superlu")
        return None, int(np.argmin(fac.pivots() / scale))
    if fac.min_pivot_ratio() < SINGULAR_PIVOT:
        return None, int(np.argmin(fac.pivots() / scale))
    return fac, None


def default_shift(system: System) -> float:
    """Magnitude of the negative shift used for shift-invert [rad^2/s^2].

    ``1e-9 max K_ii / M_ii`` (the largest eigenvalue is at least ``max K_ii / M_ii``).
    Only used when ``K`` may be singular (free or partly supported models): the shift
    must keep ``K - sigma M`` well conditioned, since the rigid-body directions are
    amplified by ``1 / |sigma|`` in every solve (measured on a free-free frame: flexible
    frequencies off by 8e-5 at 1e-12, within 4e-11 at 1e-10, 2e-12 at 1e-8), yet stay
    below the lowest flexible eigenvalues so the inverted spectrum is well separated.
    """
    return 1e-9 * eigenvalue_scale(system)


def eigenvalue_scale(system: System) -> float:
    """``max K_ii / M_ii``: a Rayleigh-quotient lower bound of the largest eigenvalue."""
    kd, md = system.K.diagonal(), system.M.diagonal()
    ok = md > 0
    return float(np.max(kd[ok] / md[ok])) if ok.any() else 1.0


#: Eigenvalues below this fraction of :func:`eigenvalue_scale` are candidates for
#: zero-frequency modes (round-off of the eigensolvers is ~1e-16..1e-14 of it). They are
#: clamped to exactly 0 if their shape is a rigid-body motion; otherwise, in a supported
#: model, they are a mechanism unless K factorises without a tiny pivot.
ZERO_EIGENVALUE = 1e-12


def solve_modes(model_or_system, n_modes: int = 20, method: str = "auto", *, autospc: bool = False,
                sigma: float | None = None, tol: float = 0.0, max_frequency_hz: float | None = None) -> Modes:
    """Lowest natural frequencies and mass-normalised mode shapes.

    Parameters
    ----------
    model_or_system : fem.Model or System
        A model is assembled first (with ``autospc``).
    n_modes : int
        Number of modes (capped at the number of DOFs that carry mass: massless DOFs add
        no finite-frequency mode).
    method : {"auto", "dense", "sparse"}
        "auto": dense up to :data:`DENSE_MAX_DOF` reduced DOFs or for more than a third
        of the modes, else shift-invert Lanczos.
    autospc : bool
        Passed to :func:`trussid.fem.assembly.assemble` when a model is given.
    sigma : float, optional
        Shift [rad^2/s^2] (both methods work on ``K - sigma M``); default 0 when the model
        has supports and K factorises without a tiny pivot, else a small negative value
        (:func:`default_shift`) so that free-free models (singular K) work.
    tol : float
        ARPACK relative tolerance (0 = machine precision).
    max_frequency_hz : float, optional
        Every mode at or below this frequency [Hz] instead of ``n_modes`` modes: the dense
        solver finds them by value; shift-invert starts from ``n_modes`` and doubles the
        count until a mode lies above it (``method="auto"`` then decides on ``n_modes``).

    Returns
    -------
    Modes

    Raises
    ------
    ModelError
        A mechanism (a zero-frequency mode that is not a rigid-body motion) in a model
        with supports, or a direction with neither mass nor stiffness, naming the node and
        component where the factorisation of K finds no stiffness.

    Examples
    --------
    A steel cantilever, 1 m of 20 x 10 mm solid section in ten elements: its first bending
    frequencies in the two planes against Euler-Bernoulli, ``(1.8751^2 / 2 pi) sqrt(E I / rho A)``
    (8.1538 and 16.3075 Hz):

    >>> import numpy as np
    >>> from trussid.fem import STEEL, Model, Section, solve_modes
    >>> m = Model()
    >>> m.add_nodes(np.arange(1, 12), np.c_[np.linspace(0, 1, 11), np.zeros((11, 2))])
    >>> m.add_beams(np.arange(1, 11), np.c_[np.arange(1, 11), np.arange(2, 12)],
    ...             Section.rectangle(0.02, 0.01), STEEL, orient=[0, 0, 1])
    >>> m.fix(1)
    >>> modes = solve_modes(m, n_modes=4)
    >>> print(np.round(modes.frequencies_hz[:2], 3))
    [ 8.154 16.308]
    """
    system = model_or_system if isinstance(model_or_system, System) else assemble(model_or_system, autospc=autospc)
    cholmod_available()  # loads cvxopt's own BLAS before the thread limit is set
    with blas_threads(BLAS_THREADS):
        return _solve_modes(system, n_modes, method, sigma, tol, max_frequency_hz)


def _solve_modes(system: System, n_modes: int, method: str, sigma, tol, max_frequency_hz=None) -> Modes:
    if method not in ("auto", "dense", "sparse"):
        raise ValueError(f"method must be 'auto', 'dense' or 'sparse', got {method!r}")
    n = system.n_dof
    k = int(min(n_modes, n))
    if k < 1:
        raise ValueError(f"n_modes must be >= 1, got {n_modes}")
    use_dense = (method == "dense" or (method == "auto" and (n <= DENSE_MAX_DOF or k > n // 3))
                 or k >= n - 1)
    proven = False
    if use_dense:
        lam, X, proven = _dense(system, k, sigma, max_frequency_hz)
        used = "dense"
    else:
        lam, X, proven = _shift_invert(system, k, sigma, tol)
        # Every mode below a frequency: double the count until one lies above it (the
        # Lanczos cost grows with the count, so no more are asked for than needed).
        while (max_frequency_hz is not None and len(lam) == k and k <= n // 3
               and lam[-1] <= (2 * np.pi * max_frequency_hz) ** 2):
            k = min(2 * k, n)
            lam, X, proven = _shift_invert(system, k, sigma, tol)
        if max_frequency_hz is not None:
            keep = lam <= (2 * np.pi * max_frequency_hz) ** 2
            lam, X = lam[keep], X[:, keep]
        used = "shift-invert"
    # Mass-normalise explicitly (ARPACK's normalisation is only as good as its tolerance).
    mm = np.einsum("ij,ij->j", X, system.M @ X)
    X = X / np.sqrt(mm)
    shapes_full = system.T @ X
    lam = _zero_modes(system, lam, X, shapes_full, proven)
    omega = np.sqrt(lam)
    return Modes(frequencies_hz=omega / (2 * np.pi), omega=omega, shapes=X, shapes_full=shapes_full,
                 node_ids=system.node_ids, xyz=system.xyz, n_dof=n, method=used)


def rigid_null_dimension(system: System) -> int:
    """Number of independent rigid-body motions the constrained model admits freely.

    The six rigid-body motions of the nodes are taken to the reduced DOFs; those the
    constraints admit (``T q = r``: no support or rigid link resists them) are kept, and
    of these the ones with no strain energy are counted. "No strain energy" is judged
    against the round-off of the quadratic form itself, ``eps |q|^T |K| |q|``, not against
    the largest eigenvalue: a model of short, stiff elements hung on soft springs has real
    sub-hertz modes far below ``1e-12 max(K_ii / M_ii)`` whose shapes are nearly rigid, and
    those must keep their frequencies.
    """
    xyz = system.xyz
    size = float(np.ptp(xyz, axis=0).max()) or 1.0
    R = rigid_body_modes(xyz)                      # (6 n_nodes, 6)
    Q = R[system.dofs]                             # reduced coordinates of each motion
    w = np.tile(np.r_[np.ones(3), np.full(3, size)], len(xyz))[:, None]  # rotations in length units
    D = (system.T @ Q - R) * w
    inert = getattr(system, "inert", None)
    if inert is not None:
        D[inert] = 0.0  # nothing acts on these DOFs: a support there stops no motion
    # Thin SVD: D is (6 n_nodes, 6) and only its right singular vectors are needed; a full
    # one forms a dense (6 n_nodes)^2 U (3.5 GB and 10 s at 1.5e4 DOF, tests/fem/test_scaling.py).
    _, sv, Vt = np.linalg.svd(D, full_matrices=False)
    sv = np.r_[sv, np.zeros(6 - len(sv))]
    admissible = Vt[sv <= 1e-9 * max(np.linalg.norm(R * w), 1.0)].T   # (6, a)
    if admissible.shape[1] == 0:
        return 0
    Qa = Q @ admissible
    K, M = system.K, system.M
    G = Qa.T @ (K @ Qa)
    H = Qa.T @ (M @ Qa)
    absQ = np.abs(Qa)
    bound = np.finfo(float).eps * (absQ.T @ (abs(K) @ absQ))   # round-off of each entry of G
    h = np.diag(H)
    if not (h > 0).all():
        return 0                                   # a massless rigid motion: leave it to the solver
    s = 1.0 / np.sqrt(h)
    mu = np.linalg.eigvalsh((G * s[:, None] * s[None, :]))
    tol = 1e3 * np.max(np.diag(bound) * s**2)
    Hs = H * s[:, None] * s[None, :]
    # Rayleigh quotients mu / eig(H): H is well conditioned after scaling (rigid motions of
    # a body with mass), so the count of tiny mu is the null dimension.
    if np.linalg.cond(Hs) > 1e8:
        return 0
    return int(np.count_nonzero(np.abs(mu) <= tol))


def _zero_modes(system: System, lam, X, shapes_full, proven: bool) -> np.ndarray:
    """Clamp the rigid-body eigenvalues to 0; raise for mechanisms of supported models."""
    lam = np.array(lam, dtype=float)
    r = rigid_null_dimension(system)
    limit = ZERO_EIGENVALUE * eigenvalue_scale(system)
    rigid = np.zeros(len(lam), bool)
    rigid[:r] = lam[:r] < limit                    # ascending: the r lowest are rigid-body modes
    lam[rigid] = 0.0
    # Zero-energy modes that move each kinematic component rigidly are free bodies (a point
    # mass joined to nothing, a free part beside a supported one): 0 Hz when the nearest
    # such motion is strain-free to round-off, otherwise a genuine low mode is kept.
    small = np.flatnonzero(~rigid & (lam < limit))
    free = np.zeros(len(lam), bool)
    if small.size:
        ok, fitted = system.free_body(shapes_full[:, small])
        free[small] = ok
        if ok.any():
            snap = np.zeros(len(ok), bool)
            snap[ok] = _strain_free(system, fitted[:, ok])
            lam[small[snap]] = 0.0
    other = np.flatnonzero(~rigid & (lam < limit) & ~free)
    if system.has_supports and other.size and not proven:
        ok, j = factor_stiffness(system)
        if ok is None:
            if j is None:  # exactly singular: name what moves most in the first such mode
                j = int(np.argmax(np.abs(X[:, other[0]])))
            raise ModelError(f"mechanism: {system.dof_label(j)} has no stiffness (it can move "
                             f"without straining the structure)")
    return np.maximum(lam, 0.0)


def _strain_free(system: System, Z: np.ndarray) -> np.ndarray:
    """Per column of full-DOF motions ``Z``: whether the constraints admit it (``T q = Z``
    with ``q`` its reduced coordinates) and its strain energy is round-off, judged as in
    :func:`rigid_null_dimension` (``eps |q|^T |K| |q|``)."""
    Q = Z[system.dofs]
    free = system.free_dofs()
    D = np.where(free[:, None], 0.0, system.T @ Q - Z)
    admitted = np.linalg.norm(D, axis=0) <= 1e-9 * np.maximum(np.linalg.norm(Z, axis=0), 1e-300)
    absQ = np.abs(Q)
    energy = np.abs(np.einsum("ij,ij->j", Q, system.K @ Q))
    bound = np.finfo(float).eps * np.einsum("ij,ij->j", absQ, abs(system.K) @ absQ)
    return admitted & (energy <= 1e3 * bound)


def _is_rigid(xyz: np.ndarray, Z: np.ndarray, tol: float = 1e-5) -> np.ndarray:
    """Which columns of ``Z`` (full DOF vectors) are rigid-body motions of the nodes."""
    size = float(np.ptp(xyz, axis=0).max()) or 1.0
    w = np.tile(np.r_[np.ones(3), np.full(3, size)], len(xyz))  # rotations in length units
    R = rigid_body_modes(xyz) * w[:, None]
    Zs = Z * w[:, None]
    coef, *_ = np.linalg.lstsq(R, Zs, rcond=None)
    res = np.linalg.norm(Zs - R @ coef, axis=0)
    return res <= tol * np.linalg.norm(Zs, axis=0)
