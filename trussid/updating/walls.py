"""Updating the six strut walls (and the modal damping) from measured modes: input checks,
the gate, the two-stage fit and the report (the method: :mod:`trussid.updating`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trussid._util.threads import blas_threads
from trussid.fem.sensors import sensor_matrix
from trussid.geometry.spec import Testbed
from trussid.plid.greybox import fit_parameters
from trussid.plid.modal import mac as modal_assurance
from trussid.plid.modal import mode_groups, pair_modes
from trussid.testbed.labels import label_testbed_modes
from trussid.testbed.model import build_testbed
from trussid.testbed.walls import WallBasis, design_at_walls, wall_basis, wall_modes
from trussid.updating.errors import UpdateError
from trussid.updating.fit import (WALL_NAMES, WallPairing, cluster_span, damping_estimate, global_fit,
                                  wall_intervals)
from trussid.updating.reduction import ModelModes, reduced_wall_basis
from trussid.updating.results import UpdateReport

__all__ = ["update_walls", "DEFAULT_BOUNDS", "RADIUS_MARGIN"]

#: Default physical bounds on each wall, as multiples of its nominal value.
DEFAULT_BOUNDS = (0.5, 1.5)
#: A wall never gets closer than this fraction of the outer radius to 0 or to the radius.
RADIUS_MARGIN = 0.02


@dataclass(frozen=True)
class _Measured:
    """The measured data, checked: frequencies [Hz], their sigmas, damping, shapes."""

    f_all: np.ndarray
    sig_all: np.ndarray | None
    z_all: np.ndarray | None
    zsig_all: np.ndarray | None
    sh_all: np.ndarray | None

    @property
    def known_sigma(self) -> bool:
        return self.sig_all is not None


def _vector(name, value, k, positive=True):
    a = np.asarray(value, float)
    if a.ndim == 0:
        a = np.full(k, float(a))
    a = a.ravel()
    if a.size != k:
        raise UpdateError(f"{name} has {a.size} entries for {k} measured modes")
    bad = np.flatnonzero(~np.isfinite(a) | ((a <= 0) if positive else (a < 0)))
    if bad.size:
        raise UpdateError(f"{name}[{bad[0]}] = {float(a[bad[0]])!r} must be finite and "
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


def _scatter(values, idx, k_all, fill=np.nan, dtype=float):
    """``values`` of the paired modes ``idx`` placed among all ``k_all`` measured modes."""
    if values is None:
        return None
    out = np.full(k_all, fill, dtype=dtype)
    out[idx] = values
    return out


def _checked_inputs(measured_freqs_hz, frequency_std_hz, damping, damping_std, shapes, sensors,
                    prior_range, confidence) -> _Measured:
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
    return _Measured(f_all, sig_all, z_all, zsig_all, sh_all)


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
    tb_nominal : trussid.geometry.Testbed, optional
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
    tbm : trussid.testbed.TestbedModel, optional
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
        Label the paired modes (on the design at the updated walls, by the wall basis).
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
    m = _checked_inputs(measured_freqs_hz, frequency_std_hz, damping, damping_std, shapes,
                        sensors, prior_range, confidence)
    with blas_threads(threads):  # small dense eigen-solves, thousands of them
        tb = Testbed() if tb_nominal is None else tb_nominal
        tbm = build_testbed(tb) if tbm is None else tbm
        basis = wall_basis(tbm)
        nominal = np.array(basis.walls_ref, float)
        lo, hi = _wall_bounds(bounds, nominal, basis.r_out)
        n_model = _model_mode_count(basis, n_model_modes, m.f_all)
        # the Ritz basis holds at least the modes compared, at each of its designs
        reduced, V = reduced_wall_basis(basis, max(reduced_vectors, n_model))
        rows_full = None
        if sensors is not None:
            rows_full = np.asarray(sensor_matrix(basis.system.node_ids, sensors) @ basis.system.T)
        coarse_modes = ModelModes(reduced, n_model, None if rows_full is None else rows_full @ V)
        full_modes = ModelModes(basis, n_model, rows_full)
        g = _gate(full_modes, m, nominal, prior_range, gate, mac_weight)
        f, used = m.f_all[g.used], g.used
        sig = m.sig_all[used] if m.known_sigma else f  # relative residuals without sigmas
        sh = None if m.sh_all is None else m.sh_all[:, used]
        zeta_bw = float(np.median(m.z_all)) if m.z_all is not None else float(tb.damping.modal_ratio)

        # stage 1: the global search on the Ritz basis, within the prior box
        coarse_fit = WallPairing(coarse_modes, f, sig, g.allowed[used], sh, zeta_bw, mac_weight)
        lo1 = np.maximum(lo, nominal * (1 - prior_range))
        hi1 = np.minimum(hi, nominal * (1 + prior_range))
        coarse, swaps, ambiguous = global_fit(coarse_fit.residual, coarse_fit.jacobian,
                                              dict(zip(WALL_NAMES, nominal)), lo1, hi1, n_starts,
                                              seed, confidence, m.known_sigma)
        start = {n: float(np.clip(coarse.estimates[n], lo[i] * (1 + 1e-9), hi[i] * (1 - 1e-9)))
                 for i, n in enumerate(WALL_NAMES)}
        unres = np.zeros(f.size)
        if unresolved_sigma:
            zi = m.z_all[used] if m.z_all is not None else np.full(f.size, tb.damping.modal_ratio)
            unres = _unresolved(full_modes, start, f, zi, sh, g.allowed[used], zeta_bw, mac_weight)
            if m.known_sigma:
                sig = np.sqrt(sig**2 + unres**2)

        # stage 2: the local fit on the full model, within the physical bounds
        fine = WallPairing(full_modes, f, sig, g.allowed[used], sh, zeta_bw, mac_weight)
        rep = fit_parameters(fine.residual, start,
                             bounds={n: (a, b) for n, a, b in zip(WALL_NAMES, lo, hi)},
                             jac=fine.jacobian, n_starts=1, confidence=confidence, min_obs=1)
        walls, F, dF, j, mac = fine.pairs({n: rep.estimates[n] for n in WALL_NAMES})
        r = (F[j] - f) / sig
        chi2 = float(r @ r)
        dof = max(f.size - 6, 0)
        intervals, std_log, birge, source = wall_intervals(m.known_sigma, dF[j], sig, walls, chi2,
                                                           dof, rep, confidence)
        zeta, ziv = damping_estimate(m.z_all, m.zsig_all, used, unres, f, confidence)
        idx_used = np.flatnonzero(used)
        k_all = m.f_all.size
        lab = _labels(tbm, basis, walls, n_model, idx_used, j, k_all) if labels else [""] * k_all
        return UpdateReport(
            walls=walls, nominal=nominal, intervals=intervals, std_log=std_log, interval_source=source,
            measured_hz=m.f_all, used=used, pairing=_scatter(j, idx_used, k_all, fill=-1, dtype=int),
            model_hz=_scatter(F[j], idx_used, k_all),
            nominal_hz=_scatter(g.f0[g.pairing[used]], idx_used, k_all),
            labels=lab, mac=None if mac is None else _scatter(mac[np.arange(f.size), j], idx_used, k_all),
            chi2=chi2, dof=dof, birge=birge, damping=zeta, damping_interval=ziv,
            greybox=rep, coarse=coarse, confidence=confidence,
            sigma_hz=_scatter(sig if m.known_sigma else None, idx_used, k_all),
            unresolved_hz=_scatter(unres, idx_used, k_all),
            info={"coarse_evaluations": coarse_modes.evaluations, "full_evaluations": full_modes.evaluations,
                  "n_model_modes": n_model, "swaps": swaps,
                  "ambiguous_swaps": ambiguous},
        )


def _model_mode_count(basis: WallBasis, n_model_modes, f_all) -> int:
    """Model modes considered for pairing (default: up to 1.5 times the highest measured
    frequency, plus 4); at least as many as the measured modes."""
    if n_model_modes is None:
        # nominal frequencies from the full model (one solve) to size the mode set
        f_nom, _ = wall_modes(basis, basis.walls_ref, min(basis.n, max(60, 2 * f_all.size)))
        n_model = int(np.count_nonzero(f_nom <= 1.5 * f_all.max())) + 4
    else:
        n_model = int(n_model_modes)
    n_model = max(min(n_model, basis.n), 1)
    if n_model < f_all.size:
        raise UpdateError(f"{f_all.size} measured modes but only {n_model} model modes considered: "
                          "raise n_model_modes")
    return n_model


@dataclass(frozen=True)
class _Gate:
    """Which measured modes the model can reach (``used``), whom each may pair with
    (``allowed``, (k, n)), the nominal frequencies ``f0`` and the nominal ``pairing``."""

    used: np.ndarray
    allowed: np.ndarray
    f0: np.ndarray
    pairing: np.ndarray


def _gate(full_modes: ModelModes, m: "_Measured", nominal, prior_range, gate, mac_weight) -> _Gate:
    """The sensitivity-aware gate at the nominal walls: model mode ``j`` may move by about
    ``|df_j/dt| prior_range t``; a measured mode farther than ``gate`` times that (plus
    ``gate`` sigmas, plus 0.5 %) from every model mode is not paired."""
    f0, d0, sh0 = full_modes(nominal)
    reach = np.abs(d0) @ (prior_range * nominal)
    tol = gate * (reach[None, :] + (m.sig_all[:, None] if m.known_sigma else 0.0)) + 5e-3 * m.f_all[:, None]
    allowed = np.abs(m.f_all[:, None] - f0[None, :]) <= tol
    mac0 = None if m.sh_all is None else modal_assurance(m.sh_all, sh0, zero_shape="zero")
    pair0 = pair_modes(m.f_all, f0, scale_hz=np.maximum(tol, 1e-300), mac=mac0, mac_weight=mac_weight,
                       allowed=allowed)
    used = pair0 >= 0
    if not used.any():
        raise UpdateError("no measured frequency lies within reach of a model mode "
                          f"(measured {np.round(m.f_all, 3).tolist()} Hz; model {np.round(f0, 3).tolist()} Hz)")
    k = int(used.sum())
    if not m.known_sigma and k < 7:
        raise UpdateError(f"{k} paired modes cannot determine 6 walls with intervals: give at least 7, "
                          "or frequency_std_hz")
    # fewer than 6 modes: the fit still runs, and its identifiability analysis names the
    # wall combinations they leave open
    return _Gate(used=used, allowed=allowed, f0=f0, pairing=pair0)


def _unresolved(full_modes: ModelModes, start: dict, f, zeta, sh, allowed, zeta_bw, mac_weight):
    """Sigma [Hz] of the close modes the experiment cannot separate, at the walls ``start``.

    When the paired model mode lies in a chain of modes each nearer to the next than the
    measured mode's half-power bandwidth 2 zeta f, the identified pole is a blend of them and
    may lie anywhere within the chain's span (sigma span / sqrt 3), a model-form error the
    measured sigma does not hold. For one strut's two planes the span is their 0.05-0.1 Hz
    split; for two struts with nearly equal walls it covers both pairs.
    """
    F1, _, sh1 = full_modes(np.array([start[n] for n in WALL_NAMES]))
    mac1 = None if sh is None else modal_assurance(sh, sh1, zero_shape="zero")
    j1 = pair_modes(f, F1, mac=mac1, mac_weight=mac_weight, allowed=allowed,
                    groups=None if sh is None else mode_groups(F1, sh1, 2 * zeta_bw * F1))
    j1 = np.where(j1 >= 0, j1, pair_modes(f, F1))
    span = np.array([cluster_span(F1, jj, 2 * z_ * f_) for jj, z_, f_ in zip(j1, zeta, f)])
    return span / math.sqrt(3)


def _labels(tbm, basis, walls, n_model, idx_used, j, k_all) -> list:
    """The label of the model mode paired with each measured mode, on the design at the
    updated walls (:func:`trussid.testbed.walls.design_at_walls`: the same wall-basis modes
    the fit paired, so mode ``j`` is the one paired)."""
    design, modes = design_at_walls(tbm, basis, walls, n_model)
    ml = label_testbed_modes(design, modes).labels
    lab = [""] * k_all
    for i, jj in zip(idx_used, j):
        lab[i] = ml[jj]
    return lab
