"""The stabilisation diagram on a simulated structure with known modes."""

import control
import numpy as np
import pytest
import scipy.linalg

from trussid.plid.data import ModeShapes
from trussid.plid.errors import IdentificationError
from trussid.plid.stabilisation_diagram import mark_stability, stabilisation
from trussid.plid.subspace import n4sid


def structure(fs=400.0):
    """Three lightly damped modes (23, 61, 118 Hz), 2 inputs, 2 outputs, discrete."""
    f = np.array([23.0, 61.0, 118.0])
    z = np.array([0.01, 0.015, 0.02])
    blocks, Bs, Cs = [], [], []
    rng = np.random.default_rng(5)
    for fk, zk in zip(f, z):
        w = 2 * np.pi * fk
        blocks.append(np.array([[0, 1], [-w * w, -2 * zk * w]]))
        Bs.append(np.vstack([np.zeros(2), rng.standard_normal(2) * w]))
        Cs.append(np.column_stack([rng.standard_normal(2) * w, np.zeros(2)]))
    sysc = control.ss(scipy.linalg.block_diag(*blocks), np.vstack(Bs), np.hstack(Cs),
                      np.zeros((2, 2)))
    return control.c2d(sysc, 1 / fs), f, z


def _n4sid(u, y, n, dt):
    return n4sid(u, y, n, 20, dt).zero_d


def test_stabilisation_marks_the_true_modes_stable_and_refuses_nothing_silently(rng):
    sys, f_true, z_true = structure()
    u = rng.standard_normal((3000, 2))
    y = control.forced_response(sys, U=u.T).outputs.T
    y = y + 1e-4 * np.std(y) * rng.standard_normal(y.shape)

    def identify(u_, y_, n, dt):
        if n % 2:
            raise IdentificationError(f"order {n} is not a multiple of the 2 outputs")
        return _n4sid(u_, y_, n, dt)

    stab = stabilisation(u, y, sys.dt, [6, 7, 8, 10, 12], identify=identify, progress=False,
                         output_names=["a1", "a2"], input_names=["f1", "f2"])
    assert stab.orders == [6, 8, 10, 12]
    assert stab.failed == [(7, "order 7 is not a multiple of the 2 outputs")]
    assert np.all(stab.status[0] == "new")  # nothing below the first order to compare with
    # at order 12 a noise pole near 146 Hz matches its neighbour at 10 once: stable for one
    # step only, where the three true modes have been stable over all 3 steps (6 to 12)
    assert stab.stable_poles().n_modes == 4
    assert list(stab.runs[-1][stab.status[-1] == "s"]) == [3, 3, 3, 1]
    stable = stab.stable_poles(min_run=2)
    assert stable.n_modes == 3
    np.testing.assert_allclose(stable.frequencies_hz, f_true, rtol=1e-3)
    np.testing.assert_allclose(stable.damping, z_true, rtol=5e-2)
    assert stable.labels == ["a1", "a2"]


def test_a_pole_that_moves_is_not_stable():
    prev = ModeShapes(np.array([10.0, 50.0]), np.array([0.01, 0.02]), np.eye(2))
    cur = ModeShapes(np.array([10.05, 52.0]), np.array([0.0102, 0.02]),
                     np.array([[1.0, 0.0], [0.1, 1.0]]))
    # 10 Hz: 0.5 % in f, 2 % in damping, MAC 0.990: stable; 50 -> 52 Hz is 4 %: new
    assert list(mark_stability(prev, cur, 0.01, 0.05, 0.98)) == ["s", "new"]
    assert list(mark_stability(prev, cur, 0.01, 0.01, 0.98)) == ["fv", "new"]
    assert list(mark_stability(prev, cur, 0.01, 0.05, 0.995)) == ["fd", "new"]


def test_stabilisation_with_no_model_at_all_says_why(rng):
    def never(u, y, n, dt):
        raise IdentificationError("always fails")

    with pytest.raises(IdentificationError, match="no order gave a model: order 2: always"):
        stabilisation(np.ones((10, 1)), np.ones((10, 1)), 1.0, [2], identify=never,
                      progress=False)


def test_a_plid_diagram_carries_each_poles_interval_from_its_identification(rng):
    # Issue 34: the intervals in the stabilisation diagram. With a PLID identify each pole
    # of each order carries the first-order standard deviations of its identification
    # (plid.uncertainty.mode_intervals; their coverage is measured by
    # benchmarks/bench_uncertainty.py), matched to the diagram's modes by frequency.
    from trussid.plid.recipe import identify
    from trussid.plid.uncertainty import mode_intervals

    sys, f_true, _ = structure()
    u = rng.standard_normal((3000, 2))
    y = control.forced_response(sys, U=u.T).outputs.T
    y = y + 1e-2 * np.std(y) * rng.standard_normal(y.shape)

    def ident(u_, y_, n, dt):
        return identify(u_, y_, n, dt, form="sqrt", progress=False)

    stab = stabilisation(u, y, sys.dt, [6, 8], progress=False, identify=ident)
    assert len(stab.frequency_std) == len(stab.damping_std) == len(stab.orders) == 2
    f, s = stab.modes[0].frequencies_hz, stab.frequency_std[0]
    np.testing.assert_allclose(f, f_true, rtol=1e-4)            # order 6: the three modes
    ivs = mode_intervals(stab.models[0], *(lambda i: (i.result.model, i.result.theta_cov))(
        ident(u, y, 6, sys.dt)))
    np.testing.assert_allclose(s, [iv.frequency_std_hz for iv in ivs], rtol=1e-12)
    np.testing.assert_allclose(stab.damping_std[0], [iv.damping_ratio_std for iv in ivs],
                               rtol=1e-12)
    assert np.all(s > 0) and np.all(s < 1e-3 * f)
    assert all(x.size == m.n_modes for x, m in zip(stab.frequency_std, stab.modes))


def test_a_bare_model_identify_gives_no_intervals(rng):
    sys, _, _ = structure()
    u = rng.standard_normal((2000, 2))
    y = control.forced_response(sys, U=u.T).outputs.T
    stab = stabilisation(u, y, sys.dt, [6], identify=_n4sid, progress=False)
    assert np.all(np.isnan(stab.frequency_std[0])) and stab.frequency_std[0].size == 3
