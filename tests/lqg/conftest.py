"""A small lightly damped 3 x 3 structure, its record, and designs on it (fast tests)."""

import control
import numpy as np
import pytest

FS = 1600.0
FREQS = (120.0, 166.0, 194.0, 220.0)
ZETA = 0.0025


def modal_structure(freqs=FREQS, zeta=ZETA, fs=FS):
    """Discrete (ZOH) 3-input, 3-output velocity-output modal plant with one sample of
    sensor delay (strictly proper, as the lab plant is)."""
    n = len(freqs)
    w = 2 * np.pi * np.asarray(freqs)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(w**2), -np.diag(2 * zeta * w)]])
    # the first mode weakly controllable (residue 1 % of the others'), as the testbed's 118 Hz
    rows = [[0.1, 0.05, 0.02], [1.0, 0.3, -0.2], [0.2, 1.0, 0.4], [-0.3, 0.2, 1.0]]
    Bm = np.array([rows[k % 4] for k in range(n)]) if n > 1 else np.array([rows[1]])
    B = np.vstack([np.zeros((n, 3)), Bm])
    C = np.hstack([np.zeros((3, n)), Bm.T])  # collocated velocity outputs
    sysc = control.ss(A, B, C, np.zeros((3, 3)))
    sysd = control.c2d(sysc, 1 / fs, "zoh")
    return control.ss(sysd.A, sysd.B, sysd.C, sysd.D, 1 / fs, inputs=["ch1", "ch2", "ch3"],
                      outputs=["acc1", "acc2", "acc3"])


@pytest.fixture(scope="session")
def structure():
    return modal_structure()


@pytest.fixture(scope="session")
def record(structure):
    """3000 samples of white input and the noisy response of :func:`structure`."""
    rng = np.random.default_rng(11)
    u = rng.normal(size=(3000, 3))
    y = control.forced_response(structure, U=u.T).outputs.T
    y = y + 0.01 * np.std(y) * rng.normal(size=y.shape)
    return u, y
