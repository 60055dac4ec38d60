"""plid.greybox: constrained multi-start fitting, intervals, identifiability, clear errors.

Every estimate is checked against something computed another way: ordinary and
constrained linear least squares in closed form, analytic responses of a first-order
system, scipy.signal.lsim.
"""

import json

import control
import numpy as np
import pytest
import scipy.linalg
import scipy.signal
import scipy.stats

from trussid.plid.errors import DataError
from trussid.plid.greybox import Constraint, fit_greybox, fit_parameters, simulate_continuous


@pytest.fixture
def linear_problem(rng):
    A = rng.normal(size=(60, 3))
    p_true = np.array([1.5, -0.7, 2.0])
    y = A @ p_true + 0.1 * rng.standard_normal(60)
    return A, y


def vec(p):
    return np.array([p["a"], p["b"], p["c"]])


# --------------------------------------------------------------------------- estimates


def test_unconstrained_fit_and_intervals_equal_ordinary_least_squares(linear_problem):
    A, y = linear_problem
    rep = fit_parameters(lambda p: A @ vec(p) - y, {"a": 0.0, "b": 0.0, "c": 0.0})
    p_ols, *_ = np.linalg.lstsq(A, y, rcond=None)
    np.testing.assert_allclose(vec(rep.estimates), p_ols, rtol=1e-7, atol=1e-9)
    # textbook OLS interval: p +- t_{0.975, n-3} s sqrt(diag((A^T A)^-1))
    res = y - A @ p_ols
    dof = len(y) - 3
    s = np.sqrt(res @ res / dof)
    half = scipy.stats.t.ppf(0.975, dof) * s * np.sqrt(np.diag(np.linalg.inv(A.T @ A)))
    for i, n in enumerate("abc"):
        lo, hi = rep.intervals[n]
        assert lo == pytest.approx(p_ols[i] - half[i], rel=1e-5, abs=1e-8)
        assert hi == pytest.approx(p_ols[i] + half[i], rel=1e-5, abs=1e-8)
    assert rep.identifiable and rep.undetermined == ()
    assert rep.dof == dof


def test_analytic_jacobian_gives_the_same_fit(linear_problem):
    A, y = linear_problem
    fd = fit_parameters(lambda p: A @ vec(p) - y, {"a": 0.0, "b": 0.0, "c": 0.0})
    an = fit_parameters(lambda p: A @ vec(p) - y, {"a": 0.0, "b": 0.0, "c": 0.0},
                        jac=lambda p: A)
    np.testing.assert_allclose(vec(an.estimates), vec(fd.estimates), rtol=1e-8)
    for n in "abc":
        np.testing.assert_allclose(an.intervals[n], fd.intervals[n], rtol=1e-6)


def test_equality_constraint_matches_the_kkt_solution(linear_problem):
    A, y = linear_problem
    rep = fit_parameters(
        lambda p: A @ vec(p) - y, {"a": 0.0, "b": 0.0, "c": 0.0},
        constraints=[Constraint(lambda p: p["a"] + p["b"] + p["c"] - 1.0, "eq", "sum")],
    )
    # KKT system of min |A p - y|^2 subject to [1 1 1] p = 1
    C = np.ones((1, 3))
    kkt = np.block([[2 * A.T @ A, C.T], [C, np.zeros((1, 1))]])
    sol = np.linalg.solve(kkt, np.concatenate([2 * A.T @ y, [1.0]]))
    np.testing.assert_allclose(vec(rep.estimates), sol[:3], rtol=1e-6, atol=1e-8)
    assert rep.method == "slsqp" and "sum" in rep.active_constraints
    # along the constraint the sum cannot move: the intervals must respect it
    assert rep.identifiable


def test_active_inequality_holds_the_parameter_on_its_limit(linear_problem):
    A, y = linear_problem
    rep = fit_parameters(
        lambda p: A @ vec(p) - y, {"a": 0.0, "b": 0.0, "c": 0.0},
        constraints=[Constraint(lambda p: 0.5 - p["c"], "ineq", "c at most 0.5")],
    )
    # independent: least squares on a, b with c held at 0.5
    ab, *_ = np.linalg.lstsq(A[:, :2], y - 0.5 * A[:, 2], rcond=None)
    np.testing.assert_allclose(vec(rep.estimates), [*ab, 0.5], rtol=1e-6, atol=1e-8)
    assert "c at most 0.5" in rep.active_constraints


def test_fixed_parameters_are_held_and_reported(linear_problem):
    A, y = linear_problem
    rep = fit_parameters(lambda p: A @ vec(p) - y, {"a": 0.0, "b": 0.0, "c": 0.0},
                         fixed={"c": 0.5})
    ab, *_ = np.linalg.lstsq(A[:, :2], y - 0.5 * A[:, 2], rcond=None)
    np.testing.assert_allclose([rep.estimates["a"], rep.estimates["b"]], ab, rtol=1e-7)
    assert rep.estimates["c"] == 0.5 and rep.fixed == ("c",) and rep.free == ("a", "b")


def test_parameter_on_a_bound_has_no_interval(linear_problem):
    A, y = linear_problem
    rep = fit_parameters(lambda p: A @ vec(p) - y, {"a": 0.0, "b": 0.0, "c": 0.0},
                         bounds={"c": (-1.0, 1.0)})
    assert rep.estimates["c"] == pytest.approx(1.0, abs=1e-9)
    assert rep.at_bound == ("c",) and rep.intervals["c"] is None
    ab, *_ = np.linalg.lstsq(A[:, :2], y - A[:, 2], rcond=None)
    np.testing.assert_allclose([rep.estimates["a"], rep.estimates["b"]], ab, rtol=1e-6)


# --------------------------------------------------------------------------- identifiability


def test_product_only_model_names_the_undetermined_ratio_and_shows_the_spread(rng):
    x = np.linspace(0.0, 1.0, 40)
    y = 6.0 * x + 0.01 * rng.standard_normal(x.size)
    rep = fit_parameters(lambda p: p["a"] * p["b"] * x - y, {"a": 1.0, "b": 1.0},
                         bounds={"a": (0.01, 100.0), "b": (0.01, 100.0)},
                         n_starts=6, seed=3)
    assert not rep.identifiable
    (und,) = rep.undetermined
    # data see a*b only: moving along a/b is free
    assert und.name == "a / b" and und.reason == "structural"
    assert und.exponents == pytest.approx({"a": 1.0, "b": -1.0}, abs=1e-6)
    assert [c.name for c in rep.determined_combinations] == ["a*b"]
    assert rep.determined == {"a": False, "b": False}
    assert rep.intervals == {"a": None, "b": None}
    assert rep.singular_values[-1] < 1e-6
    # every start fits equally well, at very different a
    assert all(s.equivalent for s in rep.starts)
    lo, hi = rep.spread["a"]
    assert hi / lo > 10
    for s in rep.starts:
        assert s.estimate["a"] * s.estimate["b"] == pytest.approx(6.0, rel=1e-2)
    text = rep.summary()
    assert "NOT determined" in text and "a / b" in text


def test_power_product_names_use_exponents():
    x = np.linspace(0.1, 1.0, 30)
    # output depends on k^2 / (b R) only: two of three log-directions are invisible
    rep = fit_parameters(lambda p: p["k"] ** 2 / (p["b"] * p["R"]) * x - 2.0 * x,
                         {"b": 1.0, "R": 1.0, "k": 1.0},
                         bounds={n: (0.0, np.inf) for n in "bRk"})  # positive: log-scaled
    (det,) = rep.determined_combinations
    assert det.exponents == pytest.approx({"b": -0.5, "R": -0.5, "k": 1.0}, abs=1e-6)
    assert det.name == "k / (b^0.5*R^0.5)"
    # the two invisible directions, in reduced row-echelon form: b and R each move with
    # sqrt(k) without changing k^2/(b R)
    assert [c.name for c in rep.undetermined] == ["b*k^0.5", "R*k^0.5"]
    assert rep.estimates["k"] ** 2 / (rep.estimates["b"] * rep.estimates["R"]) == \
        pytest.approx(2.0, rel=1e-8)


def test_separate_equal_minima_are_caught_by_the_multistart():
    x = np.linspace(0.0, 1.0, 20)
    y = 4.0 * x
    # a^2 = 4 has two roots: the local analysis at either sees a well-determined a
    rep = fit_parameters(lambda p: p["a"] ** 2 * x - y, {"a": 1.0},
                         bounds={"a": (-5.0, 5.0)}, n_starts=8, seed=1)
    assert rep.spread["a"][0] == pytest.approx(-2.0, rel=1e-6)
    assert rep.spread["a"][1] == pytest.approx(2.0, rel=1e-6)
    assert rep.determined == {"a": False}
    (und,) = rep.undetermined
    assert und.reason == "multi-start" and und.name == "a"


def test_paper_style_equality_constraints_do_not_make_the_answer_unique():
    """Adewusi (2016) claims constraints T(p) = T_hat, G(p) = G_hat make (b, R, k) unique
    given J; the fit from several starts lands on different points of one curve."""
    J, T_hat, G_hat = 9.85e-3, 3.849, 0.9753

    def tg(p):
        den = p["b"] * p["R"] + p["k"] ** 2
        return J * p["R"] / den, p["k"] / den

    rep = fit_parameters(
        lambda p: np.zeros(5),  # the misfit is constant on the constraint set
        {"b": 2e-3, "R": 5.0, "k": 1e-2},
        bounds={"b": (1e-6, 1.0), "R": (0.1, 100.0), "k": (1e-4, 1.0)},
        constraints=[Constraint(lambda p: tg(p)[0] / T_hat - 1, "eq", "T"),
                     Constraint(lambda p: tg(p)[1] / G_hat - 1, "eq", "G")],
        n_starts=5, seed=2,
    )
    lo, hi = rep.spread["R"]
    assert hi / lo > 2
    for s in rep.starts:
        T, G = tg(s.estimate)
        assert T == pytest.approx(T_hat, rel=1e-5) and G == pytest.approx(G_hat, rel=1e-5)


# --------------------------------------------------------------------------- time domain


def test_zoh_step_and_foh_ramp_responses_are_exact_at_the_samples():
    T, G, dt = 0.7, 2.0, 0.05
    t = np.arange(200) * dt
    sys = control.tf([G], [T, 1.0])
    y_step = simulate_continuous(sys, t, np.ones_like(t), hold="zoh")[:, 0]
    # the held input u[k] acts over [t_k, t_k+1): y(t_k) = G (1 - exp(-t_k/T))
    np.testing.assert_allclose(y_step, G * (1 - np.exp(-t / T)), atol=1e-12)
    y_ramp = simulate_continuous(sys, t, t, hold="foh")[:, 0]
    exact = G * (t - T + T * np.exp(-t / T))
    np.testing.assert_allclose(y_ramp, exact, atol=1e-10)
    # a held ramp lags by about half a sample
    y_zoh = simulate_continuous(sys, t, t, hold="zoh")[:, 0]
    assert abs(y_zoh[-1] - exact[-1]) == pytest.approx(G * dt / 2, rel=0.05)


def test_initial_state_response_matches_lsim():
    a = np.array([[0.0, 1.0], [-4.0, -0.3]])
    b, c = np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]])
    t = np.arange(400) * 0.02
    u = np.sin(t)
    x0 = np.array([0.5, -1.0])
    y = simulate_continuous(control.ss(a, b, c, 0), t, u, x0=x0)[:, 0]
    _, y_ref, _ = scipy.signal.lsim((a, b, c, [[0.0]]), u, t, X0=x0, interp=False)
    np.testing.assert_allclose(y, y_ref, atol=1e-10)


def test_reserved_initial_state_name_is_refused():
    with pytest.raises(DataError, match=r"'x0\[0\]' is reserved"):
        fit_greybox(first_order, T_AXIS, U_STEP, Y_STEP, {"T": 1.0, "G": 1.0, "x0[0]": 0.0},
                    initial_state="fit")


def test_mass_spring_damper_recovered_from_random_input(rng):
    m, k, c = 2.0, 80.0, 1.5
    dt = 0.01
    t = np.arange(1500) * dt
    u = np.repeat(rng.standard_normal(150), 10)  # held random levels, not a single step
    truth = scipy.signal.StateSpace([[0, 1], [-k / m, -c / m]], [[0], [1 / m]], [[1, 0]], [[0]])
    _, y, _ = scipy.signal.lsim(truth, u, t, interp=False)  # independent ZOH simulation

    def model(p):
        return control.ss([[0, 1], [-p["k"] / p["m"], -p["c"] / p["m"]]],
                          [[0], [1 / p["m"]]], [[1, 0]], [[0]])

    rep = fit_greybox(model, t, u, y, {"m": m, "k": 60.0, "c": 1.0}, fixed=["m"],
                      bounds={"k": (1.0, 1e3), "c": (1e-3, 10.0)})
    assert rep.estimates["k"] == pytest.approx(k, rel=1e-6)
    assert rep.estimates["c"] == pytest.approx(c, rel=1e-5)
    assert rep.log_scaled == ("k", "c")


def test_report_is_json_serialisable(linear_problem):
    A, y = linear_problem
    rep = fit_parameters(lambda p: A @ vec(p) - y, {"a": 0.0, "b": 0.0, "c": 0.0},
                         n_starts=3)
    d = json.loads(json.dumps(rep.to_dict()))
    assert set(d["estimates"]) == {"a", "b", "c"} and d["undetermined"] == []


# --------------------------------------------------------------------------- bad input


def first_order(p):
    return control.tf([p["G"]], [p["T"], 1.0])


T_AXIS = np.arange(50) * 0.1
U_STEP = np.ones(50)
Y_STEP = 2.0 * (1 - np.exp(-T_AXIS / 0.5))


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        ({"bounds": {"X": (0, 1)}}, r"unknown parameter 'X' in bounds"),
        ({"fixed": ["Tau"]}, r"unknown parameter 'Tau' in fixed"),
        ({"bounds": {"T": (2.0, 1.0)}}, r"parameter 'T': lower 2 is above upper 1"),
        ({"bounds": {"T": (2.0, 3.0)}}, r"initial value 1 of parameter 'T' is outside"),
        ({"constraints": [Constraint(lambda p: p["T"] - 1.0, "eq", "T is 1"),
                          Constraint(lambda p: p["T"] - 2.0, "eq", "T is 2")]},
         r"inconsistent constraints.*'T is 1'.*'T is 2'|inconsistent constraints.*'T is 2'"),
        ({"bounds": {"T": (0.1, 2.0)},
          "constraints": [Constraint(lambda p: p["T"] - 3.0, "ineq", "T at least 3")]},
         r"inconsistent constraints.*'T at least 3'"),
        ({"constraints": [Constraint(lambda p: p["L"], "eq", "uses L")]},
         r"constraint 'uses L' uses unknown parameter 'L'"),
        ({"constraints": [Constraint(lambda p: p["T"], "le", "bad kind")]},
         r"constraint 'bad kind': kind must be"),
    ],
)
def test_bad_options_raise_a_clear_error_naming_the_item(kwargs, pattern):
    with pytest.raises(DataError, match=pattern):
        fit_greybox(first_order, T_AXIS, U_STEP, Y_STEP, {"T": 1.0, "G": 1.0}, **kwargs)


def test_model_using_an_unknown_parameter_is_named():
    def model(p):
        return control.tf([p["G"]], [p["L"], p["T"], 1.0])

    with pytest.raises(DataError, match=r"uses unknown parameter 'L'"):
        fit_greybox(model, T_AXIS, U_STEP, Y_STEP, {"T": 1.0, "G": 1.0})


@pytest.mark.parametrize(
    ("t", "u", "y", "pattern"),
    [
        (T_AXIS[:3], U_STEP[:3], Y_STEP[:3], r"data too short: 3 samples for 2 free"),
        (T_AXIS[:1], U_STEP[:1], Y_STEP[:1], r"data too short"),
        (np.r_[T_AXIS[:10], T_AXIS[11:]], U_STEP[:49], Y_STEP[:49],
         r"not uniformly sampled: step before sample 10"),
        (T_AXIS, U_STEP, np.r_[Y_STEP[:7], np.nan, Y_STEP[8:]], r"y at sample 7"),
        (T_AXIS, U_STEP[:40], Y_STEP, r"u must have 50 samples"),
        (T_AXIS, U_STEP, np.column_stack([Y_STEP, Y_STEP]), r"model has 1 output"),
    ],
)
def test_bad_data_raise_a_clear_error_naming_the_sample(t, u, y, pattern):
    with pytest.raises(DataError, match=pattern):
        fit_greybox(first_order, t, u, y, {"T": 1.0, "G": 1.0})


def test_log_scaling_refused_for_a_parameter_that_may_be_negative():
    with pytest.raises(DataError, match=r"parameter 'G' cannot be log-scaled"):
        fit_greybox(first_order, T_AXIS, U_STEP, Y_STEP, {"T": 1.0, "G": 1.0},
                    bounds={"G": (-1.0, 5.0)}, log={"G": True})


# --------------------------------------------------------------------------- model updating


def test_spring_stiffnesses_updated_from_natural_frequencies_with_eigen_sensitivities():
    """The same machinery for model updating: residuals of squared natural frequencies,
    analytic Jacobian from the eigenvalue sensitivity phi^T (dK/dk) phi."""
    m = np.diag([2.0, 1.5, 1.0])
    e = [np.array([[1.0, 0, 0], [0, 0, 0], [0, 0, 0]]),   # ground - mass 1
         np.array([[1.0, -1, 0], [-1, 1, 0], [0, 0, 0]]),  # mass 1 - mass 2
         np.array([[0, 0, 0], [0, 1.0, -1], [0, -1, 1]])]  # mass 2 - mass 3
    names = ("k1", "k2", "k3")

    def stiffness(p):
        return sum(p[n] * ei for n, ei in zip(names, e))

    truth = {"k1": 100.0, "k2": 150.0, "k3": 80.0}
    lam_meas = scipy.linalg.eigh(stiffness(truth), m, eigvals_only=True)

    def residual(p):
        return scipy.linalg.eigh(stiffness(p), m, eigvals_only=True) / lam_meas - 1

    def jac(p):
        _, phi = scipy.linalg.eigh(stiffness(p), m)  # mass-normalised shapes
        return np.column_stack([np.einsum("ji,jk,ki->i", phi, ei, phi) for ei in e]) \
            / lam_meas[:, None]

    start = {n: 120.0 for n in names}
    bounds = {n: (70.0, 200.0) for n in names}
    # from the nominal start alone the fit stops in a local minimum; the multi-start
    # finds the exact solution and marks the others as worse
    rep = fit_parameters(residual, start, bounds=bounds, jac=jac, min_obs=3, n_starts=8)
    for n in names:
        assert rep.estimates[n] == pytest.approx(truth[n], rel=1e-8)
    assert rep.cost < 1e-20
    assert not all(s.equivalent for s in rep.starts)
    fd = fit_parameters(residual, start, bounds=bounds, min_obs=3, n_starts=8)
    for n in names:
        assert fd.estimates[n] == pytest.approx(truth[n], rel=1e-7)
