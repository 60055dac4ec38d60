"""The N4SID prior (PO-MOESP, Verhaegen and Verdult 2007, p. 329) against nfoursid, the
package whose algorithm it writes out, and against the true system."""

import control
import numpy as np
import pandas as pd
import pytest
from nfoursid.nfoursid import NFourSID
from nfoursid.utils import Utils

from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.subspace import block_hankel, n4sid, po_moesp


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
