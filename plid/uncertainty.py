"""95 % intervals for an identified model's modal frequencies and damping ratios.

First-order (delta-method) propagation of the parameter covariance. The PLID pass of
:func:`trussid.plid.recipe.identify` ends with the posterior covariance of its parameters
``theta = [vec Abar, vec B]`` (:attr:`trussid.plid.estimator.PLIDResult.theta_cov`), in the
observer basis where ``A = F + Abar C``: a minimal parametrisation, so the covariance is
proper. A pole moves by ``dz = w^H dAbar C v / (w^H v)``; ``s = ln z / dt`` gives the
frequency ``|s| / 2 pi`` and the damping ratio ``-Re s / |s|``
(:func:`trussid.plid.modal.pole_std`, the one home of that propagation). The interval is the
estimate +- 1.96 standard deviations.

The posterior covariance carries the pass's noise model (``R`` estimated from the prior's
simulation error) and its parameter prior, so it describes the estimate ``identify``
returns, shrinkage included. Measured coverage (``benchmarks/bench_uncertainty.py``,
``benchmarks/results/uncertainty.md``): on records of a known plant with four lightly damped
modes at three noise levels, at the true order, seen by one force and two displacement
sensors and by two forces and two accelerometers (feed-through, D estimated): 95-96 % for
frequency, 93-97 % for damping (210 records each). The intervals cover the sampling variation
of the record, not a wrong order or a plant outside the model class.

No interval (NaN) is given for a pole that was reflected into the unit circle (the data did
not pin it down) or for a model that is not the PLID pass's own (an order reduced from a
higher one).
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg

from trussid.plid.modal import pole_parameters, pole_std

__all__ = ["ModeInterval", "mode_intervals", "Z95"]

#: Two-sided 95 % quantile of the standard normal distribution.
Z95 = 1.959963984540054


@dataclass(frozen=True)
class ModeInterval:
    """One mode (a complex pole pair) with its 95 % intervals.

    Attributes
    ----------
    frequency_hz : float
        Undamped natural frequency [Hz].
    frequency_std_hz : float
        Its first-order standard deviation [Hz] (NaN: no interval).
    damping_ratio : float
        Damping ratio [-].
    damping_ratio_std : float
        Its first-order standard deviation (NaN: no interval).
    """

    frequency_hz: float
    frequency_std_hz: float
    damping_ratio: float
    damping_ratio_std: float

    @property
    def frequency_ci95_hz(self) -> tuple[float, float]:
        """95 % interval of the frequency [Hz] (NaN, NaN without one)."""
        h = Z95 * self.frequency_std_hz
        return (self.frequency_hz - h, self.frequency_hz + h)

    @property
    def damping_ratio_ci95(self) -> tuple[float, float]:
        """95 % interval of the damping ratio (NaN, NaN without one)."""
        h = Z95 * self.damping_ratio_std
        return (self.damping_ratio - h, self.damping_ratio + h)

    def as_dict(self) -> dict:
        """The ``trussid identify --json`` entry of this mode (None for no interval)."""
        def _ci(lo_hi):
            return None if not np.all(np.isfinite(lo_hi)) else [float(v) for v in lo_hi]

        return {"frequency_hz": float(self.frequency_hz),
                "frequency_ci95_hz": _ci(self.frequency_ci95_hz),
                "damping_ratio": float(self.damping_ratio),
                "damping_ratio_ci95": _ci(self.damping_ratio_ci95)}


def _modes(A, C, dt):
    lam, W, V = scipy.linalg.eig(A, left=True, right=True)
    keep = lam.imag > 1e-12 * np.maximum(np.abs(lam), 1e-300)
    lam, W, V = lam[keep], W[:, keep], V[:, keep]
    f, z, s = pole_parameters(lam, dt)
    return lam, W, V, f, z, s


def mode_intervals(model: control.StateSpace, pass_model: control.StateSpace | None,
                   theta_cov: np.ndarray | None) -> list[ModeInterval]:
    """95 % intervals for the complex modes of ``model``.

    Parameters
    ----------
    model : control.StateSpace
        The identified model (``Identification.model``).
    pass_model : control.StateSpace or None
        The PLID pass's model (``Identification.result.model``), whose ``A = F + Abar C``
        ``theta_cov`` describes.
    theta_cov : ndarray (q, q) or None
        Posterior covariance of ``[vec Abar, vec B]`` (``Identification.result.theta_cov``).

    Returns
    -------
    list of ModeInterval
        One per complex pole pair of ``model``, by frequency; a mode of ``model`` that is not
        a pole of the pass's model (a reflected pole, a reduced model) has NaN standard
        deviations.
    """
    dt = model.dt if control.isdtime(model, strict=True) else None
    A = np.asarray(model.A, float)
    if A.size == 0:
        return []
    lam, _, _, f, z, _ = _modes(A, np.asarray(model.C, float), dt)
    fstd = np.full(f.shape, np.nan)
    zstd = np.full(f.shape, np.nan)
    if pass_model is not None and theta_cov is not None and pass_model.nstates == A.shape[0]:
        Ap, Cp = np.asarray(pass_model.A, float), np.asarray(pass_model.C, float)
        lp, Wp, Vp, _, _, sp = _modes(Ap, Cp, dt)
        ps, pz = pole_std(lp, sp, Vp, Wp, Cp @ Vp, theta_cov, dt)
        for i, li in enumerate(lam):
            j = int(np.argmin(np.abs(lp - li))) if lp.size else -1
            # the same pole (the direct-term refit keeps A; a reflected pole moved)
            if j >= 0 and abs(lp[j] - li) <= 1e-9 * max(abs(li), 1.0):
                fstd[i], zstd[i] = ps[j], pz[j]
    order = np.argsort(f, kind="stable")
    return [ModeInterval(float(f[i]), float(fstd[i]), float(z[i]), float(zstd[i]))
            for i in order]
