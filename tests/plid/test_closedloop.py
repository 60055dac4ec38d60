"""Closed-loop records (issue 34, acceptance 3): the predictor-based subspace prior
:func:`trussid.plid.closedloop.pbsid` against the open-loop N4SID prior on the same record,
the detection of feedback from a reference channel, and ``identify(..., closed_loop=True)``
on simulated LQG loops of the testbed and of the campaign's steel grid
(``closedloop_cases.py``).

The plant: two modes (50 and 120 Hz, 2 % damping) seen by a collocated velocity sensor,
driven by an actuator and by an unmeasured force elsewhere on the structure; the loop is
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
    77 %, N4SID 9.2 % / 8800 % (benchmarks/results/closedloop.md)."""
    _, fit, (df, dz), (df_n4, dz_n4) = _closed_loop_case("testbed")
    assert fit.provenance.closed_loop.decided_by == "told"
    assert fit.result is None and "output" in fit.provenance.closed_loop.plid_passes
    assert df < 0.03 and dz < 1.0
    assert df < 0.5 * df_n4 and dz < 0.1 * dz_n4


@pytest.mark.slow
@pytest.mark.xfail(strict=False, reason=(
    "issue 34 acceptance 3 not reached (benchmarks/results/closedloop.md, 2e4-sample records, "
    "10 % dither, gentle LQG): the closed-loop recipe's worst mode is 0.3-1.4 % off in "
    "frequency and 26-77 % in damping on the testbed (N4SID 3.3-9.2 %, damping x75-88 off), "
    "3.0-3.9 % and 34-98 % on the grid (N4SID misses a mode); prediction error started from "
    "the truth itself drifts by over 1 % on such records: they carry too little information"))
@pytest.mark.parametrize("case", ["testbed", "grid"])
def test_identify_closed_loop_meets_one_percent_and_twenty_percent(case):
    _, _, (df, dz), (df_n4, dz_n4) = _closed_loop_case(case)
    assert df < 0.01 and dz < 0.2
    assert df_n4 > df and dz_n4 > dz


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
