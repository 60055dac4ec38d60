"""The compiled PLID recursions equal the reference numpy steps, and the fallback is them.

The references are :func:`direct_step` and :func:`sqrt_step` (themselves checked against a
Monte-Carlo propagation in ``test_recursion.py``); the kernels are written independently
(sparse C, CSR F, column-wise factor reads, a semiseparable Carlson product, their own
Householder LQ), so agreement to rounding checks the arithmetic, not a copy of it.
"""

import numpy as np
import pytest

from trussid.plid import recursion_kernel as RK
from trussid.plid.bases import basis_for
from trussid.plid.canonical import ObserverBasis
from trussid.plid.estimator import PLID
from trussid.plid.recursion_common import Problem
from trussid.plid.recursion_direct import direct_init, direct_step
from trussid.plid.recursion_sqrt import sqrt_covariance, sqrt_init, sqrt_step

needs_numba = pytest.mark.skipif(not RK.HAVE_NUMBA, reason="numba not installed")


def _problem(basis, m, N, Q_theta):
    return Problem(basis, m, Q=1e-6, R=1e-4 * np.eye(basis.p), N=N, Q_theta=Q_theta)


def _record(plant_fn, simulate, rng, m, p, n_samples):
    plant = plant_fn([60.0, 140.0, 310.0], [0.02, 0.03, 0.01], m, p, 1600, rng)
    u = rng.standard_normal((n_samples, m))
    y, _ = simulate(plant, u, rng, snr_db=40)
    return u / u.std(0), y / y.std(0)


def _reference(step, init, pb, z0, P0, us, ys, every):
    st = init(pb, z0, P0)
    E = np.empty_like(ys)
    hist = []
    for k in range(len(us)):
        step(pb, st, us[k], ys[k], E[k])
        if (k + 1) % every == 0:
            hist.append(st.z[:pb.q].copy())
    return st, E, np.array(hist)


def _rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


CASES = {
    # name: (basis factory(n, p), m, N, Q_theta)
    "shift SIMO": (lambda n, p: ObserverBasis.shift(n, p), 1, None, None),
    "rotation MIMO": (lambda n, p: basis_for(n, p, 1600.0, [50, 90, 150, 220, 300, 400]), 2,
                      None, None),
    "shift MIMO, input noise and drift": (lambda n, p: ObserverBasis.shift(n, p), 2,
                                          np.diag([1e-3, 2e-3]), 1e-8),
    # without drift the square-root kernel runs its own input-noise moments (a correlated N,
    # so that its triangular factor has an off-diagonal entry)
    "rotation MIMO, input noise": (lambda n, p: basis_for(n, p, 1600.0,
                                                          [50, 90, 150, 220, 300, 400]), 2,
                                   np.array([[1e-3, 4e-4], [4e-4, 2e-3]]), None),
}


@needs_numba
@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("form", ["direct", "sqrt"])
def test_kernel_equals_the_reference_step_to_rounding(case, form, modal_plant, simulate, rng):
    make, m, N, Qth = CASES[case]
    n, p = 6, (2 if "MIMO" in case else 3)
    basis = make(n, p)
    pb = _problem(basis, m, N, Qth)
    us, ys = _record(modal_plant, simulate, rng, m, p, 600)
    z0 = np.zeros(pb.dim)
    z0[:pb.q] = 0.05 * rng.standard_normal(pb.q)
    P0 = np.diag(np.r_[np.full(pb.q, 1e-1), np.full(n, 1e2)])
    step, init, run = ((direct_step, direct_init, RK.run_direct) if form == "direct"
                       else (sqrt_step, sqrt_init, RK.run_sqrt))
    ref, E_ref, H_ref = _reference(step, init, pb, z0, P0, us, ys, every=7)
    st = init(pb, z0, P0)
    E = np.empty_like(ys)
    hist = np.empty((RK.history_rows(0, len(us), 7), pb.q))
    out = run(pb, st, us, ys, E, hist, 7, 0, use_kernel=True)
    assert out.failed == -1
    cov = (lambda s: s.P) if form == "direct" else sqrt_covariance
    assert _rel(st.z, ref.z) < 1e-9
    assert _rel(cov(st), cov(ref)) < 1e-9
    assert _rel(E, E_ref) < 1e-9
    assert _rel(hist, H_ref) < 1e-9
    # and the comparison is not between two idle runs: the model learned (the outputs
    # have unit RMS; the last innovations are a fraction of that)
    assert np.std(E[-100:]) < 0.3



SQRT_SHAPES = {
    # name: (basis factory(n, p), n, p, m): the kernel's three-output paths (four-column
    # Carlson sweeps, dense C rows in the rotation basis, unrolled recurrences) and the
    # generic ones they stand beside (one output; four outputs, whose fourth update takes
    # the general recurrence)
    "rotation 3 -> 3": (lambda n, p: basis_for(n, p, 1600.0, [50, 90, 150, 220, 300, 400]),
                        12, 3, 3),
    "shift 1 -> 1": (lambda n, p: ObserverBasis.shift(n, p), 6, 1, 1),
    "shift 2 -> 4": (lambda n, p: ObserverBasis.shift(n, p), 8, 4, 2),
    "rotation 2 -> 4": (lambda n, p: basis_for(n, p, 1600.0, [50, 90, 150, 220, 300, 400]),
                        8, 4, 2),
}


@needs_numba
@pytest.mark.parametrize("shape", list(SQRT_SHAPES))
def test_sqrt_kernel_equals_the_reference_step_for_one_to_four_outputs(shape, modal_plant,
                                                                       simulate, rng):
    make, n, p, m = SQRT_SHAPES[shape]
    pb = _problem(make(n, p), m, None, None)
    us, ys = _record(modal_plant, simulate, rng, m, p, 500)
    z0 = np.zeros(pb.dim)
    z0[:pb.q] = 0.05 * rng.standard_normal(pb.q)
    P0 = np.diag(np.r_[np.full(pb.q, 1e-1), np.full(n, 1e2)])
    ref, E_ref, H_ref = _reference(sqrt_step, sqrt_init, pb, z0, P0, us, ys, every=7)
    st = sqrt_init(pb, z0, P0)
    E = np.empty_like(ys)
    hist = np.empty((RK.history_rows(0, len(us), 7), pb.q))
    assert RK.run_sqrt(pb, st, us, ys, E, hist, 7, 0, use_kernel=True).failed == -1
    assert _rel(st.z, ref.z) < 1e-9
    assert _rel(sqrt_covariance(st), sqrt_covariance(ref)) < 1e-9
    assert _rel(E, E_ref) < 1e-9
    assert _rel(hist, H_ref) < 1e-9
    assert np.std(E[-100:]) < 0.3         # it learned: not two idle runs compared


@needs_numba
def test_kernel_in_blocks_equals_one_call(modal_plant, simulate, rng):
    # fit runs blocks of 2000 samples, update one sample: the history counter and the
    # state must carry across the block boundaries exactly.
    pb = _problem(ObserverBasis.shift(6, 3), 1, None, None)
    us, ys = _record(modal_plant, simulate, rng, 1, 3, 300)
    P0 = np.diag(np.r_[np.full(pb.q, 1e-1), np.full(6, 1e2)])
    whole = direct_init(pb, np.zeros(pb.dim), P0)
    H1 = np.empty((RK.history_rows(0, 300, 7), pb.q))
    RK.run_direct(pb, whole, us, ys, np.empty_like(ys), H1, 7, 0)
    part = direct_init(pb, np.zeros(pb.dim), P0)
    H2 = []
    for k0, k1 in ((0, 45), (45, 46), (46, 300)):
        h = np.empty((RK.history_rows(k0, k1 - k0, 7), pb.q))
        RK.run_direct(pb, part, us[k0:k1], ys[k0:k1], np.empty((k1 - k0, 3)), h, 7, k0)
        H2.append(h)
    assert np.array_equal(part.z, whole.z) and np.array_equal(part.P, whole.P)
    assert np.array_equal(np.concatenate(H2), H1)


@pytest.mark.parametrize("form", ["direct", "sqrt"])
def test_fit_is_the_same_with_and_without_numba(form, modal_plant, simulate, rng, monkeypatch):
    plant = modal_plant([70.0, 150.0, 300.0], [0.02] * 3, 2, 3, 1600, rng)
    u = rng.standard_normal((500, 2))
    y, _ = simulate(plant, u, rng, snr_db=40)
    # A prior variance of the coefficients' size: with the default 1e4 the direct form's
    # own round-off (against the square-root form) is ~5e-9 on this record, and two
    # correct orderings of its sums differ by that much (the estimator's docstring).
    kw = dict(form=form, R=1e-4, history_every=5, prior_theta_var=1.0)
    compiled = PLID(6, **kw).fit(u, y)
    reference = PLID(6, compiled=False, **kw).fit(u, y)
    monkeypatch.setattr(RK, "HAVE_NUMBA", False)
    absent = PLID(6, **kw).fit(u, y)
    # without numba the default path is the reference steps, bit for bit
    assert np.array_equal(absent.theta, reference.theta)
    assert np.array_equal(absent.innovations, reference.innovations)
    for a, b in ((compiled.theta, reference.theta), (compiled.theta_cov, reference.theta_cov),
                 (compiled.innovations, reference.innovations),
                 (compiled.theta_history, reference.theta_history)):
        assert _rel(a, b) < 1e-9
    assert np.array_equal(compiled.history_index, reference.history_index)
    assert compiled.first_negative_variance == reference.first_negative_variance


@needs_numba
def test_a_non_finite_sample_leaves_the_estimate_non_finite_on_both_paths():
    # The kernel is compiled without the finite-math flags, so NaN/inf propagate as in the
    # reference (which PLID then reports as finite=False) instead of being optimised away.
    pb = _problem(ObserverBasis.shift(2, 1), 1, None, None)
    P0 = np.eye(pb.dim)
    us = np.ones((5, 1))
    ys = np.array([[1.0], [np.inf], [1.0], [1.0], [1.0]])
    a = direct_init(pb, np.zeros(pb.dim), P0)
    b = direct_init(pb, np.zeros(pb.dim), P0)
    with np.errstate(all="ignore"):
        RK.run_direct(pb, a, us, ys, np.empty((5, 1)), np.empty((0, pb.q)), 0, 0,
                      use_kernel=False)
        RK.run_direct(pb, b, us, ys, np.empty((5, 1)), np.empty((0, pb.q)), 0, 0,
                      use_kernel=True)
    assert not np.all(np.isfinite(a.z)) and not np.all(np.isfinite(b.z))


@needs_numba
def test_a_non_finite_sample_stops_the_square_root_kernel_as_the_reference():
    # the square-root step raises on a non-finite moment (PLID then carries NaN); the
    # kernel reports that sample and carries NaN too (the test is per entry: a branch-free
    # sum of 0 * x, NaN exactly where x is not finite, was folded to 0 under the kernels'
    # fastmath flags and missed the sample)
    pb = _problem(ObserverBasis.shift(2, 1), 1, None, None)
    P0 = np.eye(pb.dim)
    us = np.ones((5, 1))
    ys = np.array([[1.0], [np.inf], [1.0], [1.0], [1.0]])
    a = sqrt_init(pb, np.zeros(pb.dim), P0)
    b = sqrt_init(pb, np.zeros(pb.dim), P0)
    with np.errstate(all="ignore"):
        RK.run_sqrt(pb, a, us, ys, np.empty((5, 1)), np.empty((0, pb.q)), 0, 0,
                    use_kernel=False)
        out = RK.run_sqrt(pb, b, us, ys, np.empty((5, 1)), np.empty((0, pb.q)), 0, 0,
                          use_kernel=True)
    assert not np.all(np.isfinite(a.z)) and not np.all(np.isfinite(b.z))
    assert out.failed == 1
