"""The fit: pairing measured modes with the model's at trial walls (residual and Jacobian),
the global search over wall arrangements, and the intervals of walls and damping."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.stats

from trussid.plid.greybox import fit_parameters
from trussid.plid.modal import mac as modal_assurance
from trussid.plid.modal import mode_groups, pair_modes
from trussid.updating.reduction import ModelModes

__all__ = ["WALL_NAMES", "WallPairing", "global_fit", "wall_intervals", "damping_estimate",
           "cluster_span"]

#: Parameter names of the six walls (strut numbering of :mod:`trussid.testbed.model`, 0..5).
WALL_NAMES = tuple(f"wall{i}" for i in range(6))


@dataclass
class WallPairing:
    """Measured modes paired with the model's at trial walls: the residual and Jacobian
    that :func:`trussid.plid.greybox.fit_parameters` minimises.

    Pairing is redone at every evaluation (the bending modes lie close together and reorder
    when walls change): a linear assignment by frequency distance and, with identified
    shapes, by MAC within groups of close modes (:func:`trussid.plid.modal.pair_modes`).

    Attributes
    ----------
    model : ModelModes
        The model's modes at given walls (full or Ritz-reduced).
    f : (k,) float
        Measured frequencies [Hz].
    sigma : (k,) float
        Residual scale per mode [Hz] (measurement sigma, or ``f`` for relative residuals).
    allowed : (k, n) bool
        Which model modes each measured mode may pair with (the gate).
    shapes : (p, k) complex or None
        Identified shapes at the sensors.
    zeta_bw : float
        Damping ratio whose half-power bandwidth ``2 zeta f`` groups close model modes.
    mac_weight : float
        Weight of ``1 - MAC`` against the relative frequency distance.
    """

    model: ModelModes
    f: np.ndarray
    sigma: np.ndarray
    allowed: np.ndarray
    shapes: np.ndarray | None
    zeta_bw: float
    mac_weight: float

    def pairs(self, p: dict):
        """``(walls, F, dF, j, mac)`` at the walls ``p`` ({wall name: m}): model
        frequencies, sensitivities, the model mode paired with each measured one, MAC."""
        w = np.array([p[n] for n in WALL_NAMES])
        F, dF, shp = self.model(w)
        mac = groups = None
        if self.shapes is not None:
            mac = modal_assurance(self.shapes, shp, zero_shape="zero")
            groups = mode_groups(F, shp, 2 * self.zeta_bw * F)
        j = pair_modes(self.f, F, mac=mac, mac_weight=self.mac_weight, allowed=self.allowed,
                       groups=groups)
        # every gated mode stays pairable (the residual length must not change)
        j = np.where(j >= 0, j, pair_modes(self.f, F, mac=mac, mac_weight=self.mac_weight))
        return w, F, dF, j, mac

    def residual(self, p: dict) -> np.ndarray:
        """``(F_paired - f) / sigma`` (k,)."""
        _, F, _, j, _ = self.pairs(p)
        return (F[j] - self.f) / self.sigma

    def jacobian(self, p: dict) -> np.ndarray:
        """``dF_paired/dt / sigma`` (k, 6) [1/m]."""
        _, _, dF, j, _ = self.pairs(p)
        return dF[j] / self.sigma[:, None]


def global_fit(residual, jac, initial, lo, hi, n_starts, seed, confidence, known_sigma=False):
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


def wall_intervals(known_sigma, dFj, sig, walls, chi2, dof, rep, confidence):
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
        # Fewer independent data than walls (five modes for six struts, say) leave J^T J
        # singular: its "inverse" is round-off, and its diagonal can come out negative,
        # i.e. a zero-width interval. Such walls get no interval, not a false one.
        sv = np.linalg.svd(jl, compute_uv=False)
        ok = jl.shape[0] >= jl.shape[1] and sv.size and sv[-1] > 1e-10 * sv[0]
        if ok:
            cov = la.inv(jl.T @ jl) * infl**2
            ok = bool(np.isfinite(cov).all() and (np.diag(cov) > 0).all())
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


def damping_estimate(z_all, zsig_all, used, unres, f, confidence):
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


def cluster_span(F, j, bandwidth):
    """Frequency span of the chain of modes around ``F[j]`` with gaps below ``bandwidth``."""
    Fs = np.sort(F)
    i = int(np.searchsorted(Fs, F[j]))
    lo = hi = i
    while lo > 0 and Fs[lo] - Fs[lo - 1] < bandwidth:
        lo -= 1
    while hi < Fs.size - 1 and Fs[hi + 1] - Fs[hi] < bandwidth:
        hi += 1
    return float(Fs[hi] - Fs[lo])
