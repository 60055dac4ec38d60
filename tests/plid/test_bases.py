"""Rotation observer bases and exact conversion of known models into them (plid.bases)."""

import control
import numpy as np
import pytest
import scipy.linalg

from trussid.plid.bases import (band_frequencies, basis_for, conversion_condition, data_frequencies,
                        model_frequencies, rotation_basis, to_basis)
from trussid.plid.canonical import to_matrices
from trussid.plid.errors import IdentificationError
from trussid.plid.frf import frequency_response

FS = 1600.0


def modal_plant(freqs, zeta, m, p, seed, fs=FS, velocity=False):
    """ZOH-discretised lightly damped modal plant, displacement (or velocity) outputs, D = 0."""
    rng = np.random.default_rng(seed)
    n = 2 * len(freqs)
    A = np.zeros((n, n))
    for i, f in enumerate(freqs):
        w = 2 * np.pi * f
        # states (w q, q'): a well-scaled realisation, so that conversion accuracy
        # reflects the basis and not the plant's own state scaling
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, w], [-w, -2 * zeta * w]]
    B = np.zeros((n, m))
    # participations of unit size and random sign: every mode is visible in the data
    sign = lambda shape: rng.choice([-1.0, 1.0], shape) * rng.uniform(0.5, 1.5, shape)
    B[1::2] = sign((len(freqs), m))
    C = sign((p, n))
    C[:, 0 if velocity else 1::2] = 0
    return control.c2d(control.ss(A, B, C, np.zeros((p, m))), 1 / fs)


def test_rotation_basis_is_stable_observable_and_sums_one_component_per_block():
    f = [50.0, 120.0, 200.0, 310.0, 400.0, 555.0]
    b = rotation_basis(f, FS, p=2, radius=0.95)
    assert b.n == 12 and b.p == 2
    np.testing.assert_allclose(np.abs(np.linalg.eigvals(b.F)), 0.95, rtol=1e-12)
    ang = np.sort(np.abs(np.angle(np.linalg.eigvals(b.F))))[::2] * FS / (2 * np.pi)
    np.testing.assert_allclose(ang, f, rtol=1e-10)
    O = np.vstack([b.C @ np.linalg.matrix_power(b.F, k) for k in range(b.n)])
    assert np.linalg.matrix_rank(O) == b.n
    # every block's first component appears in exactly one output row, the second in none
    np.testing.assert_array_equal(b.C[:, 0::2].sum(axis=0), np.ones(6))
    np.testing.assert_array_equal(b.C[:, 1::2], 0)
    # partition: each output owns n / p = 6 states whose frequencies span the band
    owned = [np.flatnonzero(b.C[i, 0::2]) for i in range(2)]
    assert [len(o) for o in owned] == [3, 3]
    assert min(np.asarray(f)[owned[0]]) == 50.0 and max(np.asarray(f)[owned[1]]) == 555.0


@pytest.mark.parametrize("method", ["observability", "sylvester"])
@pytest.mark.parametrize("m,p", [(1, 1), (1, 2), (2, 2)])
def test_conversion_is_a_similarity_with_the_basis_C_and_the_same_frequency_response(method, m, p):
    plant = modal_plant([60, 140, 230, 330], 0.01, m, p, seed=3)
    basis = basis_for(8, p, FS, band_frequencies(4, (40, 400)))
    theta, T = to_basis(plant, basis, method)
    A2, B2, C2 = to_matrices(theta, basis, m)
    A, B, C = (np.asarray(M) for M in (plant.A, plant.B, plant.C))
    # the defining identities: C_b T = C and T A T^-1 = F + Abar C_b
    np.testing.assert_allclose(C2 @ T, C, atol=1e-8 * np.abs(C).max())
    np.testing.assert_allclose(T @ A @ np.linalg.inv(T), A2, atol=1e-7)
    f = np.linspace(10, 790, 300)
    H = frequency_response(plant, f)
    H2 = frequency_response(control.ss(A2, B2, C2, 0, plant.dt), f)
    np.testing.assert_allclose(H2, H, rtol=1e-6)


def test_observability_and_sylvester_conversions_agree():
    plant = modal_plant([55, 130, 210, 290, 370, 450], 0.005, 1, 3, seed=4)
    basis = basis_for(12, 3, FS, model_frequencies(plant, 6, FS), radius=0.97)
    th1, T1 = to_basis(plant, basis, "observability")
    th2, T2 = to_basis(plant, basis, "sylvester")
    np.testing.assert_allclose(th1, th2, rtol=1e-5, atol=1e-6 * np.abs(th2).max())
    np.testing.assert_allclose(T1, T2, rtol=1e-5, atol=1e-6 * np.abs(T2).max())


def test_odd_observability_index_gets_one_real_pole_per_output():
    # 6 states, 2 outputs: nu = 3 = one rotation + one real pole per output; the plant has
    # two modes and two real poles (like an input filter), so the form fits it naturally
    modes = modal_plant([70, 260], 0.01, 1, 2, seed=5)
    rng = np.random.default_rng(5)
    A = scipy.linalg.block_diag(modes.A, np.diag([0.5, 0.3]))
    plant = control.ss(A, np.vstack([modes.B, rng.standard_normal((2, 1))]),
                       np.hstack([modes.C, rng.standard_normal((2, 2))]), 0, modes.dt)
    basis = basis_for(6, 2, FS, [100.0, 300.0], radius=0.9)
    assert basis.n == 6
    real = np.linalg.eigvals(basis.F)
    assert np.sum(np.abs(real.imag) < 1e-12) == 2
    theta, T = to_basis(plant, basis, "sylvester")
    A2, B2, C2 = to_matrices(theta, basis, 1)
    f = np.linspace(10, 790, 200)
    H = frequency_response(plant, f)
    H2 = frequency_response(control.ss(A2, B2, C2, 0, plant.dt), f)
    np.testing.assert_allclose(H2, H, rtol=1e-6)


def test_rotation_basis_is_far_better_conditioned_than_the_shift_form():
    # 24 states, 3 outputs, 0.25 % damping: the regime of docs/plid.md "Beyond 12 states"
    f = np.geomspace(45, 360, 12)
    plant = modal_plant(f, 0.0025, 1, 3, seed=6)
    from trussid.plid.canonical import ObserverBasis, from_statespace

    _, Ts = from_statespace(plant, ObserverBasis.shift(24, 3))
    cond_rot = conversion_condition(plant, basis_for(24, 3, FS, model_frequencies(plant, 12, FS)))
    assert cond_rot < 1e-2 * np.linalg.cond(Ts)


def test_data_frequencies_find_the_resonances():
    f_true = np.array([80.0, 170.0, 260.0, 410.0])
    # velocity outputs: resonances of comparable height (with displacements the static
    # level can swallow the lowest mode's peak)
    plant = modal_plant(f_true, 0.005, 1, 2, seed=7, velocity=True)
    rng = np.random.default_rng(8)
    u = rng.standard_normal((16384, 1))
    y = control.forced_response(plant, U=u.T).outputs.T
    got = data_frequencies(u, y, FS, 4)
    np.testing.assert_allclose(got, f_true, atol=FS / 1024)


def test_model_frequencies_are_the_pole_angles_topped_up_from_the_band():
    plant = modal_plant([100.0, 200.0], 0.0, 1, 1, seed=9)
    got = model_frequencies(plant, 3, FS, band=(50, 700))
    assert got.size == 3
    np.testing.assert_allclose(got[[1, 2]], [100.0, 200.0], rtol=1e-9)
    assert 50 <= got[0] <= 700


@pytest.mark.parametrize("kwargs,word", [
    ({"freqs_hz": [100, 900]}, "fs/2"),
    ({"freqs_hz": [100, 100]}, "distinct"),
    ({"freqs_hz": [100, 200], "radius": 1.0}, "radius"),
    ({"freqs_hz": [100, 200], "layout": "spiral"}, "layout"),
    ({"freqs_hz": [100, 200, 300], "p": 2}, "evenly"),
])
def test_bad_basis_settings_are_refused_by_name(kwargs, word):
    args = {"fs": FS, "p": 1} | kwargs
    with pytest.raises(IdentificationError, match=word):
        rotation_basis(**args)


def test_conversion_refuses_a_feedthrough_term():
    plant = modal_plant([100.0, 200.0], 0.01, 1, 1, seed=1)
    bad = control.ss(plant.A, plant.B, plant.C, [[1.0]], plant.dt)
    with pytest.raises(IdentificationError, match="feed-through"):
        to_basis(bad, basis_for(4, 1, FS, [90.0, 210.0]))


def test_selector_coordinates_give_the_same_model_and_a_selector_C():
    from trussid.plid.bases import as_selector

    plant = modal_plant([60, 140, 230, 330, 420, 510], 0.01, 1, 3, seed=12)
    basis = basis_for(12, 3, FS, band_frequencies(6, (40, 600)))
    sb = as_selector(basis)
    assert np.all(sb.C.sum(axis=1) == 1) and set(np.unique(sb.C)) == {0.0, 1.0}
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(sb.F)),
                               np.sort_complex(np.linalg.eigvals(basis.F)), atol=1e-12)
    theta, _ = to_basis(plant, sb, "sylvester")
    A2, B2, C2 = to_matrices(theta, sb, 1)
    f = np.linspace(10, 790, 200)
    np.testing.assert_allclose(frequency_response(control.ss(A2, B2, C2, 0, plant.dt), f),
                               frequency_response(plant, f), rtol=1e-7)
