"""A small lightly damped 3 x 3 structure and an LQG on it (fast tests of trussid.adapt)."""

import control
import numpy as np
import pytest

from trussid.lqg.design import design_lqg

FS = 1600.0
FREQS = (120.0, 166.0, 194.0, 220.0)
ZETA = 0.0025


def modal_structure(freqs=FREQS, zeta=ZETA, fs=FS):
    """Discrete (ZOH) 3 x 3 velocity-output modal plant, strictly proper (D = 0)."""
    n = len(freqs)
    w = 2 * np.pi * np.asarray(freqs)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(w**2), -np.diag(2 * zeta * w)]])
    rows = [[0.1, 0.05, 0.02], [1.0, 0.3, -0.2], [0.2, 1.0, 0.4], [-0.3, 0.2, 1.0]]
    Bm = np.array([rows[k % 4] for k in range(n)])
    B = np.vstack([np.zeros((n, 3)), Bm])
    C = np.hstack([np.zeros((3, n)), Bm.T])
    sysd = control.c2d(control.ss(A, B, C, np.zeros((3, 3))), 1 / fs, "zoh")
    return control.ss(sysd.A, sysd.B, sysd.C, sysd.D, 1 / fs, inputs=["ch1", "ch2", "ch3"],
                      outputs=["acc1", "acc2", "acc3"])


@pytest.fixture(scope="session")
def structure():
    return modal_structure()


@pytest.fixture(scope="session")
def controller(structure):
    """An LQG (7 % on the three dominant modes) designed on an open-loop record."""
    rng = np.random.default_rng(11)
    u = rng.normal(size=(3000, 3))
    y = control.forced_response(structure, U=u.T).outputs.T
    y = y + 0.01 * np.std(y) * rng.normal(size=y.shape)
    return design_lqg(structure, u, y).controller
