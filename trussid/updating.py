"""FE model updating: the six strut wall thicknesses (and modal damping) from identified modes.

Composition layer over :mod:`trussid.fem` (the testbed model, its wall basis and analytic wall
sensitivities), :mod:`trussid.geometry` (the testbed parameters) and :mod:`trussid.plid` (the grey-box
least-squares machinery and the identified models)::

    measured modes (f, zeta, shapes at sensors)  ---pairing--->  model modes at walls t
    residual r_i = (f_model,pair(i)(t) - f_i) / sigma_i ,  Jacobian d f / d t  (fem.sensitivity)
    plid.greybox.fit_parameters(r, walls, bounds, jac)  ->  walls, intervals, identifiability

Which modes carry wall information
----------------------------------
A strut's first bending pair (two planes, nearly equal frequencies) depends almost only on
that strut's wall (``d ln f / d ln t`` about 0.14 to 0.31), so the 12 bending modes fix the
six walls *as a set*: geometrically the six struts are equivalent, and swapping two walls
leaves the bending frequencies nearly unchanged. Which wall belongs to which strut is told by
(a) mode shapes (a sensor on each strut: MAC pairing), or (b) the UDF rigid-body modes,
which depend on the struts' axial stiffness with a different weight per strut. With
frequencies alone, include the UDF modes; the global search below then finds the assignment.

Pairing measured to model modes
-------------------------------
The bending modes lie close together and reorder when walls change, so pairing is redone at
every evaluation of the residual (a linear assignment, :func:`pair_modes`), by frequency
distance and, when identified shapes at known sensors are given, by MAC. Before fitting,
measured modes that no model mode can reach are dropped: model mode ``j`` may move by about
``|df_j/dt| * prior_range * t`` (sensitivity-aware gate) within the prior wall range.

Two stages (why: an eigen-solution of the full 372-DOF model costs ~0.1-0.4 s, too much for
a global search):

1. *Global*, on a Ritz-reduced model (the lowest modes at the nominal walls and at all walls
   scaled by 0.85 and 1.15 as a basis, carried
   as a :class:`trussid.testbed.model.WallBasis` so that :func:`trussid.testbed.model.wall_modes` and
   :func:`trussid.testbed.sensitivity.eigenvalue_sensitivities` apply unchanged; frequency error about
   3e-7 relative for walls within +-15 %): :func:`trussid.plid.greybox.fit_parameters` with its
   seeded multi-start over the prior box ``nominal * (1 +- prior_range)``, then pairwise
   wall exchanges as further starts (:func:`_global_fit`): each arrangement of walls over
   the equivalent struts is its own local minimum. Exchanges that fit as well as the best
   are reported (the modes do not tell those struts apart).
2. *Local*, on the full model, from the stage-1 estimate, within the physical bounds: the
   estimate, the identifiability analysis and the intervals.

Intervals
---------
With measured-frequency standard deviations ``frequency_std_hz`` (from PLID's parameter
covariance or the scatter over sub-records, :func:`modes_from_data`), the residuals are in units
of sigma, and the walls' covariance is ``(J^T J)^-1`` in ``ln t`` (known-sigma, normal
quantile), inflated by the Birge ratio ``sqrt(chi2 / dof)`` when the fit is worse than the
stated sigmas explain. Without them, residuals are relative frequency errors and the
intervals are :mod:`trussid.plid.greybox`'s (from the residual scatter).

Measured on the bending test below (16000 samples, 40 dB): PLID's covariance gives
frequency sigmas of about 1e-4 Hz, yet each identified pole sits about 0.005 Hz from the
model mode it is paired with, because it blends the strut's two bending planes (0.05-0.1 Hz
apart, inside the 0.25 Hz half-power bandwidth). The statistical sigma alone would give
intervals that miss; the unresolved-mode term (``unresolved_sigma``, about 0.03-0.06 Hz
here; 0.14 Hz where two struts' bending pairs overlap) is what makes them honest, at the
price of 95 % wall intervals of about +-0.4 % to +-9 %.

Damping: the model's damping is one modal ratio (``Testbed.damping.modal_ratio``); it does
not depend on the walls, so its estimate is the (inverse-variance weighted) mean of the
paired modes' identified damping ratios, with a t-interval from their scatter or, when
larger, from the stated standard deviations (for a mode blended with unresolved
neighbours, these include ``span / (2 f sqrt 3)``: a blend looks more damped).

Which experiment
----------------
The lab plant (extension drive, UDF accelerometers) hardly sees the strut bending modes.
:func:`trussid.testbed.plant.testbed_plant` with ``arrangement="bending", sensors="struts"``
is the test suited to updating: all wafers driven in
anti-phase (bending) from one channel, a lateral sensor on each strut; a SIMO PLID model of
its data gives one strong mode per strut, with a shape that names the strut.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import control
import numpy as np
import scipy.linalg as la
import scipy.optimize
import scipy.stats

from trussid._util.errors import UserError
from trussid.plid.errors import DataError
from trussid.plid.modal import mac as modal_assurance
from trussid.plid.modal import mode_groups, pair_modes, pole_parameters, pole_std

__all__ = [
    "UpdateError",
    "IdentifiedModes",
    "UpdateReport",
    "reduced_wall_basis",
    "modes_of_model",
    "modes_from_data",
    "update_walls",
    "WALL_NAMES",
]

#: Parameter names of the six walls (strut numbering of :mod:`trussid.testbed.model`, 0..5).
WALL_NAMES = tuple(f"wall{i}" for i in range(6))
#: Default physical bounds on each wall, as multiples of its nominal value.
DEFAULT_BOUNDS = (0.5, 1.5)
#: A wall never gets closer than this fraction of the outer radius to 0 or to the radius.
RADIUS_MARGIN = 0.02


class UpdateError(UserError):
    """Bad input to model updating (the message names the offending item)."""


# --------------------------------------------------------------------------- data


@dataclass(frozen=True)
class IdentifiedModes:
    """Modes extracted from an identified model (or given by the user).

    Attributes
    ----------
    frequencies_hz : (k,) float
        Natural frequencies [Hz], ascending.
    damping : (k,) float
        Damping ratios [-].
    shapes : (p, k) complex or None
        Mode shapes at the model's outputs (``C v``), unit norm.
    strength : (k,) float
        Peak modal contribution ``|C v| |w^H B| / |Re s|`` (largest singular value of the
        mode's residue over its half-power bandwidth), to tell real modes from noise modes.
    frequency_std_hz, damping_std : (k,) float or None
        Standard deviations of the estimates.
    output_names : tuple of str
    """

    frequencies_hz: np.ndarray
    damping: np.ndarray
    shapes: np.ndarray | None = None
    strength: np.ndarray | None = None
    frequency_std_hz: np.ndarray | None = None
    damping_std: np.ndarray | None = None
    output_names: tuple = ()

    def select(self, idx) -> "IdentifiedModes":
        """The modes at indices ``idx``."""
        idx = np.asarray(idx, dtype=int)

        def pick(a, axis=0):
            return None if a is None else np.take(a, idx, axis=axis)

        return IdentifiedModes(self.frequencies_hz[idx], self.damping[idx], pick(self.shapes, 1),
                               pick(self.strength), pick(self.frequency_std_hz), pick(self.damping_std),
                               self.output_names)


@dataclass
class UpdateReport:
    """Result of :func:`update_walls`.

    Attributes
    ----------
    walls, nominal : (6,) float
        Updated and nominal wall thicknesses [m].
    intervals : (6, 2) float
        ``confidence`` intervals [m]; NaN where none (wall on a bound, undetermined).
    std_log : (6,) float
        Standard error of ``ln t`` (NaN where none).
    interval_source : str
        ``"known sigma"`` (from ``frequency_std_hz``) or ``"residual scatter"``.
    measured_hz : (k,) float
        All measured frequencies given.
    used : (k,) bool
        Measured modes paired with a model mode (the others could not be reached).
    pairing : (k,) int
        Index (ascending order, at the updated walls) of the paired model mode; -1 unused.
    model_hz : (k,) float
        Paired model frequencies at the updated walls (NaN unused).
    nominal_hz : (k,) float
        Paired model frequencies at the nominal walls (NaN unused).
    labels : list of str
        Labels of the paired model modes (:func:`trussid.testbed.labels.label_testbed_modes`), "" unused.
    mac : (k,) float or None
        MAC of each pair when shapes were given.
    chi2, dof, birge : float, int, float
        ``sum r^2`` at the estimate (residuals in sigma units, or relative without sigma),
        degrees of freedom, ``sqrt(chi2 / dof)``.
    damping, damping_interval : float or None, (2,) or None
        Modal damping estimate and its interval.
    greybox : plid.greybox.GreyboxReport
        Stage-2 fit (full model).
    coarse : plid.greybox.GreyboxReport
        Stage-1 fit (reduced model, multi-start).
    confidence : float
    sigma_hz : (k,) float or None
        Frequency standard deviations used in the fit [Hz] (stated, with the
        unresolved-mode term), NaN for unused modes; None without stated sigmas.
    unresolved_hz : (k,) float or None
        The unresolved-close-mode part of ``sigma_hz``.
    """

    walls: np.ndarray
    nominal: np.ndarray
    intervals: np.ndarray
    std_log: np.ndarray
    interval_source: str
    measured_hz: np.ndarray
    used: np.ndarray
    pairing: np.ndarray
    model_hz: np.ndarray
    nominal_hz: np.ndarray
    labels: list
    mac: np.ndarray | None
    chi2: float
    dof: int
    birge: float
    damping: float | None
    damping_interval: tuple | None
    greybox: object
    coarse: object
    confidence: float = 0.95
    sigma_hz: np.ndarray | None = None
    unresolved_hz: np.ndarray | None = None
    info: dict = field(default_factory=dict)

    def covers(self, truth) -> np.ndarray:
        """Whether each interval contains ``truth`` (False where there is none)."""
        t = np.asarray(truth, float)
        lo, hi = self.intervals[:, 0], self.intervals[:, 1]
        return np.isfinite(lo) & (lo <= t) & (t <= hi)

    def table(self, truth=None) -> str:
        """Walls (in inches and relative to nominal) and the mode pairs, as text."""
        inch = 0.0254
        pct = f"{100 * self.confidence:g} %"
        head = f"{'strut':>5} {'nominal [in]':>13} {'updated [in]':>13} {pct + ' interval [in]':>26}"
        if truth is not None:
            head += f" {'true [in]':>11} {'rel. error':>11} {'covered':>8}"
        lines = [f"walls ({self.interval_source} intervals)", head]
        for i in range(6):
            lo, hi = self.intervals[i]
            iv = f"[{lo / inch:.5f}, {hi / inch:.5f}]" if np.isfinite(lo) else "-"
            row = f"{i:>5} {self.nominal[i] / inch:>13.5f} {self.walls[i] / inch:>13.5f} {iv:>26}"
            if truth is not None:
                t = float(np.asarray(truth)[i])
                row += (f" {t / inch:>11.5f} {self.walls[i] / t - 1:>+11.2e}"
                        f" {'yes' if self.covers(truth)[i] else 'NO':>8}")
            lines.append(row)
        lines.append("")
        lines.append(f"{'mode':>4} {'measured [Hz]':>14} {'nominal [Hz]':>13} {'updated [Hz]':>13}"
                     f"{'  MAC' if self.mac is not None else ''}  model mode")
        for k in range(len(self.measured_hz)):
            if not self.used[k]:
                lines.append(f"{k:>4} {self.measured_hz[k]:>14.4f} {'-':>13} {'-':>13}  not paired")
                continue
            mac = f" {self.mac[k]:.3f}" if self.mac is not None else ""
            lines.append(f"{k:>4} {self.measured_hz[k]:>14.4f} {self.nominal_hz[k]:>13.4f} "
                         f"{self.model_hz[k]:>13.4f}{mac}  {self.labels[k]}")
        lines.append(f"chi2 {self.chi2:.4g} on {self.dof} dof (Birge ratio {self.birge:.3g})")
        if self.damping is not None:
            iv = self.damping_interval
            lines.append(f"modal damping {100 * self.damping:.4f} % "
                         f"[{100 * iv[0]:.4f}, {100 * iv[1]:.4f}] %")
        amb = self.info.get("ambiguous_swaps") or []
        if amb:
            lines.append("exchanging the walls of struts " + ", ".join(f"{i}<->{j}" for i, j in amb)
                         + " fits as well: these modes do not tell those struts apart")
        und = getattr(self.greybox, "undetermined", ())
        if und:
            lines.append("NOT determined by these modes: " + "; ".join(c.name for c in und))
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        def fl(a):
            return [None if not np.isfinite(v) else float(v) for v in np.ravel(a)]

        return {
            "walls": fl(self.walls), "nominal": fl(self.nominal),
            "intervals": [fl(r) for r in self.intervals], "interval_source": self.interval_source,
            "measured_hz": fl(self.measured_hz), "used": [bool(u) for u in self.used],
            "pairing": [int(p) for p in self.pairing], "model_hz": fl(self.model_hz),
            "labels": list(self.labels), "chi2": self.chi2, "dof": self.dof, "birge": self.birge,
            "damping": self.damping,
            "damping_interval": None if self.damping_interval is None else list(self.damping_interval),
            "undetermined": [c.name for c in getattr(self.greybox, "undetermined", ())],
            "ambiguous_swaps": [list(ij) for ij in self.info.get("ambiguous_swaps") or []],
        }


# --------------------------------------------------------------------------- model side


def reduced_wall_basis(basis, n_vectors: int = 40, designs=(1.0, 0.85, 1.15)):
    """A Ritz-reduced copy of a :class:`trussid.testbed.model.WallBasis`.

    The reduced DOFs are the amplitudes of ``V``: the lowest ``n_vectors`` modes of the
    model at each of ``designs`` (all walls scaled by the factor), orthonormalised. Every
    matrix of the basis is projected, ``V^T B V``, and stored densely (the pattern is all
    ``(r, c)``), so the public :func:`trussid.testbed.model.wall_modes` and
    :func:`trussid.testbed.sensitivity.eigenvalue_sensitivities` work on it unchanged. The basis stays
    affine in the tube properties, hence exact in how the walls enter; its only error is
    the Ritz error of the fixed subspace. Modes at the scaled designs are included because
    a strut's bending shape changes with its wall (its share of the adapter mass and
    stiffness): with the nominal modes alone the error was 4e-4 relative on the lowest 24
    modes of the calibrated testbed for walls within +-15 %, with the three designs 3e-7.

    Returns
    -------
    reduced : fem.testbed.WallBasis
    V : (n, r) float
        The projection (reduced shapes ``q`` expand to ``V q``).
    """
    from trussid.testbed.model import wall_matrices

    k = min(int(n_vectors), basis.n)
    cols = []
    for d in designs:
        w = np.clip(np.asarray(basis.walls_ref) * d, 0.02 * basis.r_out, 0.98 * basis.r_out)
        K, M = wall_matrices(basis, w)
        cols.append(la.eigh(K, M, subset_by_index=[0, k - 1], driver="gvx", check_finite=False)[1])
    U, sv, _ = np.linalg.svd(np.hstack(cols), full_matrices=False)
    V = U[:, sv > 1e-10 * sv[0]]  # drop (numerically) repeated directions
    r = V.shape[1]

    def proj(data):
        return (V.T @ (basis.sparse(data) @ V)).ravel()

    rr, cc = np.divmod(np.arange(r * r), r)
    reduced = replace(
        basis, n=r, rows=rr, cols=cc, K_ref=proj(basis.K_ref), M_ref=proj(basis.M_ref),
        KA=np.array([proj(d) for d in basis.KA]), KI=np.array([proj(d) for d in basis.KI]),
        MA=np.array([proj(d) for d in basis.MA]), MI=np.array([proj(d) for d in basis.MI]),
    )
    return reduced, V


class _ModelModes:
    """Frequencies, wall sensitivities and sensor shapes of a (full or reduced) wall basis,
    with a one-entry cache (the residual and its Jacobian ask at the same walls)."""

    def __init__(self, basis, n_modes: int, sensor_rows: np.ndarray | None):
        self.basis, self.n_modes, self.rows = basis, n_modes, sensor_rows
        self._key, self._val = None, None
        self.evaluations = 0

    def __call__(self, walls):
        from trussid.testbed.model import wall_modes
        from trussid.testbed.sensitivity import eigenvalue_sensitivities

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


# --------------------------------------------------------------------------- identified side


def modes_of_model(sys, band=None, *, max_damping: float = 0.2, min_damping: float = 0.0,
                   theta_cov=None) -> IdentifiedModes:
    """Modes of an identified (discrete or continuous) ``control.StateSpace``.

    One mode per complex-conjugate pole pair with a positive imaginary part; frequency
    ``|s| / 2 pi`` and damping ``-Re s / |s|`` with ``s = ln z / dt`` for a discrete model;
    shape ``C v`` (unit norm) at the outputs; strength ``|C v| |w^H B| / |Re s|``.

    Parameters
    ----------
    sys : control.StateSpace
    band : (low, high) Hz, optional
        Keep modes with frequencies in this band.
    max_damping : float
        Drop modes more damped than this (noise and filter poles).
    min_damping : float
        Drop modes damped less than this (default: unstable poles, which no structure has).
    theta_cov : (n (p + m), n (p + m)) array, optional
        Posterior covariance of a PLID model's ``theta = [vec(Abar); vec(B)]``
        (:class:`trussid.plid.estimator.PLIDResult`, where ``A = F + Abar C`` with ``F``, ``C``
        fixed): gives first-order standard deviations of frequency and damping. With
        right/left eigenvectors ``v``, ``w`` of ``A``, ``d z = w^H dAbar C v / (w^H v)``,
        then ``s = ln z / dt``, ``f = |s| / 2 pi``, ``zeta = -Re s / |s|``.
    """
    A = np.asarray(sys.A, float)
    B = np.asarray(sys.B, float)
    C = np.asarray(sys.C, float)
    if A.shape[0] == 0:
        raise UpdateError("the identified model has no states")
    lam, W, V = la.eig(A, left=True, right=True)
    keep = lam.imag > 1e-12 * np.maximum(np.abs(lam), 1e-300)
    lam, W, V = lam[keep], W[:, keep], V[:, keep]
    dt = sys.dt if control.isdtime(sys, strict=True) else None
    f, z, s = pole_parameters(lam, dt)
    sel = (z < max_damping) & (z > min_damping)
    if band is not None:
        sel &= (f >= band[0]) & (f <= band[1])
    cv = C @ V
    wb = W.conj().T @ B / np.sum(W.conj() * V, axis=0)[:, None]  # left vectors scaled: w^H v = 1
    # the mode's residue C v w^H B, here with discrete poles; at its peak the continuous
    # contribution is about residue / (dt |Re s|) -- only the ranking matters
    strength = np.linalg.norm(cv, axis=0) * np.linalg.norm(wb, axis=1) / np.maximum(np.abs(s.real), 1e-300)
    order = np.argsort(f[sel])
    idx = np.flatnonzero(sel)[order]
    shapes = cv[:, idx] / np.maximum(np.linalg.norm(cv[:, idx], axis=0), 1e-300)
    names = tuple(getattr(sys, "output_labels", ()) or ())
    fstd = zstd = None
    if theta_cov is not None:
        try:
            fstd, zstd = pole_std(lam[idx], s[idx], V[:, idx], W[:, idx], cv[:, idx], theta_cov, dt)
        except DataError as exc:
            raise UpdateError(str(exc)) from None
    return IdentifiedModes(f[idx], z[idx], shapes, strength[idx], fstd, zstd, names)


def modes_from_data(u, y, dt: float, order: int, *, band, n_modes: int | None = None,
                    uncertainty: str = "plid", n_segments: int = 4, max_damping: float = 0.05,
                    identify_kwargs=None):
    """Identify a model with PLID and extract its strongest modes, with uncertainties.

    The record is identified with :func:`trussid.plid.multipass.identify`; its ``n_modes``
    strongest modes in ``band`` are the estimates. Their standard deviations come from

    - ``uncertainty="plid"``: PLID's posterior parameter covariance, propagated to each
      pole to first order (:func:`modes_of_model`); no extra identification;
    - ``uncertainty="segments"``: the record is cut into ``n_segments`` equal pieces, each
      identified alone; a mode's standard deviation is the scatter of the matching segment
      modes divided by ``sqrt(n_segments)`` (the variance of a frequency estimate falls as
      1 / record length). A segment mode matches when it is the nearest in frequency and
      within 5 half-power bandwidths; a mode with fewer than 2 matches gets NaN.

    Parameters
    ----------
    u, y : (N, m), (N, p) arrays
    dt : float
        Sample time [s].
    order : int
        Model order (a multiple of the number of outputs).
    band : (low, high) Hz
    n_modes : int, optional
        Keep this many strongest modes (default all in band).
    uncertainty : {"plid", "segments", "none"}
    n_segments : int
    max_damping : float
    identify_kwargs : dict, optional
        Passed to :func:`trussid.plid.multipass.identify` (default here ``form="sqrt"``).

    Returns
    -------
    modes : IdentifiedModes
    info : dict
        ``identification`` (full record), ``segment_models``, ``std_fallback`` (modes
        whose PLID variance was not positive and took the largest of the others).
    """
    import warnings

    from trussid.plid.estimator import PLIDWarning
    from trussid.plid.multipass import identify

    if uncertainty not in ("plid", "segments", "none"):
        raise UpdateError(f"uncertainty must be 'plid', 'segments' or 'none', got {uncertainty!r}")
    u = np.asarray(u, float).reshape(len(u), -1)
    y = np.asarray(y, float).reshape(len(y), -1)
    # the square-root form: on one of five 16000-sample bending records the direct form
    # (identify's default) diverged to unstable poles; the square-root one did not
    kw = {"form": "sqrt", **(identify_kwargs or {})}

    def ident(uu, yy):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PLIDWarning)
            return identify(uu, yy, order, dt, **kw)

    full = ident(u, y)
    modes = modes_of_model(full.model, band, max_damping=max_damping,
                           theta_cov=full.result.theta_cov if uncertainty == "plid" else None)
    if n_modes is not None and len(modes.frequencies_hz) > n_modes:
        strongest = np.sort(np.argsort(modes.strength)[::-1][:n_modes])
        modes = modes.select(strongest)
    fallback = []
    if uncertainty == "plid":
        # a pole whose propagated variance is not positive (the covariance lost
        # definiteness) takes the largest standard deviation of the others: conservative
        fs, zs = modes.frequency_std_hz.copy(), modes.damping_std.copy()
        for a in (fs, zs):
            bad = ~(np.isfinite(a) & (a > 0))
            if bad.any() and (~bad).any():
                a[bad] = a[~bad].max()
            fallback += np.flatnonzero(bad).tolist()
        modes = replace(modes, frequency_std_hz=fs, damping_std=zs)
    seg_models = []
    if uncertainty == "segments":
        if n_segments < 2:
            raise UpdateError(f"n_segments must be at least 2, got {n_segments}")
        n = len(u) // n_segments
        k = len(modes.frequencies_hz)
        fs_seg, zs_seg = np.full((n_segments, k), np.nan), np.full((n_segments, k), np.nan)
        for q in range(n_segments):
            sl = slice(q * n, (q + 1) * n)
            mk = ident(u[sl], y[sl]).model
            seg_models.append(mk)
            sm = modes_of_model(mk, band, max_damping=max_damping)
            if not len(sm.frequencies_hz):
                continue
            j = pair_modes(modes.frequencies_hz, sm.frequencies_hz)
            for i, jj in enumerate(j):
                bw = 2 * max(modes.damping[i], 1e-4) * modes.frequencies_hz[i]
                if jj >= 0 and abs(sm.frequencies_hz[jj] - modes.frequencies_hz[i]) <= 5 * bw:
                    fs_seg[q, i], zs_seg[q, i] = sm.frequencies_hz[jj], sm.damping[jj]
        cnt = np.sum(np.isfinite(fs_seg), axis=0)
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            fstd = np.where(cnt >= 2, np.nanstd(fs_seg, axis=0, ddof=1), np.nan) / math.sqrt(n_segments)
            zstd = np.where(cnt >= 2, np.nanstd(zs_seg, axis=0, ddof=1), np.nan) / math.sqrt(n_segments)
        modes = replace(modes, frequency_std_hz=fstd, damping_std=zstd)
    return modes, {"identification": full, "segment_models": seg_models,
                   "std_fallback": sorted(set(fallback))}


# --------------------------------------------------------------------------- experiment


# --------------------------------------------------------------------------- updating


def _vector(name, value, k, positive=True):
    a = np.asarray(value, float)
    if a.ndim == 0:
        a = np.full(k, float(a))
    a = a.ravel()
    if a.size != k:
        raise UpdateError(f"{name} has {a.size} entries for {k} measured modes")
    bad = np.flatnonzero(~np.isfinite(a) | ((a <= 0) if positive else (a < 0)))
    if bad.size:
        raise UpdateError(f"{name}[{bad[0]}] = {a[bad[0]]!r} must be finite and "
                          f"{'positive' if positive else 'non-negative'}")
    return a


def _wall_bounds(bounds, nominal, r_out):
    if bounds is None:
        bounds = DEFAULT_BOUNDS
    b = np.asarray(bounds, float)
    if b.shape == (2,):
        b = np.outer(nominal, b)  # relative to nominal
    elif b.shape != (6, 2):
        raise UpdateError(f"bounds must be (low, high) relative to nominal or a (6, 2) array in m, "
                          f"got shape {b.shape}")
    lo = np.maximum(b[:, 0], RADIUS_MARGIN * r_out)
    hi = np.minimum(b[:, 1], (1 - RADIUS_MARGIN) * r_out)
    for i in range(6):
        if not lo[i] < hi[i]:
            raise UpdateError(f"bounds of wall{i}: lower {lo[i]:.4g} m is not below upper {hi[i]:.4g} m "
                              f"(walls must lie in (0, {r_out:.4g} m))")
        if not lo[i] <= nominal[i] <= hi[i]:
            raise UpdateError(f"bounds of wall{i} [{lo[i]:.4g}, {hi[i]:.4g}] m exclude its nominal "
                              f"value {nominal[i]:.4g} m")
    return lo, hi


def _cluster_span(F, j, bandwidth):
    """Frequency span of the chain of modes around ``F[j]`` with gaps below ``bandwidth``."""
    Fs = np.sort(F)
    i = int(np.searchsorted(Fs, F[j]))
    lo = hi = i
    while lo > 0 and Fs[lo] - Fs[lo - 1] < bandwidth:
        lo -= 1
    while hi < Fs.size - 1 and Fs[hi + 1] - Fs[hi] < bandwidth:
        hi += 1
    return float(Fs[hi] - Fs[lo])


def _scatter(values, idx, k_all):
    if values is None:
        return None
    out = np.full(k_all, np.nan)
    out[idx] = values
    return out


def _global_fit(residual, jac, initial, lo, hi, n_starts, seed, confidence, known_sigma=False):
    """Seeded multi-start fit, then swap moves.

    The struts are geometrically equivalent, so exchanging two walls leaves the strut
    bending frequencies (nearly) unchanged and only the modes that see all struts (UDF
    rigid-body) tell the arrangements apart: each arrangement is a separate local minimum,
    and random starts find the right one only by luck. After the multi-start, every
    pairwise exchange of the current estimate is therefore tried as a start, and the best
    fit kept, until no exchange improves the fit.

    Returns the best :class:`trussid.plid.greybox.GreyboxReport`, the accepted swaps, and the
    exchanges whose refitted cost is statistically as good as the best (likelihood-ratio
    threshold; with unknown sigma, the residual variance of the best fit): an arrangement
    the data cannot decide.
    """
    from trussid.plid.greybox import fit_parameters

    bnds = {n: (a, b) for n, a, b in zip(WALL_NAMES, lo, hi)}
    best = fit_parameters(residual, initial, bounds=bnds, jac=jac, n_starts=n_starts, seed=seed,
                          confidence=confidence, min_obs=1)
    accepted = []
    for _ in range(6):  # each accepted swap lowers the cost; a few rounds at most
        cur = np.array([best.estimates[n] for n in WALL_NAMES])
        cands = []
        for i in range(6):
            for j in range(i + 1, 6):
                w = cur.copy()
                w[i], w[j] = cur[j], cur[i]
                w = np.clip(w, lo * (1 + 1e-9), hi * (1 - 1e-9))
                r = residual(dict(zip(WALL_NAMES, w)))
                cands.append((0.5 * float(r @ r), (i, j), w))
        # An exchange keeps the strut-bending frequencies, so its cost before refitting
        # already ranks it; refit the exchanges that start below the current fit, or the
        # three best when none does (the refit may still find a lower minimum).
        cands.sort(key=lambda c: c[0])
        trial = [c for c in cands if c[0] < best.cost] or cands[:3]
        improved = False
        refits = []
        for _, ij, w in trial:
            rep = fit_parameters(residual, dict(zip(WALL_NAMES, w)), bounds=bnds, jac=jac,
                                 n_starts=1, confidence=confidence, min_obs=1)
            refits.append(([rep.estimates[n] for n in WALL_NAMES], ij, rep.cost))
            if rep.cost < best.cost * (1 - 1e-6) - 1e-16:  # not round-off
                best, improved, ij_best = rep, True, ij
        if not improved:
            break
        accepted.append(ij_best)
    n_obs = residual(best.estimates).size
    s2 = 1.0 if known_sigma else 2 * best.cost / max(n_obs - 6, 1)
    thresh = 0.5 * s2 * scipy.stats.chi2.ppf(confidence, 1)
    ambiguous = [ij for c, ij, rep_c in refits if rep_c - best.cost <= thresh and
                 not np.allclose(c, [best.estimates[n] for n in WALL_NAMES], rtol=1e-6)]
    return best, accepted, ambiguous


def _intervals(known_sigma, dFj, sig, walls, chi2, dof, rep, confidence):
    """Wall intervals in ln t: from known sigmas (inflated by the Birge ratio when the fit is
    worse than they say), or from the residual scatter of the fit ``rep``.

    Returns ``(intervals (6, 2) [m], std_log (6,), birge, source)``.
    """
    intervals = np.full((6, 2), np.nan)
    std_log = np.full(6, np.nan)
    if known_sigma:
        jl = (dFj / sig[:, None]) * walls[None, :]
        birge = math.sqrt(chi2 / dof) if dof > 0 else 1.0
        infl = max(1.0, birge)
        try:
            cov = la.inv(jl.T @ jl) * infl**2
            ok = np.isfinite(cov).all()
        except la.LinAlgError:
            ok = False
        zq = scipy.stats.norm.ppf(0.5 + confidence / 2)
        for i, n in enumerate(WALL_NAMES):
            if ok and rep.determined.get(n, True) and n not in rep.at_bound:
                std_log[i] = math.sqrt(max(cov[i, i], 0.0))
                intervals[i] = walls[i] * np.exp([-zq * std_log[i], zq * std_log[i]])
        source = "known sigma"
    else:
        birge = math.sqrt(chi2 / dof) if dof > 0 else float("nan")
        for i, n in enumerate(WALL_NAMES):
            iv = rep.intervals.get(n)
            if iv is not None:
                intervals[i] = iv
                se = rep.std_errors.get(n)
                std_log[i] = se if se is not None else np.nan
        source = "residual scatter"
    return intervals, std_log, birge, source


def _damping_estimate(z_all, zsig_all, used, unres, f, confidence):
    """One modal damping ratio, the weighted mean of the paired modes' ratios, and its
    interval; ``(None, None)`` without measured damping."""
    k = f.size
    zeta = ziv = None
    if z_all is not None:
        zz = z_all[used]
        # a blend of modes within the bandwidth looks more damped: up to span / 2f
        zs = np.sqrt((zsig_all[used] if zsig_all is not None else 0.0) ** 2 + (unres / (2 * f)) ** 2)
        w = 1.0 / zs**2 if np.all(zs > 0) else np.ones(k)
        zeta = float(np.sum(w * zz) / np.sum(w))
        scatter = math.sqrt(float(np.sum(w * (zz - zeta) ** 2) / np.sum(w) / max(k - 1, 1)))
        stated = math.sqrt(1.0 / float(np.sum(w))) if np.all(zs > 0) else 0.0
        se = max(scatter, stated)
        tq = scipy.stats.t.ppf(0.5 + confidence / 2, max(k - 1, 1))
        ziv = (zeta - tq * se, zeta + tq * se)
    return zeta, ziv


def _checked_inputs(measured_freqs_hz, frequency_std_hz, damping, damping_std, shapes, sensors,
                    prior_range, confidence):
    """The measured data of :func:`update_walls` as arrays, each mistake named."""
    f_all = _vector("measured_freqs_hz", measured_freqs_hz, np.size(measured_freqs_hz))
    k_all = f_all.size
    known_sigma = frequency_std_hz is not None
    sig_all = _vector("frequency_std_hz", frequency_std_hz, k_all) if known_sigma else None
    z_all = _vector("damping", damping, k_all, positive=False) if damping is not None else None
    zsig_all = (_vector("damping_std", damping_std, k_all) if damping_std is not None else None)
    if not 0 < prior_range < 1:
        raise UpdateError(f"prior_range must be in (0, 1), got {prior_range!r}")
    if not 0 < confidence < 1:
        raise UpdateError(f"confidence must be in (0, 1), got {confidence!r}")
    if (shapes is None) != (sensors is None):
        raise UpdateError("give shapes and sensors together (MAC pairing needs both)")
    sh_all = None
    if shapes is not None:
        sh_all = np.asarray(shapes, complex)
        if sh_all.ndim != 2 or sh_all.shape != (len(sensors), k_all):
            raise UpdateError(f"shapes must be (n_sensors={len(sensors)}, n_modes={k_all}), "
                              f"got {sh_all.shape}")
    return f_all, sig_all, z_all, zsig_all, sh_all


def update_walls(measured_freqs_hz, tb_nominal=None, *, damping=None, frequency_std_hz=None,
                 damping_std=None, shapes=None, sensors=None, tbm=None, n_model_modes: int | None = None,
                 bounds=None, prior_range: float = 0.2, gate: float = 3.0, n_starts: int = 8,
                 seed: int = 0, confidence: float = 0.95, reduced_vectors: int = 40,
                 mac_weight: float = 1.0, unresolved_sigma: bool = True,
                 labels: bool = True, threads: int | None = 1) -> UpdateReport:
    """Estimate the six strut wall thicknesses from measured natural frequencies.

    Parameters
    ----------
    measured_freqs_hz : (k,) float
        Identified natural frequencies [Hz] (any order; modes of any kind: strut bending,
        UDF rigid-body, ...). At least 7 are needed when ``frequency_std_hz`` is not given
        (6 walls plus a degree of freedom for the scatter).
    tb_nominal : geometry.testbed.Testbed, optional
        The model to update (default: the default testbed); its walls are the start.
    damping : (k,) float, optional
        Identified damping ratios [-] of the same modes: gives the damping estimate.
    frequency_std_hz : float or (k,) float, optional
        Standard deviations of the measured frequencies [Hz]: residual weights and
        known-sigma intervals. Default: relative residuals, intervals from their scatter.
    damping_std : float or (k,) float, optional
        Standard deviations of ``damping``.
    shapes : (p, k) complex, optional
        Identified mode shapes at ``sensors`` (for MAC pairing).
    sensors : list of fem.sensors.Sensor, optional
        Where ``shapes`` were measured (any quantity: MAC ignores scale).
    tbm : fem.testbed.TestbedModel, optional
        ``build_testbed(tb_nominal)`` if already built (Euler-Bernoulli).
    n_model_modes : int, optional
        Model modes considered for pairing (default: those up to 1.5 times the highest
        measured frequency, plus 4).
    bounds : (low, high) or (6, 2) array, optional
        Physical bounds: relative to nominal (default ``(0.5, 1.5)``) or per wall in m;
        always inside ``(0.02, 0.98)`` times the outer radius.
    prior_range : float
        Relative wall range expected before the test (``+-prior_range``): the box of the
        stage-1 multi-start and the reach of the pairing gate.
    gate : float
        A measured mode is paired only with model modes within ``gate`` times their reach
        ``|df/dt| prior_range t`` (plus ``gate`` measurement sigmas, plus 0.5 %).
    n_starts : int
        Stage-1 starts (the nominal walls, then a seeded Latin hypercube over the prior box).
    seed : int
    confidence : float
    reduced_vectors : int
        Modes per design in the stage-1 Ritz basis (:func:`reduced_wall_basis`).
    mac_weight : float
        Weight of ``1 - MAC`` against the relative frequency distance in pairing.
    unresolved_sigma : bool
        With ``frequency_std_hz``: when the paired model mode lies in a chain of modes
        spaced closer than the measured half-power bandwidth ``2 zeta f`` (``damping``,
        else the model's ratio), add ``span / sqrt(3)`` to that mode's sigma (the
        identified pole may be any blend of them; a strut's two bending planes are
        0.05-0.1 Hz apart).
    labels : bool
        Label the paired modes (builds the model at the updated walls: ~1 s).
    threads : int or None
        BLAS threads during the fits (:func:`trussid._util.threads.blas_threads`; None leaves
        the setting). One by default: the fits are thousands of small eigen-solutions,
        which threads only slow down (measured on the loaded 2-core machine: the
        exact-frequency test took 21 s with two threads, 3 s with one).

    Returns
    -------
    UpdateReport

    Raises
    ------
    UpdateError
        Non-finite or non-positive frequencies, mismatched lengths, bad bounds, shapes
        without sensors, fewer modes than can determine the walls, no measured mode
        reachable by the model.
    """
    # Long: the procedure (gate, stage-1 global fit, unresolved-mode sigma, stage-2 fit)
    # shares the pairing closures below between its stages; input checks, intervals and
    # damping are their own functions, the rest would pass a dozen arrays between steps.
    from trussid.fem.sensors import sensor_matrix
    from trussid.testbed.model import build_testbed, wall_basis, wall_modes
    from trussid.geometry.spec import Testbed
    from trussid.plid.greybox import fit_parameters
    from trussid._util.threads import blas_threads

    f_all, sig_all, z_all, zsig_all, sh_all = _checked_inputs(
        measured_freqs_hz, frequency_std_hz, damping, damping_std, shapes, sensors, prior_range,
        confidence)
    k_all = f_all.size
    known_sigma = sig_all is not None

    with blas_threads(threads):  # small dense eigen-solves, thousands of them
        tb = Testbed() if tb_nominal is None else tb_nominal
        tbm = build_testbed(tb) if tbm is None else tbm
        basis = wall_basis(tbm)
        nominal = np.array(basis.walls_ref, float)
        r_out = basis.r_out
        lo, hi = _wall_bounds(bounds, nominal, r_out)
        n_model = (int(n_model_modes) if n_model_modes is not None else None)

        if n_model is None:
            # nominal frequencies from the full model (one solve) to size the mode set
            f_nom, _ = wall_modes(basis, nominal, min(basis.n, max(60, 2 * k_all)))
            n_model = int(np.count_nonzero(f_nom <= 1.5 * f_all.max())) + 4
        n_model = max(min(n_model, basis.n), 1)
        if n_model < k_all:
            raise UpdateError(f"{k_all} measured modes but only {n_model} model modes considered: "
                              "raise n_model_modes")
        # the Ritz basis holds at least the modes compared, at each of its designs
        reduced, V = reduced_wall_basis(basis, max(reduced_vectors, n_model))
        rows_full = None
        if sensors is not None:
            S = sensor_matrix(basis.system.node_ids, sensors)
            rows_full = np.asarray(S @ basis.system.T)  # sensors from reduced DOFs
        rows_red = None if rows_full is None else rows_full @ V
        coarse_modes = _ModelModes(reduced, n_model, rows_red)
        full_modes = _ModelModes(basis, n_model, rows_full)

        # Sensitivity-aware gate at the nominal walls: which measured modes can be paired at all.
        f0, d0, sh0 = full_modes(nominal)
        reach = np.abs(d0) @ (prior_range * nominal)
        tol = gate * (reach[None, :] + (sig_all[:, None] if known_sigma else 0.0)) + 5e-3 * f_all[:, None]
        allowed = np.abs(f_all[:, None] - f0[None, :]) <= tol
        mac0 = None if sh_all is None else modal_assurance(sh_all, sh0, zero_shape="zero")
        pair0 = pair_modes(f_all, f0, scale_hz=np.maximum(tol, 1e-300), mac=mac0, mac_weight=mac_weight,
                           allowed=allowed)
        used = pair0 >= 0
        if not used.any():
            raise UpdateError("no measured frequency lies within reach of a model mode "
                              f"(measured {np.round(f_all, 3).tolist()} Hz; model {np.round(f0, 3).tolist()} Hz)")
        f = f_all[used]
        k = f.size
        sig = sig_all[used] if known_sigma else f  # relative residuals without sigmas
        allowed_u = allowed[used]
        sh = None if sh_all is None else sh_all[:, used]
        if not known_sigma and k < 7:
            raise UpdateError(f"{k} paired modes cannot determine 6 walls with intervals: give at least 7, "
                              "or frequency_std_hz")
        # fewer than 6 modes: the fit still runs, and its identifiability analysis names the
        # wall combinations they leave open

        zeta_bw = float(np.median(z_all)) if z_all is not None else float(tb.damping.modal_ratio)

        def make(mm, sig):
            def pairs(p):
                w = np.array([p[n] for n in WALL_NAMES])
                F, dF, shp = mm(w)
                mac = groups = None
                if sh is not None:
                    mac = modal_assurance(sh, shp, zero_shape="zero")
                    groups = mode_groups(F, shp, 2 * zeta_bw * F)
                j = pair_modes(f, F, mac=mac, mac_weight=mac_weight, allowed=allowed_u, groups=groups)
                # every gated mode stays pairable (the residual length must not change)
                j = np.where(j >= 0, j, pair_modes(f, F, mac=mac, mac_weight=mac_weight))
                return w, F, dF, j, mac

            def residual(p):
                _, F, _, j, _ = pairs(p)
                return (F[j] - f) / sig

            def jac(p):
                _, _, dF, j, _ = pairs(p)
                return dF[j] / sig[:, None]

            return pairs, residual, jac

        initial = dict(zip(WALL_NAMES, nominal))
        lo1 = np.maximum(lo, nominal * (1 - prior_range))
        hi1 = np.minimum(hi, nominal * (1 + prior_range))
        _, r1, j1 = make(coarse_modes, sig)
        coarse, swaps, ambiguous = _global_fit(r1, j1, initial, lo1, hi1, n_starts, seed, confidence,
                                               known_sigma)
        start = {n: float(np.clip(coarse.estimates[n], lo[i] * (1 + 1e-9), hi[i] * (1 - 1e-9)))
                 for i, n in enumerate(WALL_NAMES)}
        # Close modes the experiment cannot separate: when the paired model mode lies in a
        # chain of modes each nearer to the next than the measured mode's half-power bandwidth
        # 2 zeta f, the identified pole is a blend of them and may lie anywhere within the
        # chain's span (sigma span / sqrt 3), a model-form error the measured sigma does not
        # hold. For one strut's two planes the span is their 0.05-0.1 Hz split; for two struts
        # with nearly equal walls it covers both pairs.
        unres = np.zeros(k)
        if unresolved_sigma:
            w1 = np.array([start[n] for n in WALL_NAMES])
            F1, _, sh1 = full_modes(w1)
            mac1 = None if sh is None else modal_assurance(sh, sh1, zero_shape="zero")
            j1 = pair_modes(f, F1, mac=mac1, mac_weight=mac_weight, allowed=allowed_u,
                            groups=None if sh is None else mode_groups(F1, sh1, 2 * zeta_bw * F1))
            j1 = np.where(j1 >= 0, j1, pair_modes(f, F1))
            zi = z_all[used] if z_all is not None else np.full(k, tb.damping.modal_ratio)
            span = np.array([_cluster_span(F1, jj, 2 * z_ * f_) for jj, z_, f_ in zip(j1, zi, f)])
            unres = span / math.sqrt(3)
            if known_sigma:
                sig = np.sqrt(sig**2 + unres**2)
        pairs2, r2, j2 = make(full_modes, sig)
        rep = fit_parameters(r2, start, bounds={n: (a, b) for n, a, b in zip(WALL_NAMES, lo, hi)},
                             jac=j2, n_starts=1, confidence=confidence, min_obs=1)
        est = {n: rep.estimates[n] for n in WALL_NAMES}
        walls, F, dF, j, mac = pairs2(est)
        r = (F[j] - f) / sig
        chi2 = float(r @ r)
        dof = max(k - 6, 0)

        intervals, std_log, birge, source = _intervals(known_sigma, dF[j], sig, walls, chi2, dof,
                                                       rep, confidence)

        zeta, ziv = _damping_estimate(z_all, zsig_all, used, unres, f, confidence)

        # Report: pairs over all measured modes, with nominal frequencies of the same pairs.
        idx_used = np.flatnonzero(used)
        pairing = np.full(k_all, -1)
        pairing[idx_used] = j
        model_hz = np.full(k_all, np.nan)
        model_hz[idx_used] = F[j]
        nominal_hz = np.full(k_all, np.nan)
        nominal_hz[idx_used] = f0[pair0[used]]
        mac_all = None
        if mac is not None:
            mac_all = np.full(k_all, np.nan)
            mac_all[idx_used] = mac[np.arange(k), j]
        lab = [""] * k_all
        if labels:
            from trussid.testbed.labels import label_testbed_modes
            from trussid.testbed.model import solve_testbed_modes

            tbm_u = build_testbed(tb.with_walls(tuple(float(x) for x in walls)),
                                  elements_per_segment=tbm.elements_per_segment)
            ml = label_testbed_modes(tbm_u, solve_testbed_modes(tbm_u, n_model)).labels
            for i, jj in zip(idx_used, j):
                lab[i] = ml[jj]
        return UpdateReport(
            walls=walls, nominal=nominal, intervals=intervals, std_log=std_log, interval_source=source,
            measured_hz=f_all, used=used, pairing=pairing, model_hz=model_hz, nominal_hz=nominal_hz,
            labels=lab, mac=mac_all, chi2=chi2, dof=dof, birge=birge, damping=zeta, damping_interval=ziv,
            greybox=rep, coarse=coarse, confidence=confidence,
            sigma_hz=_scatter(sig if known_sigma else None, idx_used, k_all),
            unresolved_hz=_scatter(unres, idx_used, k_all),
            info={"coarse_evaluations": coarse_modes.evaluations, "full_evaluations": full_modes.evaluations,
                  "n_model_modes": n_model, "swaps": swaps,
                  "ambiguous_swaps": ambiguous},
        )
