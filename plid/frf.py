"""Frequency-response functions: of models, estimated from time data (H1/H2), and measured
by a simulated stepped-sine analyser.

Array convention: an FRF is an array ``H`` of shape (n_freq, p, m): ``H[k, i, j]`` is the
response of output i to input j at frequency ``f[k]`` [Hz].
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
import scipy.signal

from trussid.plid._validate import as_2d
from trussid.plid.errors import DataError


@dataclass
class FRF:
    """A frequency response on a grid.

    Attributes
    ----------
    f : ndarray, shape (n_freq,)
        Frequencies [Hz].
    H : ndarray, shape (n_freq, p, m), complex
        Response (output units per input unit).
    coherence : ndarray, shape (n_freq, p), optional
        Multiple coherence of each output with all inputs (ordinary coherence when m = 1).
    n_averages : int, optional
        Number of segments averaged (Welch), for estimates.
    """

    f: np.ndarray
    H: np.ndarray
    coherence: np.ndarray | None = None
    n_averages: int | None = None


def frequency_response(sys: control.StateSpace, f) -> np.ndarray:
    """Exact frequency response of a state-space model at frequencies ``f`` [Hz].

    Discrete models are evaluated at z = exp(j 2 pi f dt), continuous ones at s = j 2 pi f.
    Returns an array of shape (n_freq, p, m).

    Notes
    -----
    Evaluated through one eigendecomposition, ``C (xI - A)^-1 B = (C V) diag(1 / (x -
    lambda)) (V^-1 B)``: O(n) per frequency, where python-control without slycot solves an
    n x n system per frequency (10 ms each for the 141-state testbed plant). When the
    eigenvectors are ill-conditioned (cond(V) > 1e8, e.g. a defective A) python-control's
    own evaluation is used instead.

    Examples
    --------
    A mass-spring-damper, 10 Hz at 5 % damping: unit static gain, ``1 / (2 zeta)`` at resonance:

    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import frequency_response
    >>> w = 2 * np.pi * 10.0
    >>> G = control.ss(control.tf([w**2], [1, 2 * 0.05 * w, w**2]))
    >>> H = frequency_response(G, [0.0, 10.0])
    >>> H.shape                                   # (frequencies, outputs, inputs)
    (2, 1, 1)
    >>> print(np.round(np.abs(H[:, 0, 0]), 4))
    [ 1. 10.]
    """
    f = np.atleast_1d(np.asarray(f, dtype=float))
    x = np.exp(2j * np.pi * f * sys.dt) if control.isdtime(sys, strict=True) else 2j * np.pi * f
    A, B, C, D = (np.asarray(M, dtype=float) for M in (sys.A, sys.B, sys.C, sys.D))
    if A.shape[0]:
        lam, V = np.linalg.eig(A)
        if np.linalg.cond(V) <= 1e8:
            H = np.einsum("ps,fs,sm->fpm", C @ V, 1.0 / (x[:, None] - lam[None, :]),
                          np.linalg.solve(V, B))
            return H + D[None, :, :]
    H = np.asarray(sys(x, squeeze=False))  # python-control evaluates C (xI - A)^-1 B + D
    return np.moveaxis(H.reshape(sys.noutputs, sys.ninputs, f.size), -1, 0)


def _spectra(u, y, fs, nperseg, window, noverlap):
    """Welch auto/cross spectra with scipy's convention S_xy = E[conj(X) Y]."""
    u, y = as_2d(u, "u"), as_2d(y, "y")
    if u.shape[0] != y.shape[0]:
        raise DataError(f"u has {u.shape[0]} samples, y has {y.shape[0]}")
    n = u.shape[0]
    nperseg = int(min(nperseg, n))
    if nperseg < 8:
        raise DataError(f"segments of {nperseg} samples are too short for a spectrum")
    kw = dict(fs=fs, window=window, nperseg=nperseg, noverlap=noverlap, axis=0,
              detrend="constant")
    f, Suu = scipy.signal.csd(u[:, :, None], u[:, None, :], **kw)  # (nf, m, m)
    _, Suy = scipy.signal.csd(u[:, :, None], y[:, None, :], **kw)  # (nf, m, p)
    _, Syy = scipy.signal.welch(y, **kw)  # (nf, p)
    step = nperseg - (nperseg // 2 if noverlap is None else noverlap)
    n_avg = (n - nperseg) // step + 1
    return f, Suu, Suy, Syy, n_avg


def h1(u, y, fs: float, nperseg: int = 1024, window="hann", noverlap=None) -> FRF:
    """H1 estimate H = S_yu S_uu^-1 per frequency, with multiple coherence (Welch averaging).

    Parameters
    ----------
    u : ndarray, shape (N, m)
        Inputs.
    y : ndarray, shape (N, p)
        Outputs.
    fs : float
        Sampling frequency [Hz].
    nperseg : int
        Segment length (frequency resolution fs/nperseg); more segments = more averages.
    window, noverlap : see :func:`scipy.signal.csd` (default Hann, 50 % overlap).

    Returns
    -------
    FRF
        With ``coherence`` (n_freq, p) the multiple coherence of each output and
        ``n_averages`` the number of Welch segments.

    Notes
    -----
    H1 is unbiased by output noise (uncorrelated with u) and biased low by input noise.

    Examples
    --------
    The H1 estimate of a two-mode plant from 2000 samples of white-noise response, against the
    plant's own response at 10 Hz:

    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import excitation, frequency_response, h1, simulate
    >>> s = control.tf("s")
    >>> G = sum(g * (2 * np.pi * f) ** 2 / (s**2 + 0.04 * 2 * np.pi * f * s + (2 * np.pi * f) ** 2)
    ...         for f, g in ((50.0, 1.0), (120.0, 0.5)))
    >>> plant = control.c2d(control.ss(G), 1e-3)
    >>> u = excitation("white", 2000, fs=1000.0, seed=1)
    >>> est = h1(u, simulate(plant, u), fs=1000.0, nperseg=500)
    >>> est.H.shape, float(est.f[5])              # 2 Hz resolution
    ((251, 1, 1), 10.0)
    >>> true = frequency_response(plant, [10.0])[0, 0, 0]
    >>> print(f"|H1| {abs(est.H[5, 0, 0]):.2f}, true {abs(true):.2f}, error {100 * abs(est.H[5, 0, 0] / true - 1):.1f} %")
    |H1| 1.55, true 1.54, error 0.3 %
    """
    f, Suu, Suy, Syy, n_avg = _spectra(u, y, fs, nperseg, window, noverlap)
    m = Suu.shape[1]
    if n_avg < m:
        # S_uu is a sum of n_avg rank-one terms: singular whatever the inputs are. Say so,
        # rather than blame the inputs (the audit's B88: 20 samples, 3 inputs).
        n = as_2d(u, "u").shape[0]
        raise DataError(f"{n} samples give {n_avg} Welch segment(s) of "
                        f"{min(nperseg, n)} samples, but an H1 estimate with {m} inputs "
                        f"needs at least {m} (many more for a usable one): give a longer "
                        "record or shorter segments")
    # S_uy = S_uu H^T (scipy convention), hence H^T = S_uu^-1 S_uy per frequency.
    try:
        Ht = np.linalg.solve(Suu, Suy)
    except np.linalg.LinAlgError:
        raise DataError(f"the {m} inputs are linearly dependent at some frequency; H1 needs "
                        "independent inputs") from None
    return FRF(f=f, H=np.swapaxes(Ht, 1, 2), coherence=_coherence(Suy, Ht, Syy),
               n_averages=n_avg)


def _coherence(Suy, Ht, Syy):
    """Multiple coherence: power of y_i explained by all inputs over the power of y_i."""
    explained = np.real(np.einsum("fji,fji->fi", np.conj(Suy), Ht))
    with np.errstate(invalid="ignore", divide="ignore"):
        coh = np.where(Syy > 0, explained / Syy, 0.0)
    return np.clip(coh, 0.0, 1.0)


def h2(u, y, fs: float, nperseg: int = 1024, window="hann", noverlap=None) -> FRF:
    """H2 estimate, unbiased by input noise (biased by output noise).

    SISO and SIMO (one input): ``H_i = S_yiyi / S_yiu`` per output. Square MIMO (p = m):
    ``H = conj(S_yy S_uy^-1)``. Other shapes raise :class:`DataError`.
    """
    f, Suu, Suy, Syy, n_avg = _spectra(u, y, fs, nperseg, window, noverlap)
    m, p = Suy.shape[1], Suy.shape[2]
    if m == 1:
        # S_yy = H S_yu with S_yu = conj(S_uy), per output.
        H = (Syy / np.conj(Suy[:, 0, :]))[:, :, None]
    elif m == p:
        _, Syy_full = scipy.signal.csd(as_2d(y, "y")[:, :, None], as_2d(y, "y")[:, None, :],
                                       fs=fs, window=window, nperseg=min(nperseg, len(y)),
                                       noverlap=noverlap, axis=0, detrend="constant")
        # S_yy = conj(H) S_uy  =>  conj(H) = S_yy S_uy^-1  (solve on the right via transposes)
        Hc = np.swapaxes(np.linalg.solve(np.swapaxes(Suy, 1, 2), np.swapaxes(Syy_full, 1, 2)),
                         1, 2)
        H = np.conj(Hc)
    else:
        raise DataError(f"H2 needs one input or as many outputs as inputs; got {m} inputs "
                        f"and {p} outputs")
    try:
        coh = _coherence(Suy, np.linalg.solve(Suu, Suy), Syy)
    except np.linalg.LinAlgError:
        raise DataError(f"the {m} inputs are linearly dependent at some frequency") from None
    return FRF(f=f, H=H, coherence=coh, n_averages=n_avg)


def stepped_sine(plant: control.StateSpace, f, amplitude: float = 1.0, cycles: int = 20,
                 settle_tol: float = 1e-12, max_settle: int = 2_000_000,
                 noise_rms: float = 0.0, seed=None) -> FRF:
    """A simulated stepped-sine analyser on a discrete plant.

    For each test frequency and each input in turn, the plant (from rest) is driven by
    ``amplitude sin(2 pi f k dt)``; the analyser waits until the slowest mode has decayed by
    ``settle_tol`` (from the plant's spectral radius), then fits a sine and cosine to each
    output over ``cycles`` periods by least squares (the IEEE-1057 three-parameter sine
    fit without the offset, exact for a steady sinusoid whatever the window length) and
    reports the complex gain. All frequencies and inputs are simulated together.

    Parameters
    ----------
    plant : control.StateSpace
        Discrete, stable.
    f : array of float
        Test frequencies [Hz], 0 < f < fs/2.
    amplitude : float
        Drive amplitude [input units].
    cycles : int
        Periods of the lowest test frequency used for the fit (at least 2 periods of each).
    settle_tol : float
        Transient decay factor waited for before measuring.
    max_settle : int
        Cap on the settling samples (a :class:`DataError` if the plant needs more).
    noise_rms : float
        Optional sensor noise on the outputs [output units].
    seed : int, optional
        Seed of that noise.

    Returns
    -------
    FRF
    """
    if not control.isdtime(plant, strict=True):
        raise DataError("the stepped-sine analyser needs a discrete plant (dt > 0)")
    f = np.atleast_1d(np.asarray(f, dtype=float))
    fs = 1.0 / plant.dt
    if np.any(f <= 0) or np.any(f >= fs / 2):
        raise DataError(f"test frequencies must lie in (0, {fs / 2:g}) Hz")
    A, B, C, D = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C, plant.D))
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    rho = max(np.abs(np.linalg.eigvals(A))) if n else 0.0
    if rho >= 1:
        raise DataError(f"the plant is not stable (spectral radius {rho:.6g}); a stepped-sine "
                        "test never reaches steady state")
    settle = 0 if rho == 0 else int(np.ceil(np.log(settle_tol) / np.log(rho))) + 10 * n
    if settle > max_settle:
        raise DataError(f"the plant needs {settle} samples to settle (more than "
                        f"max_settle={max_settle})")
    n_meas = int(np.ceil(max(cycles / f.min(), 2 / f.min()) * fs))
    w = 2 * np.pi * f / fs  # rad/sample
    nc = f.size * m  # one simulation column per (frequency, input)
    w_col = np.repeat(w, m)
    B_col = np.tile(B, (1, f.size))  # column c drives input c % m
    D_col = np.tile(D, (1, f.size))
    x = np.zeros((n, nc))
    # Normal equations of the per-column sine/cosine fit, accumulated sample by sample.
    ss = sc = cc = np.zeros(nc)
    ys = np.zeros((p, nc))
    yc = np.zeros((p, nc))
    rng = np.random.default_rng(seed)
    # The loop over samples is inherent (a recursion); each step is vectorised over all
    # frequencies and inputs.
    for k in range(settle + n_meas):
        s = amplitude * np.sin(w_col * k)
        if k >= settle:
            y = C @ x + D_col * s
            if noise_rms:
                y = y + noise_rms * rng.standard_normal(y.shape)
            c = amplitude * np.cos(w_col * k)
            ys = ys + y * s
            yc = yc + y * c
            ss = ss + s * s
            sc = sc + s * c
            cc = cc + c * c
        x = A @ x + B_col * s
    det = ss * cc - sc * sc
    a = (ys * cc - yc * sc) / det  # coefficient of the drive (sin)
    b = (yc * ss - ys * sc) / det  # coefficient of the quadrature (cos)
    # y = a s + b c with s = A sin(wk), c = A cos(wk): the gain is G = a + j b.
    G = a + 1j * b
    H = np.moveaxis(G.reshape(p, f.size, m), 1, 0)
    return FRF(f=f, H=H)


__all__ = ["FRF", "frequency_response", "h1", "h2", "stepped_sine"]
