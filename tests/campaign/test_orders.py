"""A model's order chosen from its record (issue 32): held-back one-step prediction."""

import control
import numpy as np

from trussid.campaign.orders import scan_orders


def modal_record(freqs=(40.0, 95.0, 160.0), fs=1000.0, n=4000, noise=1e-3, seed=0):
    """A 2-input, 2-output structure with ``len(freqs)`` modes (2 states each), a white
    record and white sensor noise ``noise`` of the output RMS."""
    w = 2 * np.pi * np.asarray(freqs)
    k = len(freqs)
    A = np.block([[np.zeros((k, k)), np.eye(k)], [-np.diag(w**2), -np.diag(0.02 * w)]])
    rng = np.random.default_rng(seed)
    B = np.vstack([np.zeros((k, 2)), rng.normal(size=(k, 2))])
    C = np.hstack([rng.normal(size=(2, k)) * w**2, np.zeros((2, k))])
    sys = control.c2d(control.ss(A, B, C, 0), 1 / fs)
    u = rng.normal(size=(n, 2))
    y = control.forced_response(sys, U=u.T).outputs.T
    return u, y + noise * y.std(axis=0) * rng.normal(size=y.shape), 1 / fs


def test_the_true_order_of_a_three_mode_structure_is_chosen_and_the_scan_reported():
    u, y, dt = modal_record()
    choice = scan_orders(u, y, dt, range(2, 15, 2), direct=False, block_rows=20)
    assert choice.chosen == 6  # three modes, two states each
    rows = {r.order: r for r in choice.rows}
    assert rows[4].held_back_db < rows[6].held_back_db - 10  # a mode short: far worse
    assert choice.chosen not in choice.runners_up and len(choice.runners_up) == 3
    assert any("<- chosen" in line for line in choice.lines())


def test_the_scan_stops_at_its_cpu_budget_and_says_which_orders_it_left_out():
    u, y, dt = modal_record()
    choice = scan_orders(u, y, dt, range(2, 15, 2), direct=False, block_rows=20,
                         cpu_budget_s=0.0)
    assert [r.order for r in choice.rows] == [2]
    assert choice.not_scanned == tuple(range(4, 15, 2))
    assert choice.chosen == 2


def test_a_scan_whose_best_order_is_its_largest_says_the_range_limits_the_model():
    u, y, dt = modal_record()
    short = scan_orders(u, y, dt, range(2, 5, 2), direct=False, block_rows=20)
    assert short.best_at_top()  # 2 and 4 states for three modes: 4 is best, and the top
    assert any("wider range may predict better" in line for line in short.lines())
    full = scan_orders(u, y, dt, range(2, 11, 2), direct=False, block_rows=20)
    assert not full.best_at_top()
    assert not any("wider range" in line for line in full.lines())
