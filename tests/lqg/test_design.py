"""LQG design: the gains do what the recipe says, on a model whose answer is known."""

import control
import numpy as np
import pytest

from trussid.lqg import ControlError, closed_loop, design_lqg, modal_truncation, select_modes
from trussid.lqg.design import controller_matrices
from trussid.lqg.modal import freq_damping
from trussid.lqg.shaping import InputWeight

from .conftest import modal_structure


def _sorted(z):
    return np.sort_complex(np.round(np.asarray(z), 10))


def test_dominant_modes_are_those_with_a_quarter_of_the_largest_residue(structure):
    sel, rows = select_modes(structure)
    f = sorted(rows[b].frequency_hz for b in sel)
    # the 120 Hz mode has a tenth of the input gain: its residue is 1 % of the others'
    assert np.allclose(f, [166.0, 194.0, 220.0], rtol=1e-3)
    sel, rows = select_modes(structure, band=(100, 170))
    assert np.allclose(sorted(rows[b].frequency_hz for b in sel), [120.0, 166.0], rtol=1e-3)


def test_modal_truncation_keeps_the_pole_and_the_resonance_of_the_kept_mode():
    both = modal_structure(freqs=(166.0, 600.0))
    red, kept = modal_truncation(both, [0])
    w = 2 * np.pi * 166.0
    s = -0.0025 * w + 1j * w * np.sqrt(1 - 0.0025**2)
    assert np.allclose(np.sort_complex(np.linalg.eigvals(red.A)),
                       np.sort_complex(np.exp(np.array([s.conjugate(), s]) / 1600)), atol=1e-12)
    assert kept[0][1] == pytest.approx(np.exp(s / 1600), abs=1e-12)
    # at its resonance the truncated model is the two-mode plant (the 600 Hz mode adds < 5 %)
    z = np.exp(2j * np.pi * 166.0 / 1600)
    H_red, H = np.asarray(red(z)), np.asarray(both(z))
    assert np.linalg.norm(H_red - H) < 0.05 * np.linalg.norm(H)


@pytest.mark.parametrize("target", [0.03, 0.07, 0.2])
def test_state_feedback_gives_each_target_mode_the_target_damping(structure, record, target):
    des = design_lqg(structure, *record, target_damping=target)
    A, B = np.asarray(des.design_model.A), np.asarray(des.design_model.B)
    f, z = freq_damping(np.linalg.eigvals(A - B @ des.F), structure.dt)
    up = np.argsort(f)[1::2]  # one of each conjugate pair
    assert np.allclose(z[up], target, rtol=0.03)
    assert [t.frequency_hz for t in des.target_modes] == pytest.approx([166, 194, 220], rel=1e-3)


@pytest.mark.parametrize("form", ["predictor", "filter"])
def test_separation_closed_loop_on_the_design_model_has_lqr_and_estimator_poles(
        structure, record, form):
    """On the design model itself, the loop's poles are eig(A - BF) and eig(A - KC): an
    independent check of the controller's matrices and of the loop interconnection."""
    des = design_lqg(structure, *record, form=form)
    dm = des.design_model
    A, B, C = (np.asarray(M) for M in (dm.A, dm.B, dm.C))
    expect = np.concatenate([np.linalg.eigvals(A - B @ des.F), np.linalg.eigvals(A - des.K @ C)])
    got = np.linalg.eigvals(np.asarray(closed_loop(dm, des.controller).A))
    assert np.allclose(_sorted(got), _sorted(expect), atol=1e-8)
    # python-control's positive feedback agrees with the hand-built loop
    fb = control.feedback(dm, des.controller, sign=+1)
    assert np.allclose(_sorted(np.linalg.eigvals(fb.A)), _sorted(expect), atol=1e-8)


def test_predictor_form_waits_one_sample_and_filter_form_does_not(structure, record):
    p = design_lqg(structure, *record, form="predictor").controller
    f = design_lqg(structure, *record, form="filter").controller
    assert np.all(np.asarray(p.D) == 0)
    assert np.any(np.asarray(f.D) != 0)
    assert list(p.input_labels) == ["acc1", "acc2", "acc3"]
    assert list(p.output_labels) == ["ch1", "ch2", "ch3"]


def test_filter_form_from_predictor_gain_is_the_kalman_update():
    """u = -F xhat[k|k]: with L = A^-1 K the filter form's command equals -F (x + L e)."""
    rng = np.random.default_rng(5)
    A = np.diag([0.5, -0.3]) + 0.1 * rng.normal(size=(2, 2))
    B, C = rng.normal(size=(2, 1)), rng.normal(size=(1, 2))
    F, K = rng.normal(size=(1, 2)), rng.normal(size=(2, 1))
    Ac, Bc, Cc, Dc = controller_matrices(A, B, C, F, K, "filter")
    x, y = rng.normal(size=2), rng.normal(size=1)
    L = np.linalg.solve(A, K)
    xf = x + L @ (y - C @ x)
    assert np.allclose(Cc @ x + Dc @ y, -F @ xf)
    assert np.allclose(Ac @ x + Bc @ y, A @ xf + B @ (-F @ xf))


@pytest.mark.parametrize("kwargs, match", [
    ({"target_damping": 0.0}, "target damping"),
    ({"target_damping": 1.0}, "target damping"),
    ({"band": (300.0, 400.0)}, "band 300-400 Hz holds no"),
    ({"form": "smith"}, "form"),
    ({"estimator": "model"}, "no predictor gain K"),
])
def test_bad_design_requests_name_the_item(structure, record, kwargs, match):
    with pytest.raises(ControlError, match=match):
        design_lqg(structure, *record, **kwargs)


def test_unstable_or_continuous_models_are_refused(structure, record):
    bad = control.ss(1.01 * np.asarray(structure.A), structure.B, structure.C, structure.D,
                     structure.dt)
    with pytest.raises(ControlError, match="unstable"):
        design_lqg(bad, *record)
    cont = control.ss(-np.eye(2), np.ones((2, 3)), np.ones((3, 2)), np.zeros((3, 3)))
    with pytest.raises(ControlError, match="continuous"):
        design_lqg(cont, *record)
    with pytest.raises(ControlError, match="record has 2 inputs"):
        design_lqg(structure, record[0][:, :2], record[1])


def test_the_models_own_predictor_gain_can_be_the_estimator(structure, record):
    """``estimator="model"``: the identified model's K, projected on the target modes, is
    the design's predictor gain (here the Kalman gain of the full structure)."""
    from trussid.plid.metrics import predictor_gain

    n = structure.nstates
    B = np.asarray(structure.B)
    K = predictor_gain(structure, B @ B.T + 1e-9 * np.eye(n), 1e-2 * np.eye(3))
    des = design_lqg(structure, *record, estimator="model", K=K)
    assert des.K.shape == (des.design_model.nstates, 3)
    assert "model's K" in des.info["estimator_choice"]["chosen"]
    tab_rho = np.max(np.abs(np.linalg.eigvals(np.asarray(closed_loop(structure, des.controller).A))))
    assert tab_rho < 1


def _controller_response(ctrl, f_hz):
    z = np.exp(2j * np.pi * np.asarray(f_hz) * ctrl.dt)
    return np.stack([np.asarray(ctrl(zi)) for zi in z])


def test_input_weight_of_gain_one_leaves_the_controller_unchanged(structure, record):
    """W = 1 (zeros on the poles): the cost is u' R u again, so the controller's response
    is the unweighted design's (the weight's states unobservable from its output)."""
    plain = design_lqg(structure, *record, target_damping=0.05)
    unit = design_lqg(structure, *record, target_damping=0.05,
                      input_weight=InputWeight(((300.0, 10.0, 1.0),), structure.dt))
    f = np.linspace(10, 790, 157)
    assert unit.controller.nstates == plain.controller.nstates + 6
    assert np.allclose(_controller_response(unit.controller, f),
                       _controller_response(plain.controller, f), rtol=1e-6, atol=1e-9)


def test_input_weight_cuts_the_controller_gain_where_it_is_large_and_keeps_the_targets(
        structure, record):
    """Frequency-shaped cost (Gupta 1980): a x10 weight on the control at 300 Hz, away from
    the 166-220 Hz targets, lowers the controller's gain there; the state feedback still
    gives each target the damping asked, the controller stays strictly proper and the loop
    on the plant is stable with the targets damped."""
    plain = design_lqg(structure, *record, target_damping=0.05)
    w = InputWeight(((300.0, 15.0, 10.0),), structure.dt)
    shaped = design_lqg(structure, *record, target_damping=0.05, input_weight=w)
    g = lambda d, f: np.linalg.norm(_controller_response(d.controller, [f])[0], 2)  # noqa: E731
    assert g(shaped, 300.0) < 0.3 * g(plain, 300.0)
    assert g(shaped, 194.0) > 0.7 * g(plain, 194.0)
    assert [t.state_feedback_damping for t in shaped.target_modes] == pytest.approx(
        [0.05] * 3, rel=0.03)
    assert not np.any(np.asarray(shaped.controller.D))
    loop = closed_loop(structure, shaped.controller)
    lam = np.linalg.eigvals(np.asarray(loop.A))
    assert np.max(np.abs(lam)) < 1
    f, z = freq_damping(lam, structure.dt)
    for f0 in (166.0, 194.0, 220.0):
        near = np.abs(f - f0) < 0.03 * f0
        assert z[near].min() > 0.03  # well above the 0.25 % open loop
    with pytest.raises(ControlError, match="predictor form"):
        design_lqg(structure, *record, form="filter", input_weight=w)


def test_per_mode_target_and_estimator_damping_are_reached(structure, record):
    """One damping per target mode for the state feedback; the estimator tuned as the dual
    to its own damping: eig(A - B F) and eig(A - K C) of the design model show both."""
    asked = np.array([0.03, 0.05, 0.08])
    des = design_lqg(structure, *record, target_damping=asked, estimator_damping=0.04,
                     verify=False)
    dm = des.design_model
    A, B, C = (np.asarray(M) for M in (dm.A, dm.B, dm.C))
    for M, expect in ((A - B @ des.F, asked), (A - des.K @ C, np.full(3, 0.04))):
        f, z = freq_damping(np.linalg.eigvals(M), structure.dt)
        up = np.argsort(f)[1::2]
        assert np.allclose(z[up], expect, rtol=0.03)


def test_a_weight_pole_does_not_pass_for_a_target_mode(structure, record):
    """The loop of a frequency-shaped design also has the weight's poles: narrow peaks
    between the targets and a strong one near Nyquist, where the plant's coordinates move
    too (assigned by eigenvector share alone, a 194 Hz target got a weight pole at 65 %
    and the tuning stalled). The damping the tuning reports per target is that of the
    closed-loop pole next to the target (eig of the augmented loop, picked by frequency
    here), and the tuning reaches the target."""
    from trussid.lqg.shaping import augment

    w = InputWeight(((180.0, 3.0, 2.0), (207.0, 3.0, 2.0), (700.0, 60.0, 10.0)), structure.dt)
    des = design_lqg(structure, *record, target_damping=0.05, input_weight=w, verify=False)
    dm = des.design_model
    R = np.diag(1.0 / np.asarray(des.info["input_rms"]) ** 2)
    Aa, Ba, *_ = augment(np.asarray(dm.A), np.asarray(dm.B), R, w)
    f, z = freq_damping(np.linalg.eigvals(Aa - Ba @ des.F), structure.dt)
    for t in des.target_modes:
        near = np.abs(f - t.frequency_hz) < 0.05 * t.frequency_hz
        assert t.state_feedback_damping == pytest.approx(z[near].min(), rel=0.03)
        assert t.state_feedback_damping == pytest.approx(0.05, rel=0.03)
