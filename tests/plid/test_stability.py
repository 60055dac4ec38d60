"""Stabilisation by pole reflection: stable poles, |H| kept (the all-pass argument)."""

import control
import numpy as np
import pytest

from trussid.plid.errors import IdentificationError
from trussid.plid.stability import stabilise

W = np.linspace(0.01, 3.13, 80)
Z = np.exp(1j * W)


def _resp(sys):
    return np.array([np.asarray(sys(z)) for z in Z])


def test_siso_poles_are_reflected_and_magnitude_kept_exactly():
    p_bad = 1.03 * np.exp(0.3j)
    poles = [p_bad, np.conj(p_bad), 0.9 * np.exp(1j), 0.9 * np.exp(-1j), 0.5]
    H = control.ss(control.zpk([0.3, -0.5 + 0.2j, -0.5 - 0.2j], poles, 2.0, dt=0.01))
    res = stabilise(H)
    assert res.applied and res.magnitude_exact
    assert res.model.nstates == H.nstates and res.model.dt == H.dt
    new = np.sort_complex(control.poles(res.model))
    expected = np.sort_complex(np.r_[1 / np.conj(p_bad), 1 / p_bad, poles[2:]])
    assert np.allclose(new, expected, atol=1e-12)
    h, g = _resp(H).ravel(), _resp(res.model).ravel()
    assert np.max(np.abs(np.abs(g) - np.abs(h)) / np.abs(h)) < 1e-10
    # All-pass argument: G / H is the unit-modulus factor prod (z - p) / (|p| (z - 1/conj p)).
    a = np.prod([(Z - p) / (abs(p) * (Z - 1 / np.conj(p))) for p in (p_bad, np.conj(p_bad))],
                axis=0)
    assert np.allclose(np.abs(a), 1.0, atol=1e-13)
    assert np.max(np.abs(g - h * a) / np.abs(h)) < 1e-10


def test_stable_model_is_returned_unchanged_and_reported():
    H = control.ss(control.zpk([0.2], [0.5, 0.8], 1.0, dt=1))
    res = stabilise(H)
    assert not res.applied and res.model is H and res.reflected.size == 0


def test_mimo_keeps_order_stable_part_and_the_unstable_modes_own_magnitude():
    rng = np.random.default_rng(4)
    p_bad = 1.01 * np.exp(0.6j)

    def rot(r, t):
        return r * np.array([[np.cos(t), np.sin(t)], [-np.sin(t), np.cos(t)]])

    A = np.zeros((6, 6))
    A[:2, :2] = rot(abs(p_bad), np.angle(p_bad))
    A[2:4, 2:4] = rot(0.9, 1.5)
    A[4:, 4:] = rot(0.7, 2.5)
    B, C = rng.standard_normal((6, 2)), rng.standard_normal((3, 6))
    H = control.ss(A, B, C, np.zeros((3, 2)), 1)
    res = stabilise(H)
    assert res.applied and not res.magnitude_exact
    assert res.model.nstates == 6
    assert np.max(np.abs(control.poles(res.model))) < 1
    assert np.allclose(np.abs(res.reflected), abs(p_bad))
    # Residues (C v_k)(w_k^T B) of a model with distinct poles.
    def residue(sys, pole):
        lam, V = np.linalg.eig(np.asarray(sys.A))
        k = np.argmin(np.abs(lam - pole))
        assert abs(lam[k] - pole) < 1e-10
        return np.outer(np.asarray(sys.C) @ V[:, k], np.linalg.solve(V, np.asarray(sys.B))[k])

    # Stable modes untouched (same poles, same residues).
    for p in np.linalg.eigvals(A[2:, 2:]):
        assert np.allclose(residue(res.model, p), residue(H, p), rtol=1e-9, atol=1e-12)
    # Each reflected mode's residue is the original one over |p|, so its own term keeps
    # |R / (e^{jw} - p)| = |R / |p| / (e^{jw} - 1/conj p)| (MIMO: exact |H| would need
    # a higher McMillan degree, so the order is kept instead).
    for p in (p_bad, np.conj(p_bad)):
        assert np.allclose(residue(res.model, 1 / np.conj(p)), residue(H, p) / abs(p),
                           rtol=1e-9, atol=1e-12)


def test_continuous_model_is_refused():
    with pytest.raises(IdentificationError, match="discrete"):
        stabilise(control.ss([[1.0]], [[1.0]], [[1.0]], 0))


# ------------------------------------------------------------ checking (issue 19)

from trussid.plid.stability import UnstableModelWarning, check_stability, require_stable  # noqa: E402


def _modal(radius, f_hz=50.0, dt=1e-3):
    """One mode at ``f_hz`` with pole radius ``radius`` (discrete, 1 input, 1 output)."""
    th = 2 * np.pi * f_hz * dt
    A = radius * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    return control.ss(A, [[1.0], [0.0]], [[0.0, 1.0]], [[0.0]], dt)


def test_check_stability_names_the_unstable_pole_radius_and_frequency():
    st = check_stability(_modal(1.02))
    assert not st.stable and st.unstable.size == 2 and st.max_radius == pytest.approx(1.02)
    msg = st.message("model m.npz")
    # one line; the pair is reported once, at its frequency (eigenvalue angle / (2 pi dt))
    assert msg.startswith("model m.npz is unstable: 2 pole(s) outside the unit circle")
    assert "|z| = 1.02 at 50 Hz" in msg and "\n" not in msg


def test_stable_marginal_and_continuous_models_are_told_apart():
    assert check_stability(_modal(0.99)).stable
    assert check_stability(_modal(0.99)).message() is None
    marginal = check_stability(_modal(1.0))
    assert not marginal.stable and marginal.unstable.size == 0 and marginal.marginal.size == 2
    assert "marginally stable" in marginal.message()
    # continuous: a right-half-plane pole at s = +3 1/s
    sc = control.ss([[3.0, 0], [0, -1.0]], [[1.0], [1.0]], [[1.0, 1.0]], [[0.0]])
    st = check_stability(sc)
    assert st.unstable.size == 1 and "right half-plane" in st.message()
    assert "Re s = 3 1/s" in st.message()


def test_require_stable_refuses_an_unstable_model_with_the_purpose():
    require_stable(_modal(0.5))  # no error
    with pytest.raises(IdentificationError, match="the plant is unstable.*a simulation of it "
                                                  "diverges"):
        require_stable(_modal(1.5), "the plant", "a simulation of it diverges")


def test_model_files_report_stability_on_load_and_warn_on_save(tmp_path):
    from trussid.plid.modelfile import load_model, save_model

    with pytest.warns(UnstableModelWarning, match="is unstable"):
        save_model(tmp_path / "bad.npz", _modal(1.05))
    _, meta = load_model(tmp_path / "bad.npz")
    assert not meta.stability.stable and meta.stability.unstable.size == 2
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a stable model is written without a word
        save_model(tmp_path / "good.npz", _modal(0.9))
    assert load_model(tmp_path / "good.npz")[1].stability.stable


def test_run_experiment_refuses_an_unstable_plant():
    from trussid.plid.experiment import run_experiment

    with pytest.raises(IdentificationError, match="unstable"):
        run_experiment(_modal(1.5), 100, seed=1)
