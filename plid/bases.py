"""Well-conditioned observer bases for PLID at high order, and exact conversion into them.

PLID identifies ``A = F + Abar C`` for a fixed observable pair ``(F, C)``
(:class:`trussid.plid.canonical.ObserverBasis`). The thesis's block shift makes the conversion of a
lightly damped 24-state plant ill-conditioned (observability condition 2e10,
``docs/plid.md``). The *rotation* bases here replace each shift chain by 2x2 rotations
scaled by a radius ``r < 1``::

    F_k = r [[cos w_k, -sin w_k], [sin w_k, cos w_k]],   w_k = 2 pi f_k / fs

block-diagonal, with ``C`` summing the first component of every block that belongs to an
output. The pair is stable (all eigenvalues on |z| = r) and observable when the w_k are
distinct. Layouts for p outputs:

- ``"partition"``: the blocks are dealt out to the outputs in turn (sorted frequencies,
  block k to output k mod p), so each output owns ``n / p`` states (the uniform
  observability index of the shift form, the same parameter count ``n (p + m)``) and its
  blocks span the whole band. ``n / p`` odd adds one real pole ``r`` per output.
- ``"dense"``: every output row sums every block's first component with fixed seeded
  weights of unit size.

Frequencies come from the user, from a band (:func:`band_frequencies`), from the data
(:func:`data_frequencies`, peaks of the averaged output spectrum) or from a preliminary
model (:func:`model_frequencies`, the angles of its poles).

Conversion (:func:`to_basis`). For ``(A, B, C)`` find ``T`` and ``Abar`` with
``T A T^-1 = F + Abar C_b`` and ``C_b T = C``. Eliminating ``F T = T A - Abar C`` row block
by row block of the basis observability matrix gives, for j = 0, 1, ...::

    C_b F^j T = C A^j - sum_{i<j} (C_b F^(j-1-i) Abar) C A^i

i.e. ``O_F T = (I - Toep(Abar)) O_A`` with ``O_X = [C_x; C_x X; ...]`` over ``N`` block rows
and ``Toep`` block lower triangular with blocks ``C_b F^(j-1-i) Abar``. ``O_F`` has full
column rank, so ``T = O_F^+ (I - Toep) O_A``; the rows of ``(I - Toep) O_A`` outside the
range of ``O_F`` must vanish, which is linear in ``Abar`` and determines it
(``method="observability"``). ``method="sylvester"`` (the engine's
:func:`trussid.plid.canonical.from_statespace`) solves ``T A - F T = Abar C`` instead; both are
exact and are checked against each other in the tests.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.signal

from trussid.plid.canonical import ObserverBasis, from_statespace, join_theta
from trussid.plid.errors import IdentificationError

__all__ = ["rotation_basis", "as_selector", "band_frequencies", "data_frequencies", "model_frequencies",
           "to_basis", "conversion_condition", "basis_for"]


def _rot(r: float, w: float) -> np.ndarray:
    c, s = np.cos(w), np.sin(w)
    return r * np.array([[c, -s], [s, c]])


def rotation_basis(freqs_hz, fs: float, p: int, radius: float = 0.97,
                   layout: str = "partition", seed: int = 0) -> ObserverBasis:
    """Block-diagonal rotation basis with ``2 len(freqs_hz)`` (+ real poles) states.

    Parameters
    ----------
    freqs_hz : array of float
        Rotation frequencies [Hz], ``0 < f < fs / 2``, distinct. For ``layout="partition"``
        give ``n / 2`` of them when ``n / p`` is even, ``(n - p) / 2`` when odd (one real
        pole ``radius`` per output is then added).
    fs : float
        Sampling frequency [Hz].
    p : int
        Number of outputs.
    radius : float
        Pole radius of every block, ``0 < radius < 1``.
    layout : {"partition", "dense"}
        See the module docstring.
    seed : int
        Seed of the fixed weights of the ``"dense"`` layout.
    """
    f = np.sort(np.asarray(freqs_hz, dtype=float).ravel())
    if not 0 < radius < 1:
        raise IdentificationError(f"basis radius must be in (0, 1), got {radius}")
    if f.size == 0 or np.any(f <= 0) or np.any(f >= fs / 2):
        raise IdentificationError(f"basis frequencies must lie in (0, fs/2 = {fs / 2:g}) Hz")
    if np.any(np.diff(f) <= 0):
        raise IdentificationError("basis frequencies must be distinct")
    w = 2 * np.pi * f / fs
    if layout == "partition":
        nb = f.size
        if nb % p:
            raise IdentificationError(
                f"{nb} rotation blocks cannot be dealt evenly to {p} outputs")
        groups = [list(range(i, nb, p)) for i in range(p)]
        return _assemble(w, groups, radius, p)
    if layout == "dense":
        n = 2 * f.size
        F = scipy.linalg.block_diag(*[_rot(radius, wk) for wk in w])
        rng = np.random.default_rng(seed)
        C = np.zeros((p, n))
        C[:, 0::2] = rng.choice([-1.0, 1.0], size=(p, f.size)) * rng.uniform(0.5, 1.5, (p, f.size))
        C[0, 0::2] = 1.0
        return ObserverBasis(F, C, f"rotation-dense r={radius:g}")
    raise IdentificationError(f"unknown basis layout {layout!r}")


def _assemble(w, groups, radius, p):
    blocks = []
    owner = []
    for i, g in enumerate(groups):
        for k in g:
            blocks.append(_rot(radius, w[k]))
            owner.append(i)
    F = scipy.linalg.block_diag(*blocks)
    n = F.shape[0]
    C = np.zeros((p, n))
    for b, i in enumerate(owner):
        C[i, 2 * b] = 1.0
    return ObserverBasis(F, C, f"rotation r={radius:g}")


def as_selector(basis: ObserverBasis) -> ObserverBasis:
    """The same basis in coordinates where ``C`` selects one state per output.

    For each output i the first state it reads is replaced by ``C_i x`` (the sum it reads):
    ``T = I`` with row ``s_i`` set to ``C_i``, ``F' = T F T^-1``, ``C' = C T^-1 = e_{s_i}``.
    PLID in ``(F', C')`` is the same estimator (``A' = T A T^-1``, ``Abar' = T Abar``), but
    the engine's per-sample loop turns ``C x`` and ``P C^T`` into index gathers for a
    selector ``C`` (``trussid.plid.recursion_common.Problem.sel``), which is what this is for.
    ``T`` is unit triangular up to a permutation; its condition number is about the
    number of blocks per output.
    """
    C = np.asarray(basis.C)
    n, p = basis.n, basis.p
    T = np.eye(n)
    sel = []
    for i in range(p):
        nz = np.flatnonzero(C[i])
        s = next(j for j in nz if j not in sel and all(C[k, j] == 0 for k in range(p) if k != i))
        if C[i, s] == 0:
            raise IdentificationError("basis C has an empty row")
        T[s] = C[i]
        sel.append(s)
    Ti = np.linalg.inv(T)
    F = T @ basis.F @ Ti
    Cs = np.zeros((p, n))
    Cs[np.arange(p), sel] = 1.0
    if not np.allclose(C @ Ti, Cs, atol=1e-12):
        raise IdentificationError("basis cannot be put in selector form (rows of C overlap)")
    return ObserverBasis(F, Cs, basis.name + " selector")


def band_frequencies(count: int, band, spacing: str = "geometric") -> np.ndarray:
    """``count`` frequencies spread over ``band = (lo, hi)`` Hz (geometric or linear)."""
    lo, hi = (float(b) for b in band)
    if not 0 < lo < hi:
        raise IdentificationError(f"band ({lo:g}, {hi:g}) Hz must have 0 < low < high")
    if count == 1:
        return np.array([np.sqrt(lo * hi)])
    return np.geomspace(lo, hi, count) if spacing == "geometric" else np.linspace(lo, hi, count)


def data_frequencies(u, y, fs: float, count: int, band=None, nperseg: int = 1024) -> np.ndarray:
    """``count`` frequencies [Hz] from the data: the most prominent peaks of the summed
    output power spectral density (Welch) inside ``band`` (default 2 % to 48 % of fs),
    topped up with band-spread frequencies when there are too few peaks."""
    y = np.asarray(y, dtype=float)
    y = y[:, None] if y.ndim == 1 else y
    nper = int(min(nperseg, y.shape[0]))
    f, P = scipy.signal.welch(y, fs=fs, nperseg=nper, axis=0)
    P = P.sum(axis=1)
    lo, hi = band if band is not None else (0.02 * fs, 0.48 * fs)
    keep = (f > lo) & (f < hi)
    f, P = f[keep], P[keep]
    # Rank peaks by prominence in log power: the ripple of the Welch estimate on the skirt
    # of a strong resonance makes tall but not prominent peaks.
    peaks, props = scipy.signal.find_peaks(np.log(P + 1e-300), prominence=0.0, distance=2)
    top = peaks[np.argsort(props["prominences"])[::-1][:count]] if peaks.size else peaks
    chosen = f[top]
    chosen = list(np.sort(chosen))
    df = fs / nper
    for g in band_frequencies(count, (lo, hi)):
        if len(chosen) >= count:
            break
        if all(abs(g - c) > df for c in chosen):
            chosen.append(g)
    out = np.sort(np.array(chosen[:count]))
    # keep them distinct (rounding to the Welch grid can collide)
    for i in range(1, out.size):
        if out[i] <= out[i - 1]:
            out[i] = out[i - 1] + 0.25 * df
    return out


def model_frequencies(sys, count: int, fs: float, band=None) -> np.ndarray:
    """``count`` frequencies [Hz] from a preliminary model: the angles of its complex
    poles (one per pair, nearest the band first), topped up with band-spread ones."""
    lam = np.linalg.eigvals(np.asarray(sys.A, dtype=float))
    ang = np.abs(np.angle(lam[lam.imag > 1e-9])) * fs / (2 * np.pi)
    lo, hi = band if band is not None else (0.01 * fs, 0.49 * fs)
    ang = np.sort(ang[(ang > 0.2 * lo) & (ang < 0.499 * fs)])
    chosen = list(ang[:count])
    for g in band_frequencies(count, (lo, hi)):
        if len(chosen) >= count:
            break
        chosen.append(g)
    out = np.sort(np.array(chosen[:count]))
    for i in range(1, out.size):
        if out[i] - out[i - 1] < 1e-3:
            out[i] = out[i - 1] + 1e-3
    return out


def basis_for(n: int, p: int, fs: float, freqs_hz, radius: float = 0.97,
              layout: str = "partition") -> ObserverBasis:
    """A rotation basis of exactly ``n`` states for ``p`` outputs.

    Partition layout: each output owns ``nu = n / p`` states, ``nu // 2`` rotation blocks
    (the lowest ``p (nu // 2)`` of ``freqs_hz`` are used, dealt out in turn) plus one real
    pole just below ``radius`` when ``nu`` is odd; with one state per output the basis is
    real poles alone. Dense layout: ``n / 2`` blocks.

    Raises
    ------
    IdentificationError
        For the partition layout when ``p`` does not divide ``n``: with unequal shares of
        states per output, ``A = F + Abar C`` with a fixed ``C`` no longer represents a
        generic order-``n`` model (the observer form would need free entries in ``C``, and
        the state equation would no longer be linear in the parameters).
    """
    if layout == "partition":
        if int(n) != n or n < 1:
            raise IdentificationError(f"order must be a positive integer, got {n!r}")
        if n % p:
            lo, hi = (n // p) * p, -(-n // p) * p
            raise IdentificationError(
                f"order {n} is not a multiple of the {p} outputs: PLID's observer form "
                f"(A = F + Abar C, C fixed) gives every output n/p states"
                + (f"; try order {lo} or {hi}" if lo else f"; try order {hi}"))
        nus = [n // p] * p
        need = [nu // 2 for nu in nus]
        nrot = sum(need)
        f = np.sort(np.asarray(freqs_hz, dtype=float))[:nrot]
        if f.size < nrot:
            raise IdentificationError(f"need {nrot} basis frequencies, got {f.size}")
        if nrot:
            if np.any(f <= 0) or np.any(f >= fs / 2):
                raise IdentificationError(
                    f"basis frequencies must lie in (0, fs/2 = {fs / 2:g}) Hz")
            if np.any(np.diff(f) <= 0):
                raise IdentificationError("basis frequencies must be distinct")
        if not 0 < radius < 1:
            raise IdentificationError(f"basis radius must be in (0, 1), got {radius}")
        # deal the sorted frequencies out in turn to the outputs that still need blocks
        groups, left, k = [[] for _ in range(p)], list(need), 0
        while k < nrot:
            for i in range(p):
                if left[i] and k < nrot:
                    groups[i].append(k)
                    left[i] -= 1
                    k += 1
        w = 2 * np.pi * f / fs
        return _assemble_partition(w, groups, [nu % 2 for nu in nus], radius, p)
    f = np.sort(np.asarray(freqs_hz, dtype=float))[: n // 2]
    if n % 2:
        raise IdentificationError("the dense layout needs an even order")
    return rotation_basis(f, fs, p, radius, "dense")


def _assemble_partition(w, groups, reals, radius, p):
    """Rotation blocks ``groups[i]`` (indices into ``w``) and ``reals[i]`` real poles per
    output i; ``C`` row i sums the first component of each of output i's blocks."""
    blocks, owner = [], []
    for i, g in enumerate(groups):
        for k in g:
            blocks.append(_rot(radius, w[k]))
            owner.append(i)
    nrot = 2 * len(blocks)
    n_real = int(sum(reals))
    n = nrot + n_real
    F = np.zeros((n, n))
    C = np.zeros((p, n))
    for b, (blk, i) in enumerate(zip(blocks, owner)):
        F[2 * b:2 * b + 2, 2 * b:2 * b + 2] = blk
        C[i, 2 * b] = 1.0
    # distinct real poles keep (F, C) observable: spread them slightly below the radius
    vals = radius * (1 - 0.02 * np.arange(1, n_real + 1))
    s = nrot
    for i, r in enumerate(reals):
        for _ in range(r):
            F[s, s] = vals[s - nrot]
            C[i, s] = 1.0
            s += 1
    name = f"rotation r={radius:g}" + (f" +{n_real} real" if n_real else "")
    return ObserverBasis(F, C, name)


# ----------------------------------------------------------------------------- conversion


def _obsv(A, C, N):
    rows = [C]
    for _ in range(N - 1):
        rows.append(rows[-1] @ A)
    return np.vstack(rows)


def _observability_transform(A, C, basis: ObserverBasis, extra_rows: int = 1):
    """``T`` and ``Abar`` from ``O_F T = (I - Toep(Abar)) O_A`` (module docstring)."""
    F, Cb = basis.F, basis.C
    n, p = basis.n, basis.p
    N = -(-n // p) + extra_rows
    OF = _obsv(F, Cb, N)
    OA = _obsv(A, C, N)
    # Projector onto the orthogonal complement of range(O_F), via a full QR.
    Qf, Rf = np.linalg.qr(OF, mode="complete")
    rank = np.linalg.matrix_rank(OF)
    if rank < n:
        raise IdentificationError(f"the '{basis.name}' basis is not observable")
    Qperp = Qf[:, n:]
    Qr, R1 = Qf[:, :n], Rf[:n]
    # Toep(E) O_A for a unit Abar entry E = e_a e_b^T: block row j is
    # sum_{i<j} (C_b F^(j-1-i) e_a) (C A^i)[b]. Precompute C_b F^k e_a = OF[k-block, a].
    CAi = OA.reshape(N, p, n)                     # CAi[i, b, :] = (C A^i)[b]
    CbFk = OF.reshape(N, p, n)                    # CbFk[k, :, a] = C_b F^k e_a
    cols = []
    for b in range(p):
        for a in range(n):
            Tp = np.zeros((N, p, n))
            for j in range(1, N):
                # sum_i CbFk[j-1-i, :, a] outer CAi[i, b, :]
                Tp[j] = np.einsum("ip,iq->pq", CbFk[j - 1::-1, :, a], CAi[:j, b, :])
            cols.append(Tp.reshape(N * p, n))
    # residual(Abar) = Qperp^T (O_A - sum coef * Toep(E)) = 0
    Mcols = np.column_stack([(Qperp.T @ Tk).ravel() for Tk in cols])
    rhs = (Qperp.T @ OA).ravel()
    coef, *_ = np.linalg.lstsq(Mcols, rhs, rcond=None)
    Abar = coef.reshape(p, n).T
    Toep = np.tensordot(coef, np.array(cols), axes=1)
    T = scipy.linalg.solve_triangular(R1, Qr.T @ (OA - Toep))
    return T, Abar


def to_basis(sys, basis: ObserverBasis, method: str = "observability"):
    """Exact observer-form parameters of a known model in ``basis``.

    Parameters
    ----------
    sys : control.StateSpace or tuple (A, B, C[, D])
        Discrete, strictly proper, ``basis.n`` states, ``basis.p`` outputs.
    basis : ObserverBasis
    method : {"observability", "sylvester"}
        See the module docstring.

    Returns
    -------
    theta : ndarray (n (p + m),)
        ``[vec(Abar); vec(T B)]``.
    T : ndarray (n, n)
        State transformation ``x' = T x``.
    """
    if method == "sylvester":
        return from_statespace(sys, basis, method="sylvester")
    if method != "observability":
        raise IdentificationError(f"unknown conversion method {method!r}")
    if hasattr(sys, "A"):
        A, B, C, D = (np.asarray(M, dtype=float) for M in (sys.A, sys.B, sys.C, sys.D))
    else:
        A, B, C = (np.atleast_2d(np.asarray(M, dtype=float)) for M in sys[:3])
        D = np.asarray(sys[3], dtype=float) if len(sys) > 3 else np.zeros((C.shape[0], B.shape[1]))
    if A.shape != (basis.n, basis.n) or C.shape[0] != basis.p:
        raise IdentificationError(
            f"model has {A.shape[0]} states and {C.shape[0]} outputs; the basis needs "
            f"{basis.n} states and {basis.p} outputs")
    if np.any(D != 0):
        raise IdentificationError("model has a direct feed-through term D; PLID models have D = 0")
    T, Abar = _observability_transform(A, C, basis)
    return join_theta(Abar, T @ B), T


def conversion_condition(sys, basis: ObserverBasis, method: str = "sylvester") -> float:
    """2-norm condition number of the transformation ``T`` into ``basis``."""
    _, T = to_basis(sys, basis, method)
    return float(np.linalg.cond(T))
