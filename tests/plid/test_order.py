"""Order-selection help (plid.order): the table points at the true order."""

import control
import numpy as np
import pytest

from trussid.plid.errors import IdentificationError
from trussid.plid.order import format_table, order_table
from trussid.plots import order_figure, save_figure

FS = 1600.0


@pytest.fixture(scope="module")
def rows():
    # 4-mode SIMO plant (8 states), 50 dB output noise
    rng = np.random.default_rng(11)
    freqs = [80.0, 170.0, 260.0, 380.0]
    n = 8
    A = np.zeros((n, n))
    for i, f in enumerate(freqs):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, w], [-w, -2 * 0.01 * w]]
    B = np.zeros((n, 1))
    B[1::2, 0] = rng.choice([-1, 1], 4) * rng.uniform(0.5, 1.5, 4) * 300
    C = rng.choice([-1, 1], (2, n)) * rng.uniform(0.5, 1.5, (2, n))
    plant = control.c2d(control.ss(A, B, C, np.zeros((2, 1))), 1 / FS)
    u = rng.standard_normal((4000, 1))
    y0 = control.forced_response(plant, U=u.T).outputs.T
    y = y0 + rng.standard_normal(y0.shape) * np.sqrt(np.mean(y0 ** 2, 0)) * 10 ** (-50 / 20)
    return order_table(u, y, [4, 6, 8, 10], 1 / FS, method="subspace", block_rows=20)


def test_prediction_rises_until_the_true_order_then_stops(rows):
    pred = {r.order: r.prediction_db for r in rows}
    assert pred[8] > max(pred[4], pred[6]) + 20          # a missing mode costs a lot
    assert abs(pred[10] - pred[8]) < 1.0                 # nothing left to gain
    assert pred[8] > 45                                  # close to the 50 dB noise floor


def test_frf_change_drops_once_the_order_is_reached(rows):
    change = {r.order: r.frf_change_db for r in rows}
    assert change[4] is None
    assert change[10] < 0.1 * min(change[6], change[8])


def test_table_and_plot(rows, tmp_path):
    text = format_table(rows)
    assert text.splitlines()[0].startswith("order")
    assert len(text.splitlines()) == 1 + len(rows)
    path = tmp_path / "orders.png"
    save_figure(order_figure(rows), path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_orders_must_suit_the_outputs():
    u = np.zeros((100, 1))
    y = np.ones((100, 2))
    with pytest.raises(IdentificationError, match="multiple"):
        order_table(u, y, [5], 1 / FS, method="subspace")


def test_no_warning_when_the_table_brackets_the_true_order(rows):
    from trussid.plid.order import order_warnings

    # the true order 8 is inside the range 4..10 and the model does not overfit: nothing to say
    assert [r.order for r in rows][-1] == 10
    assert all(np.isfinite(r.identification_db) for r in rows)
    assert order_warnings(rows) == []


def test_warns_when_the_best_order_is_the_highest_scanned(rows):
    from trussid.plid.order import order_warnings

    short = [r for r in rows if r.order <= 8]          # stop the scan at the true order
    notes = order_warnings(short)
    assert len(notes) == 1 and "top of the scanned range (order 8)" in notes[0]


def test_warns_when_validation_is_far_below_identification():
    from trussid.plid.order import OrderRow, order_warnings

    rows = [OrderRow(4, 20.0, None, 0, 0.1, None, identification_db=22.0),
            OrderRow(6, 24.0, 1.0, 0, 0.1, None, identification_db=40.0),
            OrderRow(8, 23.0, 0.5, 0, 0.1, None, identification_db=45.0)]
    notes = order_warnings(rows)
    assert len(notes) == 1
    assert "order 6" in notes[0] and "16.0 dB below" in notes[0]
