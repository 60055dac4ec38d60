"""Closed-loop evaluation checked against independent computations."""

import control
import numpy as np
import pytest
import scipy.linalg

from trussid.lqg import (ControlError, closed_loop, damping_table, decentralised, disk_margins,
                         h2_norm, simulate_loop)
from trussid.lqg.modal import freq_damping

from .conftest import modal_structure


def test_h2_norm_equals_the_impulse_response_energy_and_the_lyapunov_solution(structure):
    sys = control.ss(np.asarray(structure.A) * 0.999, structure.B, structure.C, structure.D,
                     structure.dt)  # faster decay: the impulse sum converges in 20000 samples
    A, B, C = (np.asarray(M) for M in (sys.A, sys.B, sys.C))
    X, energy = B.copy(), 0.0
    for _ in range(20000):
        energy += np.sum((C @ X) ** 2)
        X = A @ X
    assert h2_norm(sys) == pytest.approx(np.sqrt(energy), rel=1e-6)
    P = scipy.linalg.solve_discrete_lyapunov(A, B @ B.T)
    assert h2_norm(sys) == pytest.approx(np.sqrt(np.trace(C @ P @ C.T)), rel=1e-8)


def test_h2_norm_of_slow_poles_stays_positive():
    """Poles within 1e-5 of z = 1 (the testbed's suspension): the modal solution is exact
    where a dense Lyapunov solve loses the small variances."""
    lam = np.array([1 - 1e-5, 0.5])
    sys = control.ss(np.diag(lam), [[1.0], [1.0]], [[1.0, 1.0]], [[0.0]], 1.0)
    # sum_k (l1^k + l2^k)^2 = 1/(1-l1^2) + 2/(1-l1 l2) + 1/(1-l2^2)
    exact = 1 / (1 - lam[0] ** 2) + 2 / (1 - lam[0] * lam[1]) + 1 / (1 - lam[1] ** 2)
    assert h2_norm(sys) == pytest.approx(np.sqrt(exact), rel=1e-9)


def test_closed_loop_channels_match_python_control_interconnection(structure):
    c = decentralised("bandpass", 0.05, structure.dt, ["acc1", "acc2", "acc3"],
                      ["ch1", "ch2", "ch3"], (150, 250))
    cl = closed_loop(structure, c)
    assert list(cl.input_labels)[:6] == ["d_ch1", "d_ch2", "d_ch3", "n_acc1", "n_acc2", "n_acc3"]
    assert list(cl.output_labels) == ["acc1", "acc2", "acc3", "u_ch1", "u_ch2", "u_ch3"]
    # y = (I - P C)^-1 P d with positive feedback u = C y
    # Two independent references: python-control's interconnection and the transfer-matrix
    # formula evaluated frequency by frequency. At 194 Hz (a 0.25 %-damped mode) rounding is
    # amplified by the resonance: the two references themselves differ by 1.5e-8 there
    # (python-control 0.10.2), so 1e-7 is the tightest tolerance the comparison can carry.
    ref = control.feedback(structure, c, sign=+1)
    z = np.exp(2j * np.pi * np.array([100.0, 194.0, 300.0]) * structure.dt)
    for zk in z:
        P, K = np.asarray(structure(zk)), np.asarray(c(zk))
        formula = np.linalg.solve(np.eye(3) - P @ K, P)
        assert np.allclose(np.asarray(cl(zk))[:3, :3], np.asarray(ref(zk)), rtol=1e-7, atol=1e-12)
        assert np.allclose(np.asarray(cl(zk))[:3, :3], formula, rtol=1e-7, atol=1e-12)


def test_damping_table_tracks_the_poles_of_decoupled_loops():
    """Two decoupled SISO loops: the closed-loop poles are those of each 2x2 block."""
    P = modal_structure(freqs=(166.0, 220.0))
    A, B, C = (np.asarray(M) for M in (P.A, P.B, P.C))
    # make the two modes decoupled in channels 1 and 2, channel 3 idle
    B = np.zeros_like(B)
    C = np.zeros_like(C)
    B[2, 0], B[3, 1] = 1.0, 1.0
    B = np.asarray(control.c2d(control.ss(
        np.asarray(control.ss(*[np.block([[np.zeros((2, 2)), np.eye(2)],
                                          [-np.diag((2 * np.pi * np.array([166.0, 220.0])) ** 2),
                                           -np.diag(2 * 0.0025 * 2 * np.pi * np.array([166.0, 220.0]))]]),
                                np.vstack([np.zeros((2, 3)), np.eye(2, 3)]), np.zeros((3, 4)),
                                np.zeros((3, 3))]).A),
        np.vstack([np.zeros((2, 3)), np.eye(2, 3)]), np.zeros((3, 4)), np.zeros((3, 3))),
        P.dt).B)
    C[0, 2], C[1, 3] = 1.0, 1.0
    plant = control.ss(A, B, C, np.zeros((3, 3)), P.dt, inputs=["ch1", "ch2", "ch3"],
                       outputs=["acc1", "acc2", "acc3"])
    g = -300.0
    ctrl = decentralised("static", g, P.dt, ["acc1", "acc2", "acc3"], ["ch1", "ch2", "ch3"])
    tab = damping_table(plant, ctrl, band=(100, 300))
    assert tab.stable
    expect = []
    for i in range(2):
        idx = [i, i + 2]
        Ai = A[np.ix_(idx, idx)] + g * B[idx, i:i + 1] @ C[i:i + 1, idx]
        f, z = freq_damping(np.linalg.eigvals(Ai), P.dt)
        expect.append(z.min())
    got = [r.damping_tracked for r in tab.rows]
    assert got == pytest.approx(expect, rel=1e-9)
    assert all(r.damping_worst_visible == r.damping_tracked for r in tab.rows)
    assert all(r.damping_tracked > 5 * r.damping_open for r in tab.rows)


def test_a_lightly_damped_controller_pole_counts_when_visible(structure, record):
    """A controller with its own 0.5 %-damped resonance at a plant mode: the plant mode is
    damped, but the worst visible damping reports the controller's ringing pole."""
    from trussid.lqg import design_lqg

    des = design_lqg(structure, *record)
    c = des.controller
    w = 2 * np.pi * 194.0
    ring = control.c2d(control.ss(control.tf([0.02 * w, 0], [1, 2 * 0.005 * w, w**2])),
                       structure.dt, "zoh")
    bank = control.append(ring, ring, ring)
    ringing = control.parallel(c, control.ss(bank.A, bank.B, bank.C, bank.D, structure.dt))
    ringing = control.ss(ringing.A, ringing.B, ringing.C, ringing.D, structure.dt,
                         inputs=list(c.input_labels), outputs=list(c.output_labels))
    plain = damping_table(structure, c)
    tab = damping_table(structure, ringing)
    r194 = [r for r in tab.rows if abs(r.frequency_hz - 194) < 1][0]
    p194 = [r for r in plain.rows if abs(r.frequency_hz - 194) < 1][0]
    assert p194.damping_worst_visible > 0.04
    assert 0.003 < r194.damping_worst_visible < 0.012
    # the well-damped plant pole is still there: one of the two poles near 194 Hz
    f, z = freq_damping(tab.closed_loop_poles, structure.dt)
    assert np.any((np.abs(f - 194) < 15) & (z > 0.04))


def test_disk_margins_agree_with_python_control(structure, record):
    from trussid.lqg import design_lqg

    c = design_lqg(structure, *record).controller
    f = np.linspace(1.0, 799.0, 400)
    ours = disk_margins(structure, c, f)
    L = -control.series(structure, c)  # loop at the plant input, negative-feedback sign
    L = control.ss(L.A, L.B, L.C, L.D, structure.dt)
    dm, gm, pm = control.disk_margins(L, 2 * np.pi * f, skew=0.0)
    assert ours.mimo.alpha == pytest.approx(dm, rel=1e-6)
    assert ours.mimo.gain_db == pytest.approx(gm, rel=1e-6)
    assert ours.mimo.phase_deg == pytest.approx(pm, rel=1e-6)
    # loop 1 with loops 2 and 3 closed, built by python-control
    others = control.ss(c.A, c.B, np.asarray(c.C)[1:], np.asarray(c.D)[1:], structure.dt)
    Pc = control.feedback(structure, control.ss(others.A, others.B,
                                                np.vstack([np.zeros((1, c.nstates)), others.C]),
                                                np.vstack([np.zeros((1, 3)), others.D]),
                                                structure.dt), sign=+1)
    L1 = -control.series(Pc, control.ss(c.A, c.B, np.asarray(c.C)[:1], np.asarray(c.D)[:1],
                                        structure.dt))[0, 0]
    dm1, gm1, _ = control.disk_margins(control.ss(L1.A, L1.B, L1.C, L1.D, structure.dt),
                                       2 * np.pi * f, skew=0.0)
    assert ours.loops[0].alpha == pytest.approx(dm1, rel=1e-6)


def test_time_simulation_command_rms_matches_the_h2_prediction(structure, record):
    """Without converters' effect (fine quantisation, no clipping), the command RMS under
    white disturbance equals the H2 norm of the disturbance-to-command channel."""
    from trussid.lqg import design_lqg

    c = design_lqg(structure, *record).controller
    rng = np.random.default_rng(2)
    d = np.zeros((12000, 3))
    d[:, 0] = rng.normal(size=12000)
    sim = simulate_loop(structure, c, d, 0.0, bits=32, dac_full_scale=1e3, adc_full_scale=1e3)
    cl = closed_loop(structure, c)
    h = h2_norm(control.ss(cl.A, np.asarray(cl.B)[:, :1], np.asarray(cl.C)[3:4],
                           np.asarray(cl.D)[3:4, :1], structure.dt))
    assert sim.u_rms[0] == pytest.approx(h, rel=0.08)
    assert sim.dac_clipped == [0, 0, 0]


def test_mismatched_controller_and_plant_are_named(structure, record):
    from trussid.lqg import design_lqg

    c = design_lqg(structure, *record).controller
    renamed = control.ss(structure.A, structure.B, structure.C, structure.D, structure.dt,
                         inputs=["ch1", "ch2", "ch3"], outputs=["acc1", "acc2", "accX"])
    with pytest.raises(ControlError, match="controller input 'acc3' is not a plant output"):
        damping_table(renamed, c)
    small = control.ss(structure.A, np.asarray(structure.B)[:, :2], structure.C,
                       np.zeros((3, 2)), structure.dt, inputs=["ch1", "ch2"],
                       outputs=["acc1", "acc2", "acc3"])
    with pytest.raises(ControlError, match="controller output 'ch3' is not a plant input"):
        closed_loop(small, c)
    other_dt = control.ss(structure.A, structure.B, structure.C, structure.D, 1e-3,
                          inputs=["ch1", "ch2", "ch3"], outputs=["acc1", "acc2", "acc3"])
    with pytest.raises(ControlError, match="sample interval"):
        disk_margins(other_dt, c)


def test_disk_margins_equal_a_frequency_by_frequency_computation_on_numpy_2(structure, record):
    """Issue 30: disk_margins' loop-at-a-time solve over a stack of frequencies failed on
    numpy 2 (a stack of vectors as b). Against 2-D numpy at each frequency and, for the MIMO
    margin, mu from a D-scaled singular value bound (not slycot), on every loop; and with
    slycot's ab13md called directly at every frequency of the grid (no bound pruning)."""
    from slycot import ab13md

    from trussid.lqg import design_lqg

    from .conftest import reference_disk_margins

    assert int(np.__version__.split(".")[0]) >= 2
    c = design_lqg(structure, *record).controller
    # a plain grid plus +-3 Hz around each mode at 0.05 Hz (0.25 % damping: 0.8 Hz wide)
    f = np.unique(np.r_[np.linspace(1.0, 799.0, 400),
                        np.concatenate([np.arange(-3, 3.01, 0.05) + fm for fm in
                                        (120.0, 166.0, 194.0, 220.0)])])
    ours = disk_margins(structure, c, f)
    ref = reference_disk_margins(structure, c, f)
    assert [lp.alpha for lp in ours.loops] == pytest.approx(ref["loop_alpha"], rel=1e-9)
    assert ours.mimo.alpha == pytest.approx(ref["mimo_alpha"], rel=1e-7)
    assert ours.mimo.frequency_hz == ref["mimo_frequency_hz"]
    a = ours.mimo.alpha  # balanced disk: gain (1 + a/2)/(1 - a/2), phase 2 atan(a/2)
    assert ours.mimo.gain_db == pytest.approx(20 * np.log10((2 + a) / (2 - a)), rel=1e-12)
    assert ours.mimo.phase_deg == pytest.approx(np.degrees(2 * np.arctan(a / 2)), rel=1e-12)
    assert min(lp.alpha for lp in ours.loops) > a  # one loop at a time: no less margin
    # slycot directly at every frequency: the bound pruning in disk_margins loses nothing
    z = np.exp(2j * np.pi * f * structure.dt)
    H = [np.asarray(c(zk)) @ np.asarray(structure(zk)) for zk in z]  # K P
    mu = [ab13md(np.linalg.inv(np.eye(3) - KP) - 0.5 * np.eye(3), np.ones(3, int),
                 2 * np.ones(3, int))[0] for KP in H]
    assert ours.mimo.alpha == pytest.approx(1 / max(mu), rel=1e-9)
