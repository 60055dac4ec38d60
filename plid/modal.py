"""Experimental-modal-analysis conventions around an identified model.

- :func:`modal_table`: the modal parameters of a state-space model, one row per mode
  (complex pair) or real pole: natural frequency [Hz] and damping ratio (from
  ``control.damp``), the mode shape at the sensors (the outputs) and the modal
  participation factors of the inputs.
- :func:`pole_parameters`: natural frequency [Hz], damping ratio and s-plane image of poles
  (the one conversion of the project; ``modal_parameters``, ``modal_table``, the LQG
  evaluation and model updating call it).
- :func:`mac`: the modal assurance criterion between two sets of mode shapes.
- :func:`pair_modes`, :func:`assign_pairs`, :func:`mode_groups`: pairing of one set of modes
  with another (linear assignment by frequency distance and MAC), and the groups of modes an
  experiment cannot tell apart.
- :func:`pole_std`: first-order standard deviations of frequency and damping of poles from
  the covariance of a PLID parameter vector.

Conventions
-----------
For a model with eigen-decomposition ``A = V diag(lambda) V^-1`` the transfer function is
the sum over poles of ``R_k / (q - lambda_k)`` (plus D), with residue matrices
``R_k = (C v_k)(w_k B)``, ``v_k`` a column of ``V`` and ``w_k`` the matching row of ``V^-1``
(``q`` is ``z`` for a discrete model, ``s`` for a continuous one). The mode shape at the
sensors is ``C v_k`` scaled so that its largest component is 1 (real); the participation
factors are ``w_k B`` scaled the other way, so that ``R_k = shape_k participation_k^T``
holds exactly. Frequencies and damping of a discrete pole are those of the continuous pole
``s = ln(lambda) / dt``.
"""

from __future__ import annotations

import math

import control
import numpy as np
import scipy.optimize

from trussid.plid.data import ModeShapes
from trussid.plid.errors import DataError

# ModeShapes lives in plid.data (imported here for the callers that know it from this
# module); the stabilisation diagram in plid.stabilisation_diagram
__all__ = ["modal_table", "format_modal_table", "mac", "s_plane", "pole_parameters", "assign_pairs", "pair_modes",
           "mode_groups", "pole_std"]


def _names(sys, kind: str, n: int, letter: str) -> list[str]:
    names = getattr(sys, f"{kind}_labels", None)
    return list(names) if names is not None and len(names) == n else \
        [f"{letter}{k + 1}" for k in range(n)]


def modal_table(sys, physical_only: bool = False) -> ModeShapes:
    """Modal parameters of a state-space model, one entry per mode (complex pair) or real pole.

    Parameters
    ----------
    sys : control.StateSpace
        Discrete (``dt`` > 0) or continuous model.
    physical_only : bool
        Keep only lightly damped oscillatory modes (complex pairs with 0 < damping < 1).

    Returns
    -------
    ModeShapes
        Sorted by frequency; ``shapes`` (p x n_modes) at the outputs (``labels`` = output
        names), ``participation`` (n_modes x m), ``poles`` [rad/s].

    Notes
    -----
    Frequencies and damping are those of the eigenvalues through :func:`pole_parameters`
    (``s = ln(z)/dt`` for a discrete model), the same conversion as :func:`control.damp`.
    A defective A (repeated poles without a full set of eigenvectors) gives shapes of poor
    accuracy; identified models practically never have one.

    Examples
    --------
    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import modal_table
    >>> s = control.tf("s")
    >>> G = sum(g * (2 * np.pi * f) ** 2 / (s**2 + 0.04 * 2 * np.pi * f * s + (2 * np.pi * f) ** 2)
    ...         for f, g in ((50.0, 1.0), (120.0, 0.5)))
    >>> modes = modal_table(control.c2d(control.ss(G), 1e-3))
    >>> modes.n_modes, np.round(modes.frequencies_hz, 3), np.round(modes.damping, 4)
    (2, array([ 50., 120.]), array([0.02, 0.02]))
    """
    A = np.asarray(sys.A, dtype=float)
    B = np.asarray(sys.B, dtype=float)
    C = np.asarray(sys.C, dtype=float)
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    out_names, in_names = _names(sys, "output", p, "y"), _names(sys, "input", m, "u")
    if n == 0:
        return ModeShapes(np.zeros(0), np.zeros(0), np.zeros((p, 0), complex), labels=out_names,
                          participation=np.zeros((0, m), complex), input_names=in_names,
                          poles=np.zeros(0, complex))
    lam, V = np.linalg.eig(A)
    W = np.linalg.solve(V, np.eye(n))  # rows: left eigenvectors with W V = I
    dt = sys.dt if control.isdtime(sys, strict=True) else None
    f_all, zeta, s_all = pole_parameters(lam, dt)
    wn = 2 * np.pi * f_all
    keep = lam.imag >= -1e-12 * np.maximum(np.abs(lam), 1e-300)
    cand = np.flatnonzero(keep)
    if physical_only:
        cand = [k for k in cand if lam[k].imag > 1e-12 * abs(lam[k]) and 0 < zeta[k] < 1]
    idx = sorted(cand, key=lambda k: (wn[k], k))
    shapes = C @ V[:, idx]
    part = W[idx, :] @ B
    for c in range(len(idx)):
        big = int(np.argmax(np.abs(shapes[:, c])))
        scale = shapes[big, c]
        if abs(scale) > 0:
            shapes[:, c] /= scale
            part[c, :] *= scale
    s = s_all[idx]
    return ModeShapes(frequencies_hz=f_all[idx], damping=zeta[idx], shapes=shapes,
                      labels=out_names, participation=part, input_names=in_names, poles=s)


def format_modal_table(modes: ModeShapes, max_rows: int | None = None) -> str:
    """The modal parameter table as text: frequency, damping, ``|shape|`` per sensor and
    ``|L|`` per input."""
    labels = modes.labels or [f"dof{k + 1}" for k in range(modes.shapes.shape[0])]
    ins = modes.input_names or []
    head = ["mode", "f [Hz]", "damping [%]"] + [f"|{s}|" for s in labels] + \
        [f"|L {s}|" for s in ins]
    rows = []
    for k in range(modes.n_modes if max_rows is None else min(max_rows, modes.n_modes)):
        row = [str(k + 1), f"{modes.frequencies_hz[k]:.3f}", f"{100 * modes.damping[k]:.3f}"]
        row += [f"{abs(v):.3f}" for v in modes.shapes[:, k]]
        if modes.participation is not None:
            row += [f"{abs(v):.3g}" for v in modes.participation[k]]
        rows.append(row)
    width = [max(len(r[c]) for r in [head] + rows) for c in range(len(head))]
    return "\n".join("  ".join(x.rjust(w) for x, w in zip(r, width)) for r in [head] + rows)


def mac(phi_a, phi_b=None, zero_shape: str = "raise") -> np.ndarray:
    """Modal assurance criterion between two sets of mode shapes.

    ``MAC_ij = |a_i^H b_j|^2 / ((a_i^H a_i)(b_j^H b_j))``: 1 for shapes that are multiples
    of each other (any complex scale), 0 for orthogonal ones.

    Parameters
    ----------
    phi_a : array_like, shape (n_dof, n_a) or ModeShapes
    phi_b : array_like, shape (n_dof, n_b) or ModeShapes, optional
        Default: ``phi_a`` (the auto-MAC).
    zero_shape : {"raise", "zero"}
        A shape that is zero (or not finite): a :class:`DataError` naming it, or MAC 0 with
        every shape (what pairing wants: a mode no sensor sees matches nothing by shape).

    Returns
    -------
    ndarray, shape (n_a, n_b)

    Examples
    --------
    >>> import numpy as np
    >>> from trussid.plid import mac
    >>> phi = np.array([[1.0, 1.0], [1.0, -1.0], [0.5, 0.0]])   # two shapes at three sensors
    >>> print(np.round(mac(phi, phi * [2.0, -3.0]), 3))          # scaled shapes: MAC 1 on the diagonal
    [[1. 0.]
     [0. 1.]]
    >>> print(np.round(mac(phi), 3)[0, 1])                        # shapes orthogonal in the sensors
    0.0
    """
    a = np.asarray(getattr(phi_a, "shapes", phi_a))
    b = a if phi_b is None else np.asarray(getattr(phi_b, "shapes", phi_b))
    a = a[:, None] if a.ndim == 1 else a
    b = b[:, None] if b.ndim == 1 else b
    if a.ndim != 2 or b.ndim != 2 or a.shape[0] != b.shape[0]:
        raise DataError(f"MAC needs shapes at the same DOFs: got {a.shape[0]} and "
                        f"{b.shape[0]} rows")
    na = np.sum(np.abs(a) ** 2, axis=0)
    nb = np.sum(np.abs(b) ** 2, axis=0)
    if zero_shape == "zero":
        num = np.abs(a.conj().T @ b) ** 2
        den = np.outer(na, nb)
        return np.divide(num, den, out=np.zeros_like(num), where=den > 0)
    if zero_shape != "raise":
        raise DataError(f"zero_shape must be 'raise' or 'zero', got {zero_shape!r}")
    for what, nrm in (("first", na), ("second", nb)):
        if np.any(nrm == 0) or not np.all(np.isfinite(nrm)):
            k = int(np.argmax((nrm == 0) | ~np.isfinite(nrm)))
            raise DataError(f"MAC: mode {k + 1} of the {what} set is zero or not finite")
    return np.abs(a.conj().T @ b) ** 2 / np.outer(na, nb)


# --------------------------------------------------------------------- poles


def s_plane(poles, dt: float | None) -> np.ndarray:
    """Continuous-time (s-plane) images of poles: ``s = ln(z) / dt`` for a discrete model
    (``dt`` > 0), the poles themselves for a continuous one (``dt`` None or 0)."""
    poles = np.asarray(poles)
    if not dt:
        return poles.astype(complex)
    z = np.where(np.abs(poles) < 1e-300, 1e-300, poles)
    return np.log(z.astype(complex)) / dt


def pole_parameters(poles, dt: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Natural frequency, damping ratio and s-plane image of each pole (in the given order).

    Parameters
    ----------
    poles : array_like, complex
        Discrete poles ``z`` (with ``dt``) or continuous poles ``s`` [rad/s] (``dt`` None).
    dt : float or None
        Sampling interval [s] of a discrete model.

    Returns
    -------
    frequency_hz : ndarray
        ``|s| / 2 pi`` [Hz].
    damping : ndarray
        ``-Re(s) / |s|`` [-] (1 for a pole at s = 0).
    s : ndarray, complex
        ``ln(z) / dt`` [rad/s] (a discrete pole at 0 is taken at 1e-300).
    """
    s = s_plane(poles, dt)
    wn = np.abs(s)
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(wn > 0, -s.real / wn, 1.0)
    return wn / (2 * np.pi), zeta, s


def pole_std(poles, s, V, W, Cv, theta_cov, dt: float | None) -> tuple[np.ndarray, np.ndarray]:
    """First-order standard deviations of frequency [Hz] and damping of poles of a PLID model.

    PLID's parameters ``theta = [vec(Abar); vec(B)]`` give ``A = F + Abar C`` (``F``, ``C``
    fixed); with right/left eigenvectors ``v``, ``w`` of ``A`` a pole moves by
    ``d z = w^H dAbar C v / (w^H v)``, then ``s = ln z / dt``, ``f = |s| / 2 pi``,
    ``zeta = -Re s / |s|``.

    Parameters
    ----------
    poles : (k,) complex
        Eigenvalues of ``A`` (discrete poles ``z`` or continuous ``s``).
    s : (k,) complex
        Their s-plane images [rad/s] (:func:`s_plane`).
    V, W : (n, k) complex
        Right and left eigenvectors of ``A`` (``scipy.linalg.eig(A, left=True)``).
    Cv : (p, k) complex
        ``C V``.
    theta_cov : (N, N) array, N >= n p
        Posterior covariance of theta (:class:`trussid.plid.estimator.PLIDResult`).
    dt : float or None
        Sampling interval [s] of a discrete model.

    Returns
    -------
    frequency_std_hz, damping_std : (k,) float
        NaN for a pole whose propagated variance is not positive (a covariance that lost
        definiteness, which PLID's direct form can give).
    """
    n, p = np.shape(V)[0], np.shape(Cv)[0]
    cov = np.asarray(theta_cov, float)
    if cov.ndim != 2 or cov.shape[0] != cov.shape[1] or cov.shape[0] < n * p:
        raise DataError(f"theta_cov must be square with at least n p = {n * p} rows, got {cov.shape}")
    caa = cov[: n * p, : n * p]
    fstd, zstd = np.empty(len(s)), np.empty(len(s))
    for k in range(len(s)):  # a handful of modes
        wv = W[:, k].conj() @ V[:, k]
        g = np.outer(W[:, k].conj(), Cv[:, k]).ravel(order="F") / wv  # d z / d vec(Abar)
        gs = g / (poles[k] * dt) if dt else g  # d s
        mag = abs(s[k])
        a_f = np.real(np.conj(s[k]) * gs) / (2 * np.pi * mag)
        a_z = -np.real(gs) / mag + s[k].real * np.real(np.conj(s[k]) * gs) / mag**3
        vf, vz = a_f @ caa @ a_f, a_z @ caa @ a_z
        fstd[k] = math.sqrt(vf) if vf > 0 else np.nan
        zstd[k] = math.sqrt(vz) if vz > 0 else np.nan
    return fstd, zstd


# --------------------------------------------------------------------- pairing


def assign_pairs(cost, allowed=None, groups=None) -> np.ndarray:
    """Pair each row with a distinct column at least total cost (linear assignment).

    The one pairing of the project: :func:`pair_modes` (frequency and MAC) and
    :func:`trussid.plid.metrics.compare_poles` (s-plane distance) build a cost and call it.

    Parameters
    ----------
    cost : (k, n) float
    allowed : (k, n) bool, optional
        Pairs outside it are never chosen.
    groups : (n,) int, optional
        Columns with the same number form a group (:func:`mode_groups`): each group takes at
        most one row, with its lowest-cost member.

    Returns
    -------
    (k,) int
        Column paired with each row, -1 when no allowed column is left.
    """
    cost = np.asarray(cost, float)
    k = cost.shape[0]
    big = 1e6 + 10 * float(np.max(cost[np.isfinite(cost)], initial=0.0))
    if allowed is not None:
        cost = np.where(allowed, cost, big)
    member = None
    if groups is not None:
        groups = np.asarray(groups, int)
        labels = np.unique(groups)
        gc = np.full((k, labels.size), big)
        member = np.zeros((k, labels.size), dtype=int)
        for q, lab in enumerate(labels):  # a few dozen groups
            idx = np.flatnonzero(groups == lab)
            best = np.argmin(cost[:, idx], axis=1)
            member[:, q] = idx[best]
            gc[:, q] = cost[np.arange(k), idx[best]]
        cost = gc
    out = np.full(k, -1)
    if cost.shape[1] == 0:
        return out
    rows, cols = scipy.optimize.linear_sum_assignment(cost)
    ok = cost[rows, cols] < big
    out[rows[ok]] = cols[ok] if member is None else member[rows[ok], cols[ok]]
    return out


def pair_modes(measured_hz, model_hz, *, scale_hz=None, mac=None, mac_weight: float = 1.0,
               allowed=None, groups=None) -> np.ndarray:
    """Pair each measured mode with a distinct model mode (linear assignment).

    Cost of a pair: ``|f_i - F_j| / scale_i`` (default ``scale_i = f_i``: relative distance)
    plus ``mac_weight * (1 - MAC_ij)`` when ``mac`` is given. Pairs outside ``allowed`` are
    never chosen.

    Parameters
    ----------
    measured_hz : (k,) float
    model_hz : (n,) float
    scale_hz : (k,) or (k, n) float, optional
    mac : (k, n) float, optional
    mac_weight : float
    allowed : (k, n) bool, optional
    groups : (n,) int, optional
        Model modes with the same number form a group (:func:`mode_groups`): each group
        takes at most one measured mode, with its lowest-cost member.

    Returns
    -------
    (k,) int
        Model index paired with each measured mode, -1 when no allowed model mode is left.
    """
    f = np.asarray(measured_hz, float)
    F = np.asarray(model_hz, float)
    scale = f[:, None] if scale_hz is None else np.asarray(scale_hz, float)
    if scale.ndim == 1:
        scale = scale[:, None]
    cost = np.abs(f[:, None] - F[None, :]) / scale
    if mac is not None:
        cost = cost + mac_weight * (1.0 - np.asarray(mac, float))
    return assign_pairs(cost, allowed=allowed, groups=groups)


def mode_groups(model_hz, shapes, bandwidth_hz, mac_min: float = 0.9) -> np.ndarray:
    """Group model modes that an experiment cannot tell apart.

    Two modes (adjacent in frequency) are one group when they are closer than
    ``bandwidth_hz`` and their shapes at the sensors agree (MAC above ``mac_min``): the
    two bending planes of one strut, seen by one lateral sensor. An identified pole is then
    one blend of the group, so at most one measured mode may pair with it.

    Parameters
    ----------
    model_hz : (n,) float
        Frequencies [Hz].
    shapes : (p, n) array or None
        Shapes at the sensors (None: frequency alone, no two modes are grouped).
    bandwidth_hz : float or (n,) float
    mac_min : float

    Returns
    -------
    (n,) int
        Group number of each mode (modes in frequency order get consecutive numbers).
    """
    F = np.asarray(model_hz, float)
    order = np.argsort(F)
    macs = None if shapes is None else mac(np.asarray(shapes, complex),
                                           np.asarray(shapes, float).real, zero_shape="zero")
    bw = np.broadcast_to(np.asarray(bandwidth_hz, float), F.shape)
    g = np.empty(F.size, dtype=int)
    cur = 0
    for a, b in zip(order[:-1], order[1:]):  # a chain along the sorted frequencies
        g[a] = cur
        close = F[b] - F[a] < bw[b]
        if not (close and macs is not None and macs[a, b] > mac_min):
            cur += 1
    if F.size:
        g[order[-1]] = cur
    return g
