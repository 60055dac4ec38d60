"""Frequency-shaped LQG (Gupta 1980, "Frequency-shaped cost functionals: extension of
linear-quadratic-Gaussian design methods", J. Guidance Control 3(6)): a weight ``W(z)`` on
the control signal turns the LQR's ``u' R u`` into the energy of ``W u``, so the state
feedback spends little control where the identified model is unreliable (clusters it
smears, modes near Nyquist). The weight's states join the design model for the Riccati
equation and the controller runs the weight's filter on its own command.

:func:`trussid.lqg.design.design_lqg` takes an :class:`InputWeight`; the damping tuning
(:func:`trussid.lqg.design.lqr_for_damping`) works on :func:`augment`'s system.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import ControlError

__all__ = ["InputWeight", "augment", "weighted_controller"]


@dataclass(frozen=True)
class InputWeight:
    """A frequency-shaped weight on the control signal (Gupta 1980, "Frequency-shaped cost
    functionals"): the LQR penalises ``|W(e^{jw}) u|^2`` instead of ``|u|^2``, so the
    feedback spends little control where ``|W|`` is large (the bands where the identified
    model is unreliable: clusters it smears, modes near Nyquist).

    ``W`` is the same on every input: ``W(1) = 1`` (no change at low frequency) times one
    second-order section per ``peaks`` entry ``(f0, half_width, gain)``: poles at
    ``exp(-2 pi half_width / fs) e^{+-j 2 pi f0 / fs}`` and zeros at radius ``exp(-2 pi
    gain half_width / fs)``, so ``|W|`` rises to about ``gain`` over ``f0 +- half_width``
    [Hz] and returns to 1 a few ``gain * half_width`` away.

    Attributes
    ----------
    peaks : tuple of (float, float, float)
        ``(f0 [Hz], half_width [Hz], gain [-])`` per section, ``0 < f0 <= fs / 2``.
    dt : float
        Sample time [s].
    """

    peaks: tuple
    dt: float

    def siso(self):
        """``(num, den)`` polynomials in ``z`` (highest power first) of ``W``."""
        fs = 1.0 / self.dt
        num, den = np.ones(1), np.ones(1)
        for f0, hw, g in self.peaks:
            if not (0 < f0 <= fs / 2 and hw > 0 and g >= 1):
                raise ControlError(f"input weight peak ({f0:g} Hz, {hw:g} Hz, x{g:g}): need "
                                   f"0 < f0 <= {fs / 2:g} Hz, half width > 0, gain >= 1")
            th = 2 * np.pi * f0 / fs
            rp = np.exp(-2 * np.pi * hw / fs)
            rz = np.exp(-2 * np.pi * g * hw / fs)
            num = np.polymul(num, [1.0, -2 * rz * np.cos(th), rz**2])
            den = np.polymul(den, [1.0, -2 * rp * np.cos(th), rp**2])
        return num / (np.polyval(num, 1.0) / np.polyval(den, 1.0)), den

    def gain(self, f_hz):
        """``|W|`` at the frequencies ``f_hz`` [Hz]."""
        num, den = self.siso()
        z = np.exp(2j * np.pi * np.asarray(f_hz, dtype=float) * self.dt)
        return np.abs(np.polyval(num, z) / np.polyval(den, z))

    def matrices(self, m: int):
        """``(Aw, Bw, Cw, Dw)`` of ``W`` on each of ``m`` inputs (block diagonal)."""
        from scipy.signal import tf2ss

        a, b, c, d = tf2ss(*self.siso())
        eye = np.eye(m)
        return np.kron(eye, a), np.kron(eye, b), np.kron(eye, c), np.kron(eye, d)


def augment(A, B, R, weight: InputWeight):
    """``(Aa, Ba, Qw, N, Ra)``: the plant ``(A, B)`` with the states of ``weight`` on its
    input appended, and the cost ``|Cw w + Dw S u|^2`` (``R = S' S``) as state, cross and
    input weights: at ``|W| = 1`` it is ``u' R u``."""
    n, m = B.shape
    Aw, Bw, Cw, Dw = weight.matrices(m)
    S = np.linalg.cholesky(R).T
    Bw, Dw = Bw @ S, Dw @ S
    nw = Aw.shape[0]
    Aa = np.block([[A, np.zeros((n, nw))], [np.zeros((nw, n)), Aw]])
    Ba = np.vstack([B, Bw])
    Qw = np.zeros((n + nw, n + nw))
    Qw[n:, n:] = Cw.T @ Cw
    N = np.zeros((n + nw, m))
    N[n:] = Cw.T @ Dw
    return Aa, Ba, Qw, N, Dw.T @ Dw


def weighted_controller(A, B, C, D, F, K, augmented):
    """``(Ac, Bc, Cc, Dc)`` of the predictor-form LQG whose state feedback ``F`` acts on the
    design model's states and those of an input weight (``augmented``: ``(Aa, Ba)`` of
    :func:`augment`); the controller runs the weight's filter on its own command."""
    Aa, Ba = augmented
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    nw = Aa.shape[0] - n
    Aw, Bw = Aa[n:, n:], Ba[n:]
    Fx, Fw = F[:, :n], F[:, n:]
    BKD = B - K @ D
    # xhat+ = A xhat + B u + K (y - C xhat - D u), w+ = Aw w + Bw u, u = -Fx xhat - Fw w
    Ac = np.block([[A - K @ C - BKD @ Fx, -BKD @ Fw], [-Bw @ Fx, Aw - Bw @ Fw]])
    Bc = np.vstack([K, np.zeros((nw, p))])
    return Ac, Bc, -F, np.zeros((m, p))
