"""Plants and simulation shared by the PLID tests (helpers exposed as fixtures)."""

import control
import numpy as np
import pytest


def _modal_plant(freqs_hz, zetas, m, p, fs, rng, collocated=False):
    """ZOH-discretised plant of lightly damped modes with random (or collocated) shapes."""
    n = 2 * len(freqs_hz)
    A = np.zeros((n, n))
    if collocated:
        B = np.zeros((n, m))
        B[1::2] = 1.0
        C = np.zeros((p, n))
        C[:, 0::2] = 1.0
    else:
        B = rng.standard_normal((n, m))
        B[0::2] = 0.0
        C = rng.standard_normal((p, n))
    for i, (f, z) in enumerate(zip(freqs_hz, zetas)):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-w * w, -2 * z * w]]
    return control.c2d(control.ss(A, B, C, np.zeros((p, m))), 1.0 / fs)


def _simulate(sys, u, rng=None, snr_db=None):
    """Outputs of a discrete model from x0 = 0; with snr_db, white output noise that far
    below each output's RMS. Returns (measured, noise-free)."""
    A, B, C = (np.asarray(M) for M in (sys.A, sys.B, sys.C))
    x = np.zeros(A.shape[0])
    Y = np.empty((u.shape[0], C.shape[0]))
    for k in range(u.shape[0]):
        Y[k] = C @ x
        x = A @ x + B @ u[k]
    if snr_db is None:
        return Y, Y
    sig = np.sqrt(np.mean(Y ** 2, axis=0))
    return Y + rng.standard_normal(Y.shape) * sig * 10 ** (-snr_db / 20), Y


@pytest.fixture
def modal_plant():
    return _modal_plant


@pytest.fixture
def simulate():
    return _simulate
