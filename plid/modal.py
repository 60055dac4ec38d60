"""Experimental-modal-analysis conventions around an identified model.

- :func:`modal_table`: the modal parameters of a state-space model, one row per mode
  (complex pair) or real pole: natural frequency [Hz] and damping ratio (from
  ``control.damp``), the mode shape at the sensors (the outputs) and the modal
  participation factors of the inputs.
- :func:`mac`: the modal assurance criterion between two sets of mode shapes.
- :func:`stabilisation`: models over a range of orders, each pole marked stable in
  frequency, damping and mode shape against the model one order step below, as modal
  analysts choose order and poles (the figure: :func:`trussid.plots.stabilisation_figure`).

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

import time
from dataclasses import dataclass, field

import numpy as np

from trussid.plid.errors import DataError, IdentificationError

__all__ = ["ModeShapes", "modal_table", "format_modal_table", "mac", "Stabilisation",
           "stabilisation"]


@dataclass
class ModeShapes:
    """A set of modes: frequencies, damping and shapes at some degrees of freedom.

    Attributes
    ----------
    frequencies_hz : ndarray, shape (n_modes,)
        Undamped natural frequencies [Hz].
    damping : ndarray, shape (n_modes,)
        Damping ratios [-] (1 for a real pole).
    shapes : ndarray, shape (n_dof, n_modes)
        Mode shapes, one column per mode (complex for identified modes).
    labels : list of str, optional
        Name of each DOF (e.g. the model's output names).
    dofs : list of (int, int), optional
        (node id, direction 1-6) of each DOF, for UFF 55 export and FE comparison.
    participation : ndarray, shape (n_modes, n_inputs), optional
        Modal participation factors of the inputs (see the module docstring).
    input_names : list of str, optional
    poles : ndarray, shape (n_modes,), optional
        Continuous-time poles [rad/s], one per mode (positive imaginary part).
    """

    frequencies_hz: np.ndarray
    damping: np.ndarray
    shapes: np.ndarray
    labels: list | None = None
    dofs: list | None = None
    participation: np.ndarray | None = None
    input_names: list | None = None
    poles: np.ndarray | None = None

    @property
    def n_modes(self) -> int:
        return int(np.asarray(self.frequencies_hz).size)

    def select(self, index) -> "ModeShapes":
        """The modes ``index`` (indices or a boolean mask), in that order."""
        idx = np.arange(self.n_modes)[index]
        pick = (lambda a: None if a is None else np.asarray(a)[idx])
        return ModeShapes(
            frequencies_hz=np.asarray(self.frequencies_hz)[idx],
            damping=np.asarray(self.damping)[idx], shapes=np.asarray(self.shapes)[:, idx],
            labels=self.labels, dofs=self.dofs, participation=pick(self.participation),
            input_names=self.input_names, poles=pick(self.poles))


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
    Frequencies and damping come from :func:`control.damp` (its conversion of discrete
    poles through ``ln(z)/dt``); the shapes and participation factors need the eigenvectors,
    which it does not return, so each of its poles is matched to the nearest eigenvalue.
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
    import control

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
    wn_c, zeta_c, poles_c = control.damp(sys, doprint=False)
    wn, zeta = np.empty(n), np.empty(n)
    used = np.zeros(n, bool)
    for k, lk in enumerate(lam):  # pair control.damp's poles with the eigenvalues
        d = np.abs(np.asarray(poles_c) - lk) + np.where(used, np.inf, 0.0)
        j = int(np.argmin(d))
        used[j] = True
        wn[k], zeta[k] = wn_c[j], zeta_c[j]
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
    dt = sys.dt if control.isdtime(sys, strict=True) else None
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.log(lam[idx].astype(complex)) / dt if dt else lam[idx].astype(complex)
    return ModeShapes(frequencies_hz=wn[idx] / (2 * np.pi), damping=zeta[idx], shapes=shapes,
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


def mac(phi_a, phi_b=None) -> np.ndarray:
    """Modal assurance criterion between two sets of mode shapes.

    ``MAC_ij = |a_i^H b_j|^2 / ((a_i^H a_i)(b_j^H b_j))``: 1 for shapes that are multiples
    of each other (any complex scale), 0 for orthogonal ones.

    Parameters
    ----------
    phi_a : array_like, shape (n_dof, n_a) or ModeShapes
    phi_b : array_like, shape (n_dof, n_b) or ModeShapes, optional
        Default: ``phi_a`` (the auto-MAC).

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
    for what, nrm in (("first", na), ("second", nb)):
        if np.any(nrm == 0) or not np.all(np.isfinite(nrm)):
            k = int(np.argmax((nrm == 0) | ~np.isfinite(nrm)))
            raise DataError(f"MAC: mode {k + 1} of the {what} set is zero or not finite")
    return np.abs(a.conj().T @ b) ** 2 / np.outer(na, nb)


# --------------------------------------------------------------------- stabilisation


@dataclass
class Stabilisation:
    """Poles of models over a range of orders, each marked against the order below.

    Attributes
    ----------
    orders : list of int
        Orders that gave a model.
    modes : list of ModeShapes
        Per order, its physical modes (0 < damping < 1, one per pair).
    status : list of ndarray of str
        Per order and mode: ``"new"`` (no pole near it at the order below), ``"f"``
        (frequency stable), ``"fd"`` (frequency and damping), ``"fv"`` (frequency and
        shape) or ``"s"`` (all three: stable).
    runs : list of ndarray of int
        Per order and mode: over how many consecutive order steps (ending here) the pole
        has been stable in all three (0 for any other status). Modal analysts trust a
        column of stable poles, not one stable step: a noise pole can match once.
    failed : list of (int, str)
        Orders that gave no model, with the reason.
    tolerances : dict
        ``f`` and ``damping`` (relative), ``mac`` (lowest MAC).
    models : list
        The identified models, by order.
    seconds : list of float
    """

    orders: list
    modes: list
    status: list
    runs: list = field(default_factory=list)
    failed: list = field(default_factory=list)
    tolerances: dict = field(default_factory=dict)
    models: list = field(default_factory=list)
    seconds: list = field(default_factory=list)

    def stable_poles(self, order: int | None = None, min_run: int = 1) -> ModeShapes:
        """The modes stable in all three at ``order`` (default: the highest order) over at
        least ``min_run`` consecutive order steps."""
        k = len(self.orders) - 1 if order is None else self.orders.index(order)
        return self.modes[k].select(self.runs[k] >= max(min_run, 1))


def mark_stability(prev: ModeShapes | None, cur: ModeShapes, tol_f: float, tol_zeta: float,
                   tol_mac: float, return_match: bool = False):
    """Status of each mode of ``cur`` against the nearest-frequency mode of ``prev``
    (and, with ``return_match``, the index of that mode, -1 where none is near)."""
    status = np.array(["new"] * cur.n_modes, dtype=object)
    match = np.full(cur.n_modes, -1)
    if prev is None or prev.n_modes == 0 or cur.n_modes == 0:
        return (status, match) if return_match else status
    macs = mac(cur.shapes, prev.shapes)
    for k in range(cur.n_modes):
        j = int(np.argmin(np.abs(prev.frequencies_hz - cur.frequencies_hz[k])))
        df = abs(cur.frequencies_hz[k] - prev.frequencies_hz[j]) / max(prev.frequencies_hz[j],
                                                                        1e-300)
        if df > tol_f:
            continue
        match[k] = j
        dz = abs(cur.damping[k] - prev.damping[j]) / max(prev.damping[j], 1e-300)
        d_ok, v_ok = dz <= tol_zeta, macs[k, j] >= tol_mac
        status[k] = "s" if d_ok and v_ok else "fd" if d_ok else "fv" if v_ok else "f"
    return (status, match) if return_match else status


def stabilisation(u, y, dt: float, orders, identify=None, tol_f: float = 0.01,
                  tol_zeta: float = 0.05, tol_mac: float = 0.98, progress=None,
                  input_names=None, output_names=None) -> Stabilisation:
    """Identify at each order and mark every pole stable in frequency, damping and shape.

    Parameters
    ----------
    u : ndarray, shape (N, m)
    y : ndarray, shape (N, p)
    dt : float
        Sampling interval [s].
    orders : sequence of int
        Model orders, ascending.
    identify : callable, optional
        ``identify(u, y, order, dt) -> control.StateSpace``; default PLID
        (:func:`trussid.plid.multipass.identify`, its ``.model``).
    tol_f, tol_zeta : float
        Largest relative change of frequency and of damping from the nearest pole one
        order step below for the pole to count as stable in them (defaults 1 % and 5 %, the
        usual values of modal-analysis software).
    tol_mac : float
        Lowest MAC of the shape with that pole's (default 0.98).
    progress : bool or None
        tqdm bar over the orders (None: only on a terminal).
    input_names, output_names : list of str, optional
        Labels of the shapes and participation factors.

    Returns
    -------
    Stabilisation
        An order whose identification fails (:class:`IdentificationError` or
        :class:`DataError`) is listed in ``failed`` with the reason, and the next order is
        compared with the last one that worked.
    """
    import control
    from tqdm.auto import tqdm

    if identify is None:
        from trussid.plid.multipass import identify as plid_identify

        def identify(u_, y_, n_, dt_):
            return plid_identify(u_, y_, n_, dt_, progress=False).model

    orders = [int(n) for n in orders]
    if not orders or sorted(orders) != orders or orders[0] < 1:
        raise IdentificationError(f"stabilisation orders must be ascending positive "
                                  f"integers, got {orders}")
    res = Stabilisation(orders=[], modes=[], status=[],
                        tolerances={"f": tol_f, "damping": tol_zeta, "mac": tol_mac})
    prev = None
    bar = tqdm(orders, desc="stabilisation", unit="order", disable=progress is False
               if progress is not None else None, leave=False)
    for n in bar:
        t0 = time.perf_counter()
        try:
            model = identify(u, y, n, dt)
        except (IdentificationError, DataError) as exc:
            res.failed.append((n, str(exc)))
            continue
        if output_names is not None or input_names is not None:
            model = control.ss(model.A, model.B, model.C, model.D, model.dt,
                               inputs=input_names, outputs=output_names)
        modes = modal_table(model, physical_only=True)
        res.orders.append(n)
        res.modes.append(modes)
        status, match = mark_stability(prev, modes, tol_f, tol_zeta, tol_mac, True)
        run_prev = res.runs[-1] if res.runs else np.zeros(0, int)
        res.status.append(status)
        res.runs.append(np.array([run_prev[j] + 1 if st == "s" else 0
                                  for st, j in zip(status, match)], dtype=int))
        res.models.append(model)
        res.seconds.append(time.perf_counter() - t0)
        prev = modes
    bar.close()
    if not res.orders:
        raise IdentificationError("no order gave a model: " + "; ".join(
            f"order {n}: {why}" for n, why in res.failed))
    return res
