"""The N4SID prior (PO-MOESP, Verhaegen and Verdult 2007, p. 329) against nfoursid, the
package whose algorithm it writes out, and against the true system."""

import control
import numpy as np
import pandas as pd
import pytest
from nfoursid.nfoursid import NFourSID
from nfoursid.utils import Utils

from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.subspace import (MIN_GAIN_DB, block_hankel, direct_term_test, n4sid,
                                   output_error_fit, po_moesp, sweep_block_rows)
from tests.plid.plants import accelerometer_plant, record as plant_record


@pytest.fixture(scope="module")
def record():
    rng = np.random.default_rng(0)
    sys = control.c2d(control.ss([[-1.0, 40.0], [-40.0, -1.0]], [[0.0, 1.0], [1.0, 0.5]],
                                 [[1.0, 0.0], [0.3, 1.0]], 0), 0.01)
    u = rng.standard_normal((800, 2))
    y = control.forced_response(sys, U=u.T).outputs.T
    return sys, u, y + 1e-4 * rng.standard_normal(y.shape)


def test_block_hankel_is_nfoursids(record):
    _, u, y = record
    for a, rows in ((u, 7), (y, 5), (u[:, :1], 1)):
        assert np.array_equal(block_hankel(a, rows), Utils.block_hankel_matrix(a, rows))


def test_po_moesp_factors_and_the_model_are_nfoursids(record):
    _, u, y = record
    nf = NFourSID(pd.DataFrame(np.hstack([u, y]), columns=["u0", "u1", "y0", "y1"]),
                  output_columns=["y0", "y1"], input_columns=["u0", "u1"], num_block_rows=10)
    nf.subspace_identification()
    R22, R32, sv, _ = po_moesp(u, y, 10)
    # QR factors are unique up to the signs of their rows
    np.testing.assert_allclose(np.abs(R32), np.abs(nf.R32), rtol=1e-12, atol=1e-12 * sv[0])
    np.testing.assert_allclose(np.abs(R22), np.abs(nf.R22), rtol=1e-12,
                               atol=1e-12 * np.abs(R22).max())
    np.testing.assert_allclose(sv, np.diag(nf.R32_decomposition.eigenvalues), rtol=1e-12)
    ours = n4sid(u, y, 2, 10, 0.01).with_d
    theirs, _ = nf.system_identification(rank=2)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(ours.A)),
                               np.sort_complex(np.linalg.eigvals(theirs.a)), rtol=1e-10)


def test_the_true_poles_are_found(record):
    sys, u, y = record
    fit = n4sid(u, y, 2, 10, 0.01)
    for model in (fit.with_d, fit.zero_d):
        np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(model.A)),
                                   np.sort_complex(np.linalg.eigvals(sys.A)), rtol=1e-4)


def test_bad_requests_are_named(record):
    _, u, y = record
    with pytest.raises(IdentificationError, match="at most order 4"):
        n4sid(u, y, 6, 2, 0.01)
    with pytest.raises(DataError, match="at least 22 samples"):
        n4sid(u[:10], y[:10], 2, 10, 0.01)
    bad = y.copy()
    bad[5, 1] = np.nan
    with pytest.raises(DataError, match="y at sample 5 .column 1. is not finite"):
        n4sid(u, bad, 2, 10, 0.01)


# ---- output error with a direct term, and the test for one (issue 16) -------------------


def test_n4sid_refuses_too_few_block_rows_for_the_order():
    u = np.random.default_rng(0).standard_normal((400, 1))
    with pytest.raises(IdentificationError, match="at most order"):
        n4sid(u, u, 6, 3, 1.0)


def test_output_error_fit_recovers_B_and_D_exactly_on_noiseless_data():
    plant = accelerometer_plant()
    u, _ = plant_record(plant, 600, 300, seed=1)
    y = np.atleast_2d(control.forced_response(plant, U=u.T).outputs).T
    wrong = control.ss(plant.A, np.ones_like(plant.B), plant.C, 0 * plant.D, plant.dt)
    fit, y_sim, D_std = output_error_fit(wrong, u, y, direct=True)
    np.testing.assert_allclose(fit.D, plant.D, rtol=1e-7, atol=1e-9 * np.abs(plant.D).max())
    np.testing.assert_allclose(fit.B, plant.B, rtol=1e-6, atol=1e-9 * np.abs(plant.B).max())
    np.testing.assert_allclose(y_sim, y, atol=1e-8 * np.abs(y).max())
    assert D_std.shape == plant.D.shape


def test_direct_term_test_asks_for_D_on_an_accelerometer_and_not_on_a_strictly_proper_plant():
    acc = accelerometer_plant()
    u, y = plant_record(acc, 3000, 40, seed=2)
    assert direct_term_test(acc, u, y)["direct"]
    proper = control.ss(acc.A, acc.B, acc.C, 0 * acc.D, acc.dt)
    u, y = plant_record(proper, 3000, 40, seed=2)
    test = direct_term_test(proper, u, y)
    assert not test["direct"]
    # with no feed-through in the data, D only fits noise: the held-out error does not drop
    assert test["held_out_nmse"]["with"] > 0.95 * test["held_out_nmse"]["without"]


def test_output_error_fit_refuses_an_unstable_model():
    unstable = control.ss([[1.01]], [[1.0]], [[1.0]], 0, 1.0)
    u = np.ones((50, 1))
    with pytest.raises(IdentificationError, match="stable"):
        output_error_fit(unstable, u, u)


# ---- the block-row sweep of the priors (issue 34: the lean front end) -------------------


def _expected_prefix(scores: dict, patience: int, min_gain_db: float) -> list:
    """The block rows a default sweep tries, from every candidate's score: in increasing
    order, stopping after ``patience`` candidates without improvement or after one that
    improved on the best by less than ``min_gain_db``."""
    tried, best, worse = [], None, 0
    for i, s in sorted(scores.items()):
        if worse >= patience:
            break
        tried.append(i)
        if best is None or s > best:
            gain = None if best is None else s - best
            best, worse = s, 0
            if gain is not None and gain < min_gain_db:
                break
        else:
            worse += 1
    return tried


@pytest.mark.parametrize("direct", [False, True])
def test_the_default_sweep_stops_where_the_rule_says_on_the_full_sweeps_scores(direct):
    acc = accelerometer_plant(m=1, p=1)
    u, y = plant_record(acc, 1500, 40, seed=4)
    full = sweep_block_rows(u, y, 6, acc.dt, direct=direct, patience=None)[1]
    assert sorted(full.candidates) == [20, 30, 40, 60, 80]
    for min_gain in (MIN_GAIN_DB, np.inf):
        fits = {}
        model, choice = sweep_block_rows(u, y, 6, acc.dt, direct=direct, fits=fits,
                                         min_gain_db=min_gain)
        tried = _expected_prefix(full.candidates, 1, min_gain)
        assert list(choice.candidates) == tried
        assert sorted(fits) == tried           # no N4SID run beyond the stop
        np.testing.assert_allclose([choice.candidates[i] for i in tried],
                                   [full.candidates[i] for i in tried], rtol=1e-12)
        assert choice.block_rows == max(tried, key=full.candidates.get)
        assert choice.stopped
    # an infinite threshold stops after the second candidate, whatever it scored
    assert len(tried) == 2


def test_given_block_rows_are_all_tried():
    acc = accelerometer_plant(m=1, p=1)
    u, y = plant_record(acc, 1500, 40, seed=4)
    _, choice = sweep_block_rows(u, y, 6, acc.dt, [20, 30, 40], min_gain_db=np.inf)
    assert list(choice.candidates) == [20, 30, 40] and choice.stopped is None


def test_the_product_with_the_pseudo_inverse_of_r22_is_numpys_pinv(record):
    # the triangular solve of a well-conditioned R22 against numpy's SVD pseudo-inverse,
    # and a rank-deficient factor (noise-free data: one row of exact zeros), where only the
    # pseudo-inverse is defined, must take that route
    from trussid.plid.subspace import _times_pinv

    _, u, y = record
    R22, R32, _, _ = po_moesp(u, y, 10)
    ref = R32 @ np.linalg.pinv(R22)
    np.testing.assert_allclose(_times_pinv(R32, R22), ref, rtol=0, atol=1e-10 * np.abs(ref).max())
    singular = R22.copy()
    singular[3:, 3] = 0.0
    singular[3, :4] = 0.0
    ref = R32 @ np.linalg.pinv(singular)
    assert np.all(np.isfinite(ref))
    np.testing.assert_array_equal(_times_pinv(R32, singular), ref)
