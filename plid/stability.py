"""Stabilise an identified discrete model by reflecting its unstable poles into the unit circle.

Identified models of lightly damped plants can have poles just outside the unit circle
from noise. Reflecting a pole ``p`` (``|p| > 1``) to ``1 / conj(p)`` and multiplying by
``1 / |p|`` is the all-pass argument: on the unit circle
``|e^{jw} - p| = |p| |e^{jw} - 1/conj(p)|``, so the factor

    a(z) = prod_k (z - p_k) / (|p_k| (z - 1/conj(p_k)))

has ``|a(e^{jw})| = 1`` and ``G = H a`` keeps ``|H|`` exactly while its poles are stable.

- Single-input single-output (and any model where ``G = H a`` keeps the order, i.e. SISO):
  ``G = H a`` exactly, realised from its partial fractions at the same order.
- Multi-input or multi-output: ``H a`` generally has a higher McMillan degree (its residue
  at the reflected pole is full rank), so the order is kept instead: each unstable mode is
  reflected and its residue scaled by ``1 / |p|``, which keeps that mode's own contribution
  ``|R / (e^{jw} - p)|`` exactly and ``|H|`` approximately (near a lightly damped
  resonance the mode dominates). ``magnitude_exact`` is False then.

The model must have distinct (diagonalisable) poles; identified models generically do.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from trussid.plid.errors import IdentificationError

__all__ = ["StabiliseResult", "stabilise", "Stability", "check_stability", "UnstableModelWarning",
           "require_stable"]


class UnstableModelWarning(UserWarning):
    """Issued when an unstable model is written (:func:`trussid.plid.modelfile.save_model`)."""


@dataclass
class Stability:
    """Outcome of :func:`check_stability`.

    Attributes
    ----------
    stable : bool
        Every pole strictly inside the unit circle (discrete) or the left half-plane
        (continuous), by more than ``tol``.
    unstable : ndarray (complex)
        Poles outside: ``|z| > 1 + tol`` (discrete) or ``Re s > tol |s|`` (continuous).
    marginal : ndarray (complex)
        Poles on the boundary within ``tol`` (integrators, undamped modes).
    max_radius : float
        Largest ``|z|`` (discrete) or largest ``Re s`` [1/s] (continuous).
    discrete : bool
    dt : float
        Sampling interval [s] (0 for a continuous model).
    """

    stable: bool
    unstable: np.ndarray
    marginal: np.ndarray
    max_radius: float
    discrete: bool
    dt: float

    def _describe(self, poles) -> str:
        parts = []
        # one entry per conjugate pair, the least stable first
        key = np.abs(poles) if self.discrete else poles.real
        for p in poles[np.argsort(-key)]:
            if p.imag < -1e-12 * max(abs(p), 1.0):
                continue
            if self.discrete:
                f = abs(np.angle(p)) / (2 * np.pi * self.dt)
                parts.append(f"|z| = {abs(p):.6g} at {f:.4g} Hz")
            else:
                parts.append(f"Re s = {p.real:.4g} 1/s at {abs(p.imag) / (2 * np.pi):.4g} Hz")
            if len(parts) == 3:
                break
        return "; ".join(parts)

    def message(self, what: str = "the model") -> str | None:
        """One line saying that (and where) ``what`` is unstable, or None when it is not."""
        if self.unstable.size:
            where = "outside the unit circle" if self.discrete else "in the right half-plane"
            return (f"{what} is unstable: {self.unstable.size} pole(s) {where} "
                    f"({self._describe(self.unstable)})")
        if self.marginal.size:
            where = "on the unit circle" if self.discrete else "on the imaginary axis"
            return (f"{what} is marginally stable: {self.marginal.size} pole(s) {where} "
                    f"({self._describe(self.marginal)})")
        return None


def check_stability(sys, tol: float = 1e-9) -> Stability:
    """Stability of a state-space model from the eigenvalues of its ``A``.

    Parameters
    ----------
    sys : control.StateSpace
        Discrete (``dt > 0``) or continuous (``dt = 0``).
    tol : float
        Relative margin that counts as "on the boundary" (marginal).

    Returns
    -------
    Stability

    Examples
    --------
    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import check_stability
    >>> G = control.ss(np.diag([1.02, 0.5]), [[1.0], [1.0]], [[1.0, 1.0]], 0, 1e-3)
    >>> st = check_stability(G)
    >>> st.stable, st.unstable, st.max_radius
    (False, array([1.02+0.j]), 1.02)
    """
    A = np.asarray(sys.A, dtype=float)
    poles = np.linalg.eigvals(A) if A.size else np.zeros(0, complex)
    discrete = bool(control.isdtime(sys, strict=True))
    dt = float(sys.dt) if discrete and sys.dt is not True else 0.0
    if discrete:
        r = np.abs(poles)
        bad, edge = r > 1 + tol, np.abs(r - 1) <= tol
        worst = float(r.max(initial=0.0))
    else:
        scale = np.maximum(np.abs(poles), 1.0)
        bad, edge = poles.real > tol * scale, np.abs(poles.real) <= tol * scale
        worst = float(poles.real.max(initial=-np.inf))
    return Stability(bool(not bad.any() and not edge.any()), poles[bad].astype(complex),
                     poles[edge].astype(complex), worst, discrete, dt)


def require_stable(sys, what: str = "the model", purpose: str | None = None) -> Stability:
    """Raise :class:`IdentificationError` if ``sys`` is unstable (marginal is accepted).

    ``purpose`` completes the message, e.g. ``"a simulation of it diverges"``.
    """
    st = check_stability(sys)
    if st.unstable.size:
        raise IdentificationError(st.message(what) + (f"; {purpose}" if purpose else ""))
    return st


@dataclass
class StabiliseResult:
    """Outcome of :func:`stabilise`.

    Attributes
    ----------
    model : control.StateSpace
        The stabilised model (the input model unchanged if nothing was reflected).
    applied : bool
        True when at least one pole was reflected.
    reflected : ndarray (complex)
        The unstable poles that were reflected (their images are ``1 / conj(p)``).
    magnitude_exact : bool
        True when ``|G(e^{jw})| = |H(e^{jw})|`` holds exactly (all-pass factor).
    """

    model: control.StateSpace
    applied: bool
    reflected: np.ndarray
    magnitude_exact: bool


def _real_from_modal(lam, Bc, Cc, D, dt):
    """Real block-diagonal realisation of a complex diagonal one with conjugate pairs."""
    n = lam.size
    A = np.zeros((n, n))
    B = np.zeros((n, Bc.shape[1]))
    C = np.zeros((Cc.shape[0], n))
    used = np.zeros(n, bool)
    col = 0
    order = np.argsort(-np.abs(lam.imag))  # complex first, so pairs are found cleanly
    for k in order:
        if used[k]:
            continue
        used[k] = True
        if abs(lam[k].imag) <= 1e-12 * max(1.0, abs(lam[k])):
            A[col, col] = lam[k].real
            B[col] = Bc[k].real
            C[:, col] = Cc[:, k].real
            col += 1
            continue
        # its conjugate partner
        cand = np.flatnonzero(~used)
        j = cand[np.argmin(np.abs(lam[cand] - np.conj(lam[k])))]
        used[j] = True
        if lam[k].imag < 0:
            k, j = j, k
        a, b = lam[k].real, lam[k].imag
        # x_r = 2 Re x_k, x_i = -2 Im x_k
        A[col:col + 2, col:col + 2] = [[a, b], [-b, a]]
        B[col] = 2 * Bc[k].real
        B[col + 1] = -2 * Bc[k].imag
        C[:, col] = Cc[:, k].real
        C[:, col + 1] = Cc[:, k].imag
        col += 2
    return control.ss(A, B, C, D, dt)


def stabilise(sys: control.StateSpace, radius: float = 1.0) -> StabiliseResult:
    """Reflect the poles of a discrete model outside ``|z| = radius`` into the unit circle.

    Parameters
    ----------
    sys : control.StateSpace
        Discrete-time model (``dt > 0`` or True).
    radius : float
        Poles with ``|p| > radius`` are reflected (default 1: strictly unstable ones).

    Returns
    -------
    StabiliseResult
        ``applied`` says whether anything changed.

    Examples
    --------
    The pole at 1.02 is reflected to 1 / 1.02 = 0.980; the magnitude response is kept:

    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import stabilise
    >>> G = control.ss(np.diag([1.02, 0.5]), [[1.0], [1.0]], [[1.0, 1.0]], 0, 1e-3)
    >>> r = stabilise(G)
    >>> r.applied, np.round(np.sort(np.abs(np.linalg.eigvals(r.model.A))), 3), r.magnitude_exact
    (True, array([0.5 , 0.98]), True)
    """
    if not isinstance(sys, control.StateSpace) or not control.isdtime(sys, strict=True):
        raise IdentificationError("stabilise needs a discrete-time control.StateSpace")
    A = np.asarray(sys.A, float)
    B = np.asarray(sys.B, float)
    C = np.asarray(sys.C, float)
    D = np.asarray(sys.D, float)
    lam, V = np.linalg.eig(A)
    bad = np.abs(lam) > radius
    if not bad.any():
        return StabiliseResult(sys, False, np.array([], complex), True)
    if np.linalg.cond(V) > 1e12:
        raise IdentificationError(
            "cannot stabilise: the state matrix is (nearly) defective, its modes are not separable"
        )
    Bc = np.linalg.solve(V, B.astype(complex))
    Cc = C @ V
    p_bad = lam[bad]
    r_bad = 1.0 / np.conj(p_bad)
    siso = B.shape[1] == 1 and C.shape[0] == 1

    def allpass(z, skip=None):
        val = np.ones_like(z, dtype=complex)
        for k, (p, r) in enumerate(zip(p_bad, r_bad)):
            if k != skip:
                val *= (z - p) / (abs(p) * (z - r))
        return val

    lam_new = lam.copy()
    if siso:
        # G = H a exactly: residues at the stable poles times a(mu); at each reflected
        # pole r_k, H(r_k) (r_k - p_k) / |p_k| prod_{l != k} a_l(r_k).
        res = (Cc[0] * Bc[:, 0]).astype(complex)
        res_new = np.empty_like(res)
        idx_bad = np.flatnonzero(bad)
        for i in np.flatnonzero(~bad):
            res_new[i] = res[i] * allpass(np.array([lam[i]]))[0]
        for k, i in enumerate(idx_bad):
            r = r_bad[k]
            H_r = np.sum(res / (r - lam)) + D[0, 0]
            res_new[i] = (H_r * (r - p_bad[k]) / abs(p_bad[k])
                          * allpass(np.array([r]), skip=k)[0])
            lam_new[i] = r
        Bc_new = res_new[:, None]
        Cc_new = np.ones((1, lam.size), complex)
        # D a(inf) keeps |G| = |H| with a feed-through too (a(inf) = prod 1/|p|).
        D_new = D * np.prod(1.0 / np.abs(p_bad))
        exact = True
    else:
        Bc_new = Bc.copy()
        Bc_new[bad] /= np.abs(lam[bad])[:, None]
        lam_new[bad] = r_bad
        Cc_new = Cc
        D_new = D
        exact = False
    model = _real_from_modal(lam_new, Bc_new, Cc_new, D_new, sys.dt)
    return StabiliseResult(model, True, p_bad, exact)
