"""The identified side: modes (frequency, damping, shape, uncertainty) of an identified model
or of a record, by PLID."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import control
import numpy as np
import scipy.linalg as la

from trussid.plid.errors import DataError
from trussid.plid.estimator import PLIDWarning
from trussid.plid.modal import pair_modes, pole_parameters, pole_std
from trussid.plid.recipe import identify
from trussid.updating.errors import UpdateError
from trussid.updating.results import IdentifiedModes

__all__ = ["modes_of_model", "modes_from_data"]


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

    The record is identified with :func:`trussid.plid.recipe.identify`; its ``n_modes``
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
        Passed to :func:`trussid.plid.recipe.identify` (default here ``form="sqrt"``).

    Returns
    -------
    modes : IdentifiedModes
    info : dict
        ``identification`` (full record), ``segment_models``, ``std_fallback`` (modes
        whose PLID variance was not positive and took the largest of the others).
    """
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
