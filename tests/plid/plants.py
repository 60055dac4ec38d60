"""Plants for the direct-term and predictor tests (imported, not fixtures)."""

import control
import numpy as np


def accelerometer_plant(seed=3, m=2, p=3, fs=1000.0):
    """Force in, acceleration out, no filters: three modes (40, 130, 310 Hz, 1-2 %),
    ``y = C_acc x + D u`` with the true feed-through ``D = sum_i phi_i b_i^T`` of the
    acceleration of a modal system; ZOH at ``fs`` keeps D."""
    rng = np.random.default_rng(seed)
    freqs, zetas = (40.0, 130.0, 310.0), (0.01, 0.02, 0.015)
    n = 2 * len(freqs)
    A = np.zeros((n, n))
    phi = rng.standard_normal((p, len(freqs)))
    b = rng.standard_normal((len(freqs), m))
    B = np.zeros((n, m))
    C = np.zeros((p, n))
    for i, (f, z) in enumerate(zip(freqs, zetas)):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-w * w, -2 * z * w]]
        B[2 * i + 1] = b[i]
        # acceleration q'' = -w^2 q - 2 z w q' + b u
        C[:, 2 * i] = -w * w * phi[:, i]
        C[:, 2 * i + 1] = -2 * z * w * phi[:, i]
    D = phi @ b
    return control.c2d(control.ss(A, B, C, D), 1 / fs)


def record(plant, n_samples, snr_db, seed):
    """White-noise input and the plant's output with white noise ``snr_db`` below it."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n_samples, plant.ninputs))
    y0 = np.atleast_2d(control.forced_response(plant, U=u.T).outputs).T
    noise = rng.standard_normal(y0.shape) * np.sqrt(np.mean(y0 ** 2, 0)) / 10 ** (snr_db / 20)
    return u, y0 + noise
