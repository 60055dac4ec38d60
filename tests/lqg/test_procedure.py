"""The default design procedure (issue 32): the LQR damping iteration stops with a reason,
the procedure backs off to the best design stable and robust on the model and says what
limited each target, and refuses only when no design is stable with the margin.

The two failures issue 32 names are reproduced here first (at commit 2b468f8):

- the stalled iteration: two modes 1 % apart driven through one actuator along the same
  direction. Only one combination of them is controllable; the old iteration ran its 200
  iterations silently and returned 22.14 % for one mode and 0.58 % for the other against
  the 7 % asked;
- the redesign that raised from inside the library: on the testbed with the UDF mass
  -10 % (the 224.9 Hz mode merged with the strut cluster), targeting 150-260 Hz raised
  ``LinAlgError: The associated symplectic pencil has eigenvalues too close to the unit
  circle`` from the Riccati solver (adapt-feasibility: ``ControlArgument: Q must be a
  symmetric matrix`` when the weights had turned NaN), not a ControlError.
"""

import control
import numpy as np
import pytest
from scipy.linalg import block_diag

from trussid.lqg import ControlError
from trussid.lqg.design import WEIGHT_RANGE, lqr_for_damping, real_modal_basis
from trussid.lqg.evaluate import damping_table, disk_margins
from trussid.lqg.procedure import LIMITS, design_procedure

FS = 1000.0


def close_pair(b2=1.0, f=(100.0, 101.0), zeta=0.005):
    """Two modes ``f`` [Hz] driven by one force input (the second through ``b2``), in
    real modal coordinates: ``(A, B, blocks, open-loop damping)``."""
    parts = []
    for fi in f:
        w = 2 * np.pi * fi
        parts.append(np.array([[0.0, 1.0], [-w * w, -2 * zeta * w]]))
    d = control.c2d(control.ss(block_diag(*parts), [[0.0], [1.0], [0.0], [b2]],
                               [[0.0, 1.0, 0.0, 1.0]], 0.0), 1 / FS)
    T, _ = real_modal_basis(d.A)
    Ti = np.linalg.inv(T)
    A, B = Ti @ np.asarray(d.A) @ T, Ti @ np.asarray(d.B)
    return A, B, [np.array([0, 1]), np.array([2, 3])]


def test_the_iteration_on_close_modes_through_one_actuator_stops_and_says_which_is_short():
    A, B, blocks = close_pair()
    t = lqr_for_damping(A, B, blocks, 0.07, 1 / FS)
    assert t.reason == "no progress" and t.iterations < 50  # was 200 iterations, silent
    # one combination of the pair is damped far past the target, the other cannot be:
    # it stays near the open-loop 0.5 % (ZOH-sampled), and it is the one flagged short
    assert t.damping.max() > 0.2 and t.damping.min() < 0.01
    assert list(t.short) == list(t.damping < 0.07 * 0.98)
    assert np.all(np.isfinite(t.F))


def test_a_mode_the_actuator_does_not_reach_stops_at_the_weight_limit_with_finite_weights():
    A, B, blocks = close_pair(b2=0.0, f=(100.0, 160.0))
    t = lqr_for_damping(A, B, blocks, 0.07, 1 / FS)
    assert t.reason in ("weight limit", "no progress")
    q0 = 1e-3 / np.linalg.norm(B, 2) ** 2
    assert np.all(np.isfinite(t.weights)) and t.weights.max() <= WEIGHT_RANGE * q0 * (1 + 1e-12)
    assert t.short[1] and not t.short[0]
    assert abs(t.damping[0] / 0.07 - 1) < 0.02


def accel_plant(freqs=(30.0, 55.0, 90.0, 140.0), zeta=0.01, fs=500.0):
    """Two force inputs, three accelerometers (a feed-through), modal, ZOH at ``fs``."""
    n = len(freqs)
    w = 2 * np.pi * np.asarray(freqs)
    phi_in = np.array([[1.0, 0.4], [0.6, -0.8], [-0.5, 0.7], [0.8, 0.5]])[:n]
    phi_out = np.array([[1.0, 0.5, 0.3], [0.5, -0.7, 0.4], [-0.4, 0.6, 0.9],
                        [0.7, 0.4, -0.6]])[:n]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(w**2), -np.diag(2 * zeta * w)]])
    sys_c = control.ss(A, np.vstack([np.zeros((n, 2)), phi_in]), phi_out.T @ A[n:],
                       phi_out.T @ phi_in)
    d = control.c2d(sys_c, 1 / fs, "zoh")
    return control.ss(d.A, d.B, d.C, d.D, 1 / fs, inputs=["f1", "f2"],
                      outputs=["a1", "a2", "a3"])


def record(plant, n=4000, seed=3):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, plant.ninputs))
    y = control.forced_response(plant, U=u.T).outputs.T
    return u, y + 0.01 * y.std(axis=0) * rng.normal(size=y.shape)


def test_the_default_procedure_is_stable_with_its_margin_on_the_model_and_strictly_proper():
    plant = accel_plant()
    proc = design_procedure(plant, *record(plant))
    c = proc.design.controller
    assert not np.any(np.asarray(c.D))  # the plant has a feed-through: no algebraic loop
    # graded again here, independently of the procedure's own bookkeeping
    tab = damping_table(plant, c, band=(0.0, 250.0))
    assert tab.stable
    assert disk_margins(plant, c).mimo.gain_db >= 6.0
    assert proc.band_hz == (0.0, 125.0)  # a quarter of the 500 Hz sample rate
    assert [round(o.frequency_hz) for o in proc.outcomes] == [90, 55, 30]  # by residue
    for o in proc.outcomes:
        assert o.limited_by in LIMITS
        row = min(tab.rows, key=lambda r: abs(r.frequency_hz - o.frequency_hz))
        assert row.damping_worst_visible == pytest.approx(o.on_model, rel=1e-6)


def test_asking_too_much_backs_off_and_says_what_limited_each_mode():
    plant = accel_plant()
    proc = design_procedure(plant, *record(plant), target_damping=0.6)
    assert proc.short and proc.design.info["target_damping"] < 0.6
    assert proc.disk_gain_db >= 6.0
    assert len(proc.attempts) > 1 and not proc.attempts[0].passed
    text = proc.warning()
    assert "less than the 60.0 % asked" in text and "disk margin" in text
    for o in proc.outcomes:
        assert o.limited_by != "reached" and o.limited_by in LIMITS and o.detail


@pytest.mark.slow
def test_the_cluster_redesign_that_raised_from_the_riccati_solver_now_designs_or_says_why():
    """The testbed with the UDF mass -10 %: its 224.9 Hz mode sits 1-4 % from three strut
    modes. The targets of 150-260 Hz made the old iteration raise from the library."""
    from trussid.campaign.control import perturbed_testbed
    from trussid.geometry.spec import Testbed
    from trussid.plid.experiment import excitation, simulate
    from trussid.testbed.plant import testbed_plant

    truth = testbed_plant(perturbed_testbed(Testbed(), {"udf__mass": ("x", 0.90)})).discrete
    u = excitation("white", 6000, truth.ninputs, 1 / truth.dt, 2.5, (0.0, 400.0), 5)
    y = simulate(truth, u)
    y = y + 1e-3 * y.std(axis=0) * np.random.default_rng(1).standard_normal(y.shape)
    try:
        proc = design_procedure(truth, u, y, band=(150.0, 260.0))
    except ControlError as exc:  # a refusal is a sentence, not a library exception
        assert "no design is stable" in str(exc)
        return
    c = proc.design.controller
    assert damping_table(truth, c, band=(0.0, 800.0)).stable
    assert disk_margins(truth, c).mimo.gain_db >= 6.0
    for o in proc.outcomes:
        assert o.limited_by in LIMITS


def test_a_mode_short_for_lack_of_authority_does_not_drive_the_design_above_the_asked():
    """The newcomer audit's truss (issue 32): a close pair (46.9 / 48.3 Hz) that both
    actuators drive along one direction, so only one combination of it is controllable.
    The state feedback stops short on one mode; aiming higher for it used to tune the
    design to three times the asked damping ("chosen: 21.0 %" beside "asked 7.0 %") and
    overdrive the other mode. Now the design stays at the asked damping and the short mode
    is said to lack actuator authority."""
    fs, f, zeta = 1000.0, np.array([46.9, 48.3]), 0.01
    w = 2 * np.pi * f
    phi_in = np.array([[1.0, 0.001], [1.0, 0.001]])  # the PZT a thousand times weaker
    phi_out = np.array([[1.0, 0.5, 0.3], [0.5, -0.7, 0.4]])
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.diag(w**2), -np.diag(2 * zeta * w)]])
    d = control.c2d(control.ss(A, np.vstack([np.zeros((2, 2)), phi_in]), phi_out.T @ A[2:],
                               phi_out.T @ phi_in), 1 / fs, "zoh")
    plant = control.ss(d.A, d.B, d.C, d.D, 1 / fs, inputs=["shaker", "pzt"],
                       outputs=["a1", "a2", "a3"])
    proc = design_procedure(plant, *record(plant))
    assert proc.design.info["target_damping"] <= 0.07 + 1e-12
    assert "above the asked damping" not in proc.choice_line()
    limits = sorted(o.limited_by for o in proc.outcomes)
    assert limits == ["actuator authority", "reached"], proc.lines()
    reached = max(o.on_model for o in proc.outcomes)
    assert 0.95 * 0.07 <= reached < 0.15  # at the asked damping, not overdriven
    tab = damping_table(plant, proc.design.controller, band=(0.0, 500.0))
    assert tab.stable and disk_margins(plant, proc.design.controller).mimo.gain_db >= 6.0
