"""The recipe's winner made ready for a report (:mod:`trussid.plid.chosen`)."""

import control
import numpy as np

import trussid.plid.chosen as chosen
from trussid.plid.multipass import Identification, PassRecord, Provenance, Stabilised


class _Result:
    """The PLID pass the winner came from: its history is long enough to keep."""

    theta_history = np.zeros((3, 2))
    history_index = np.arange(3)
    innovations = np.zeros((10, 1))
    form = "direct"
    finite = True
    theta_cov = None


def _identification(model):
    _Result.model = model
    prov = Provenance(chosen="via 4, reduced", stabilised=Stabilised(),
                      predictor={"chosen": "kalman Q/R ratio 1"},
                      passes=[PassRecord(0, "direct", 0.0)])
    return Identification(_Result, model, np.zeros((model.nstates, 1)), "subspace", None,
                          np.ones(1), None, prov)


def test_an_unstable_winner_is_reflected_in_and_its_predictor_chosen_afresh(monkeypatch):
    dt = 1 / 1600
    # poles at 1.25 (unstable) and 0.5: reflected in, 1.25 becomes 1 / 1.25 = 0.8
    unstable = control.ss(np.diag([1.25, 0.5]), [[1.0], [1.0]], [[1.0, 1.0]], 0, dt)
    monkeypatch.setattr(chosen, "fit_model", lambda *a, **k: _identification(unstable))
    rng = np.random.default_rng(3)
    u = rng.standard_normal((400, 1))
    y = rng.standard_normal((400, 1))
    ch = chosen.choose_model(u, y, 2, dt)
    poles = np.sort(np.abs(np.linalg.eigvals(np.asarray(ch.model.A))))
    np.testing.assert_allclose(poles, [0.5, 0.8], rtol=1e-9)
    assert ch.stabilised == Stabilised(applied=True, reflected_poles=1)
    assert ch.K_source != "" and ch.predictor["chosen"] == ch.K_source
    assert ch.theta_history.shape == (3, 2)     # the pass's own history is kept


def test_a_stable_winner_keeps_the_recipe_s_gain_and_record(monkeypatch):
    dt = 1 / 1600
    stable = control.ss(np.diag([0.9, 0.5]), [[1.0], [1.0]], [[1.0, 1.0]], 0, dt)
    idn = _identification(stable)
    monkeypatch.setattr(chosen, "fit_model", lambda *a, **k: idn)
    rng = np.random.default_rng(4)
    ch = chosen.choose_model(rng.standard_normal((300, 1)), rng.standard_normal((300, 1)), 2,
                             dt)
    assert ch.model is stable and ch.K is idn.K
    assert ch.K_source == "kalman Q/R ratio 1" and ch.stabilised == Stabilised()
    assert ch.chosen == "via 4, reduced"
