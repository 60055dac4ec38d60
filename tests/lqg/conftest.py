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


def _response(sys, z):
    """C (zI - A)^-1 B + D at one point z, by a 2-D solve."""
    A, B, C, D = (np.asarray(M) for M in (sys.A, sys.B, sys.C, sys.D))
    return C @ np.linalg.solve(z * np.eye(A.shape[0]) - A, B) + D


def _mu_dscaled(M):
    """mu of M over independent complex scalar perturbations of each channel, as the D-scaled
    upper bound inf_D sigma_max(D M D^-1) (D > 0 diagonal): equal to mu for up to three
    blocks (Doyle 1982). Minimised over log D, where log sigma_max is convex."""
    import scipy.optimize

    def sigma(x):
        d = np.exp(np.r_[0.0, x])
        return np.linalg.norm(d[:, None] * M / d[None, :], 2)

    res = scipy.optimize.minimize(sigma, np.zeros(M.shape[0] - 1), method="Nelder-Mead",
                                  options={"xatol": 1e-10, "fatol": 1e-14, "maxiter": 4000})
    return res.fun


def reference_disk_margins(plant, controller, f):
    """Balanced (skew 0) disk margins at the plant input, frequency by frequency with 2-D
    numpy only: the independent reference of trussid.lqg.disk_margins (issue 30: its stacked
    solve failed on numpy 2). L = -K P with the controller's inputs taken by the plant's
    output names; loop i broken with the others closed, L_i = L_ii - L_ir (I + L_rr)^-1 L_ri,
    alpha_i = min 1 / |1 / (1 + L_i) - 1/2|; MIMO alpha = 1 / max mu((I + L)^-1 - I/2), mu
    from :func:`_mu_dscaled` where mu can be the largest (its upper bound sigma_max reaches
    the largest lower bound, the spectral radius)."""
    iy = [list(plant.output_labels).index(n) for n in controller.input_labels]
    iu = [list(plant.input_labels).index(n) for n in controller.output_labels]
    m = len(iu)
    loops = np.full((m, len(f)), np.inf)
    Ms = []
    for k, fk in enumerate(f):
        z = np.exp(2j * np.pi * fk * plant.dt)
        P = _response(plant, z)[np.ix_(iy, iu)]
        L = -_response(controller, z) @ P
        for i in range(m):
            r = [j for j in range(m) if j != i]
            Li = L[i, i] - L[i, r] @ np.linalg.solve(np.eye(m - 1) + L[np.ix_(r, r)], L[r, i])
            loops[i, k] = 1.0 / abs(1.0 / (1.0 + Li) - 0.5)
        Ms.append(np.linalg.solve(np.eye(m) + L, np.eye(m)) - 0.5 * np.eye(m))
    rho = np.array([np.max(np.abs(np.linalg.eigvals(M))) for M in Ms])
    sig = np.array([np.linalg.norm(M, 2) for M in Ms])
    mu = rho.copy()
    for k in np.flatnonzero(sig >= rho.max()):
        mu[k] = _mu_dscaled(Ms[k])
    return {"mimo_alpha": 1.0 / mu.max(), "mimo_frequency_hz": float(f[np.argmax(mu)]),
            "loop_alpha": loops.min(axis=1), "n_dscaled": int(np.sum(sig >= rho.max()))}
