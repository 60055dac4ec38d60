"""PLID on measured data: the DaISy CD-player arm (2 inputs, 2 outputs) of ../shared/realdata.

The data lives beside the repository (``../shared/realdata`` from the repository root;
``TRUSSID_REALDATA`` points elsewhere); the test is skipped only when that directory is
missing.
"""

import os
import warnings

import numpy as np
import pytest

from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.multipass import identify

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.environ.get("TRUSSID_REALDATA",
                      os.path.join(os.path.dirname(REPO), "shared", "realdata"))
CD = os.path.join(DATA, "CD_player_arm.dat")


@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir(DATA), reason=f"no measured data at {DATA}")
def test_every_order_from_1_to_40_on_the_cd_arm_gives_a_model_or_one_clear_line():
    arr = np.loadtxt(CD)
    n_id = int(round(0.6 * arr.shape[0]))         # the identification part, as the benchmark
    u = arr[:n_id, :2] - arr[:n_id, :2].mean(0)
    y = arr[:n_id, 2:4] - arr[:n_id, 2:4].mean(0)
    models, refused = {}, {}
    for order in range(1, 41):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                ident = identify(u, y, order, 1.0)
            except (IdentificationError, DataError) as exc:   # anything else fails the test
                refused[order] = str(exc)
                continue
        models[order] = ident
        assert ident.model.nstates == order
        assert ident.K is not None and ident.K.shape == (order, 2)
        assert np.all(np.isfinite(np.asarray(ident.model.A)))
        # stabilised if it had to be: no unstable model is returned
        assert np.max(np.abs(np.linalg.eigvals(ident.model.A))) < 1
    for order, msg in refused.items():
        assert msg and "\n" not in msg, (order, msg)
    assert set(models) | set(refused) == set(range(1, 41))
    for order, msg in refused.items():
        assert f"order {order}" in msg, msg
    # every multiple of the outputs is identified directly, and order 1 by reduction
    assert set(range(2, 41, 2)) | {1} <= set(models), refused
