"""Closed-loop records (issue 34, acceptance 3): the predictor-based subspace prior
:func:`trussid.plid.closedloop.pbsid` against the open-loop N4SID prior on the same record,
the detection of feedback from a reference channel, and ``identify(..., closed_loop=True)``
on simulated LQG loops of the testbed and of the campaign's steel grid
(``closedloop_cases.py``): under a white unmeasured output disturbance (the acceptance's
setting, 1 % / 20 % on every dominant mode) and under an unmeasured structural force (harder,
not reached: an xfail with its measured misses).

The first tests' plant: two modes (50 and 120 Hz, 2 % damping) seen by a collocated
velocity sensor, driven by an actuator and by an unmeasured force elsewhere on the structure; the loop is
velocity feedback through one sample of computation delay, the dither 10 % of the control
signal's RMS, so the excitation is mostly the unmeasured force, as on the measured
cantilever record of the issue. The truth is the plant's own poles.
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from trussid.plid import modal_table
from trussid.plid.closedloop import FEEDBACK_SHARE, closed_loop_prior, feedback_share, pbsid
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.subspace import subspace_prior

DT = 1e-3
F0, Z0 = np.array([50.0, 120.0]), 0.02


def _plant() -> control.StateSpace:
    w = 2 * np.pi * F0
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2, 0], A[3, 1] = -w[0] ** 2, -w[1] ** 2
    A[2, 2], A[3, 3] = -2 * Z0 * w[0], -2 * Z0 * w[1]
    B = np.array([[0, 0], [0, 0], [1.0, 0.3], [0.6, -1.0]])   # actuator, unmeasured force
    C = 100.0 * np.array([[0, 0, 1.0, 0.6]])                  # collocated velocity
    return control.c2d(control.ss(A, B, C, 0), DT)


def _record(gain: float, n: int = 10000, dither_share: float = 0.1, seed: int = 0):
    """``(u, y, r)`` of the loop ``u_k = r_k - gain y_(k-1)``; ``r`` is ``dither_share`` of
    the RMS the control signal has without it (open loop: ``gain`` 0 and unit ``r``)."""
    G = _plant()
    A, B, C = (np.asarray(M) for M in (G.A, G.B, G.C))
    rng = np.random.default_rng(seed)
    d, noise = rng.standard_normal(n), 1e-3 * rng.standard_normal(n)

    def run(r):
        x, u, y = np.zeros(4), np.zeros(n), np.zeros(n)
        for k in range(n):
            y[k] = (C @ x)[0] + noise[k]
            u[k] = r[k] - gain * (y[k - 1] if k else 0.0)
            x = A @ x + B @ np.array([u[k], d[k]])
        return u, y

    scale = dither_share * np.std(run(np.zeros(n))[0]) if gain else 1.0
    r = scale * rng.standard_normal(n)
    u, y = run(r)
    return u[:, None], y[:, None], r[:, None]


def _modes(model):
    t = modal_table(model)
    keep = t.damping < 0.5
    return t.frequencies_hz[keep], t.damping[keep]


def _worst_errors(model):
    """Largest relative frequency and damping errors over the two true modes (each matched
    to the nearest identified mode); inf if the model has fewer modes."""
    f, z = _modes(model)
    if f.size < F0.size:
        return np.inf, np.inf
    idx = [int(np.argmin(np.abs(f - f0))) for f0 in F0]
    return (float(np.max(np.abs(f[idx] - F0) / F0)), float(np.max(np.abs(z[idx] - Z0) / Z0)))


def test_pbsid_recovers_the_plant_from_an_open_loop_record():
    u, y, _ = _record(gain=0.0)
    df, dz = _worst_errors(pbsid(u, y, 4, DT, past=40).model)
    assert df < 0.002 and dz < 0.1


def test_on_a_closed_loop_record_pbsid_is_far_closer_than_open_loop_n4sid():
    u, y, r = _record(gain=1.0)
    assert np.std(r) <= 0.1 * np.std(u)                  # the dither is at most 10 % of u
    n4sid_prior, _ = subspace_prior(u, y, 4, DT)
    df_n4, dz_n4 = _worst_errors(n4sid_prior)
    model, K, info = closed_loop_prior(u, y, 4, DT)
    df, dz = _worst_errors(model)
    # N4SID takes the loop for the plant: a mode more than 10 % off in frequency
    assert df_n4 > 0.1
    # PBSID: within 5 % in frequency and a factor 2 in damping (measured 2.5 % and 82 %:
    # the 1 % / 20 % are not reached at this dither share; see the report)
    assert df < 0.05 and dz < 1.0
    assert df < 0.5 * df_n4
    assert info.past in info.candidates and K.shape == (4, 1)


def test_feedback_share_tells_a_closed_loop_record_from_an_open_loop_one():
    u, _, r = _record(gain=1.0)
    assert feedback_share(u, r)[0] > 0.9
    u, _, r = _record(gain=0.0)
    assert feedback_share(u, r)[0] < 1e-6 < FEEDBACK_SHARE


def test_bad_input_is_named():
    u, y, r = _record(gain=0.0, n=2000)
    with pytest.raises(IdentificationError, match="order 80"):
        pbsid(u, y, 90, DT, past=80)
    with pytest.raises(DataError, match="samples"):
        pbsid(u[:300], y[:300], 4, DT, past=80)
    with pytest.raises(DataError, match="reference has 10 samples"):
        feedback_share(u, r[:10])


def _truth_errors(model, truth):
    """Worst relative frequency and damping errors over the truth's modes, each matched to
    the nearest identified lightly damped mode (inf when the model has fewer)."""
    t = modal_table(model)
    keep = (t.damping > 0) & (t.damping < 0.5)
    f, z = t.frequencies_hz[keep], t.damping[keep]
    if f.size < truth.frequencies_hz.size:
        return np.inf, np.inf
    idx = [int(np.argmin(np.abs(f - f0))) for f0 in truth.frequencies_hz]
    return (float(np.max(np.abs(f[idx] - truth.frequencies_hz) / truth.frequencies_hz)),
            float(np.max(np.abs(z[idx] - truth.damping) / truth.damping)))


def _closed_loop_case(case, seed=0):
    from tests.plid import closedloop_cases as cc

    from trussid.plid import identify

    truth = cc.testbed_truth() if case == "testbed" else cc.grid_truth()
    u, y, r = cc.record(truth, cc.lqg(truth), cc.SAMPLES, seed=seed)
    assert np.std(r) <= 0.1 * np.std(u) + 1e-12          # dither at most 10 % of the input
    n, dt = truth.plant.nstates, truth.plant.dt
    n4sid_prior, _ = subspace_prior(u, y, n, dt)
    fit = identify(u, y, n, dt, closed_loop=True, progress=False)
    return truth, fit, _truth_errors(fit.model, truth), _truth_errors(n4sid_prior, truth)


@pytest.mark.slow
def test_on_the_testbed_loop_identify_closed_loop_is_far_closer_than_open_loop_n4sid():
    """The testbed under a gentle LQG loop (its three dominant modes, 0.25 % damping, raised
    to 0.4-10 % by the loop), 2e4 samples: measured (seed 0) closed-loop recipe 1.4 % /
    77 %, N4SID 9.2 % / 8800 % (benchmarks/results/closedloop_i35.md)."""
    _, fit, (df, dz), (df_n4, dz_n4) = _closed_loop_case("testbed")
    assert fit.provenance.closed_loop.decided_by == "told"
    assert fit.result is None and "output" in fit.provenance.closed_loop.plid_passes
    assert df < 0.03 and dz < 1.0
    assert df < 0.5 * df_n4 and dz < 0.1 * dz_n4


@pytest.mark.slow
@pytest.mark.xfail(strict=False, reason=(
    "the harder structural-force setting (an unmeasured force on the structure, not the "
    "acceptance's output disturbance; benchmarks/results/closedloop_i35.md, 2e4 samples): "
    "the closed-loop recipe's worst mode is 0.3-1.4 % off in frequency and 26-77 % in "
    "damping on the testbed, 3.0-3.9 % and 35-99 % on the grid; the one-step criterion is "
    "flat in the modal parameters there (the fit started from the truth itself drifts by "
    "over 1 %; longer records did not help within the fit's budget)"))
@pytest.mark.parametrize("case", ["testbed", "grid"])
def test_identify_closed_loop_under_a_structural_force(case):
    _, _, (df, dz), (df_n4, dz_n4) = _closed_loop_case(case)
    assert df < 0.01 and dz < 0.2
    assert df_n4 > df and dz_n4 > dz


#: Output-disturbance record lengths: the grid's 2e4 samples at 400 Hz (50 s); the testbed's
#: 1e6 at 1.6 kHz (10 min). The testbed's loop damps its 166 Hz mode from 0.25 % to 10 %, and
#: 85 % of its outputs' power is the disturbance: on 2e4-2e5 samples the fit started from
#: the truth itself scatters by 6-54 % in damping over seeds, where the recipe lands on the
#: same optimum (benchmarks/results/closedloop_i35.md): the record's information, not the
#: method, sets the length. Measured (seed 0): grid 0.05 % / 1.9 %, testbed at 1e6 0.026 % /
#: 4.4 % (N4SID: 23 % / 850 % on the grid, a mode missed on the testbed); the testbed case
#: took 9.4 CPU minutes at load 4-5.
OUTPUT_SAMPLES = {"grid": 20000, "testbed": 1000000}


def _output_case(case, samples, seed=0):
    """Truth, record and the acceptance's conditions on it: the dither at most 10 % of the
    control signal's RMS and the input mostly feedback of the unmeasured disturbance."""
    from tests.plid import closedloop_cases as cc

    truth = cc.testbed_truth("actuator") if case == "testbed" else cc.grid_truth("actuator")
    ctl = cc.lqg(truth, design_noise="actuator")
    u, y, r = cc.record(truth, ctl, samples, seed=seed, disturbance="output")
    assert np.std(r) <= 0.1 * np.std(u)
    assert feedback_share(u, r)[0] > 0.95
    return truth, u, y


@pytest.mark.parametrize("case", [
    "grid", pytest.param("testbed", marks=pytest.mark.slow)])
def test_identify_closed_loop_meets_one_percent_and_twenty_percent(case):
    """Acceptance 3: under a white unmeasured output disturbance fed back by the LQG loop,
    every dominant mode within 1 % in frequency and 20 % in damping, where open-loop N4SID
    on the same record misses by more in both (it takes the loop for the plant)."""
    from trussid.plid import identify

    truth, u, y = _output_case(case, OUTPUT_SAMPLES[case])
    n, dt = truth.plant.nstates, truth.plant.dt
    fit = identify(u, y, n, dt, closed_loop=True, progress=False)
    df, dz = _truth_errors(fit.model, truth)
    df_n4, dz_n4 = _truth_errors(subspace_prior(u, y, n, dt)[0], truth)
    assert df < 0.01 and dz < 0.2
    assert df_n4 > df and dz_n4 > dz
    assert df_n4 > 0.1                      # N4SID misses by far more than the target


def test_on_an_output_disturbance_record_the_recipe_reaches_the_truth_started_optimum():
    """The recipe's misses are the record's information, not its optimisation: started from
    the truth itself (its actuator path with K = 0, the true innovations model of a white
    output disturbance), the prediction-error fit lands on the recipe's optimum."""
    import control

    from trussid.plid.closedloop import identify_closed_loop, prediction_error_fit

    truth, u, y = _output_case("grid", 20000, seed=1)
    G = truth.plant
    model, _, _, info = identify_closed_loop(u, y, G.nstates, G.dt)
    start = control.ss(G.A, np.asarray(G.B)[:, :1], G.C, 0, G.dt)
    from_truth = prediction_error_fit(start, np.zeros((G.nstates, 2)), u, y,
                                      max_evaluations=200)
    assert info.converged and from_truth.converged
    assert from_truth.cost_end == pytest.approx(info.cost_end, rel=1e-6)
    a, b = modal_table(model), modal_table(from_truth.model)
    np.testing.assert_allclose(a.frequencies_hz, b.frequencies_hz, rtol=1e-5)
    np.testing.assert_allclose(a.damping, b.damping, rtol=1e-3)


def test_a_reference_channel_that_shows_feedback_selects_the_closed_loop_recipe():
    from trussid.plid import identify

    u, y, r = _record(gain=1.0, n=4000)
    fit = identify(u, y, 4, DT, reference=r, progress=False)
    assert fit.provenance.closed_loop.decided_by == "reference channel"
    assert fit.provenance.closed_loop.feedback_share[0] > 0.9
    u, y, r = _record(gain=0.0, n=4000)
    assert identify(u, y, 4, DT, reference=r, progress=False).provenance.closed_loop is None


def test_the_closed_loop_recipe_refuses_a_direct_term():
    from trussid.plid import identify

    u, y, _ = _record(gain=1.0, n=3000)
    with pytest.raises(IdentificationError, match="direct"):
        identify(u, y, 4, DT, closed_loop=True, direct=True, progress=False)


def test_prediction_error_fit_lowers_the_criterion_and_keeps_an_open_loop_truth():
    """On an open-loop record (where every consistent method agrees) the refinement from
    PBSID's start lowers the one-step criterion and stays on the plant's modes."""
    from trussid.plid.closedloop import prediction_error_fit

    u, y, _ = _record(gain=0.0)
    start = pbsid(u, y, 4, DT, past=40)
    fit = prediction_error_fit(start.model, start.K, u, y)
    df, dz = _worst_errors(fit.model)
    assert fit.cost_end <= fit.cost_start
    assert df < 0.002 and dz < 0.1
    assert fit.predictor_radius < 1
