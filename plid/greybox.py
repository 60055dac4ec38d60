"""Grey-box identification: fit named physical parameters of a model to data, honestly.

Two layers, so the same machinery serves time-domain fitting and FE model updating:

* :func:`fit_parameters` fits any residual function ``residual(p) -> 1-D array`` of a
  parameter dict (optionally with its analytic Jacobian), with bounds, fixed parameters,
  equality/inequality constraints and seeded multi-start, and returns a
  :class:`GreyboxReport` with estimates, Jacobian confidence intervals, an identifiability
  analysis naming the parameter combinations the data cannot determine, and the
  multi-start spread.
* :func:`fit_greybox` builds that residual from a continuous-time model
  ``model(p) -> control.StateSpace | control.TransferFunction`` simulated (ZOH or FOH, to
  match how the data were sampled) with any input, against measured outputs.

Positive parameters (lower bound >= 0 and positive initial value) are estimated in
``ln p`` by default: their scale then drops out of the optimiser and of the
identifiability analysis, and a direction ``v`` in log space that the data cannot see is
the power product ``prod p_i ** v_i`` -- which is how undetermined combinations are named
(e.g. ``R*k``). Other parameters are estimated as ``p / scale`` with ``scale`` the initial
magnitude.

Constraints are callables of the parameter dict: ``Constraint(fun, "eq")`` means
``fun(p) == 0``, ``Constraint(fun, "ineq")`` means ``fun(p) >= 0`` (scipy's convention).
Write them in a scaled form (e.g. ``T(p) / T_hat - 1``): feasibility is judged with the
absolute tolerance ``ctol``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import control
import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.signal
import scipy.stats
from scipy.stats import qmc

from trussid.plid._validate import as_2d, check_time
from trussid.plid.errors import DataError

__all__ = [
    "Combination",
    "Constraint",
    "GreyboxReport",
    "StartResult",
    "fit_greybox",
    "fit_parameters",
    "simulate_continuous",
]

#: Relative singular value below which a direction counts as structurally undetermined
#: (finite-difference noise of an exactly invisible direction sits near 1e-8).
STRUCTURAL_RTOL = 1e-6
#: A parameter whose component in a unit null direction exceeds this is undetermined.
INVOLVEMENT_TOL = 1e-2
#: Penalty residual used when the model fails (non-finite output) away from the start.
_PENALTY = 1e6


@dataclass(frozen=True)
class Constraint:
    """A constraint between parameters.

    Parameters
    ----------
    fun : callable
        ``fun(p) -> float or array`` of the parameter dict ``p`` (all parameters, fixed
        ones included).
    kind : {"eq", "ineq"}
        ``"eq"``: ``fun(p) == 0``; ``"ineq"``: ``fun(p) >= 0``.
    name : str
        Used in messages and the report.
    """

    fun: Callable[[Mapping[str, float]], float | np.ndarray]
    kind: str = "eq"
    name: str = "constraint"


@dataclass(frozen=True)
class Combination:
    """A parameter combination, as a direction in the estimation coordinates.

    Attributes
    ----------
    exponents : dict
        Direction normalised so that its largest component is 1 (for log parameters the
        exponents of the power product ``prod p ** e``; for linear ones the coefficients
        of ``p / scale``).
    name : str
        Readable form, e.g. ``"R*k / b^0.016"``.
    singular_value : float or None
        Singular value of the scaled sensitivity matrix along this direction, relative to
        the largest (None for the determined combinations, which are a readable basis and
        not singular directions).
    reason : str
        ``"structural"`` (invisible to the model), ``"practical"`` (invisible at this
        noise level: 95 % half-width wider than a factor e for log parameters, than
        100 % of the initial magnitude for linear ones), ``"multi-start"`` (equally good
        fits from different starts disagree) or ``"determined"``.
    """

    exponents: dict[str, float]
    name: str
    singular_value: float | None = None
    reason: str = "determined"


@dataclass(frozen=True)
class StartResult:
    """One start of the multi-start: where it began, where it ended, how good it was."""

    start: dict[str, float]
    estimate: dict[str, float]
    cost: float
    success: bool
    equivalent: bool
    message: str = ""


@dataclass(frozen=True)
class GreyboxReport:
    """Result of a grey-box fit.

    Attributes
    ----------
    estimates : dict
        Best estimate of every parameter (fixed ones at their given value). For
        undetermined parameters this is one representative of equally good fits.
    fixed : tuple of str
    free : tuple of str
    log_scaled : tuple of str
        Free parameters estimated in ``ln p``.
    intervals : dict
        ``name -> (low, high)`` 95 % (``confidence``) interval for each free, determined,
        not-at-bound parameter; ``None`` otherwise. Intervals are conditional on the
        undetermined combinations.
    std_errors : dict
        Standard error in the estimation coordinate (of ``ln p`` for log parameters).
    determined : dict
        ``name -> bool`` for free parameters.
    at_bound : tuple of str
        Free parameters that ended on a bound (no interval).
    cost : float
        ``0.5 * sum(residual**2)`` at the estimate.
    rms : float
        RMS residual.
    residual_std : float
        ``sqrt(sum r^2 / dof)``.
    n_obs, dof : int
    singular_values : ndarray
        Of the scaled sensitivity matrix on the constraint tangent space, relative to the
        largest, descending.
    determined_combinations, undetermined : tuple of Combination
    starts : tuple of StartResult
    spread : dict
        ``name -> (min, max)`` over the starts that reached an equivalent fit (cost within
        the likelihood-ratio 95 % threshold of the best).
    method : str
    confidence : float
    """

    estimates: dict[str, float]
    fixed: tuple[str, ...]
    free: tuple[str, ...]
    log_scaled: tuple[str, ...]
    intervals: dict[str, tuple[float, float] | None]
    std_errors: dict[str, float | None]
    determined: dict[str, bool]
    at_bound: tuple[str, ...]
    cost: float
    rms: float
    residual_std: float
    n_obs: int
    dof: int
    singular_values: np.ndarray
    determined_combinations: tuple[Combination, ...]
    undetermined: tuple[Combination, ...]
    starts: tuple[StartResult, ...]
    spread: dict[str, tuple[float, float]]
    method: str
    confidence: float = 0.95
    active_constraints: tuple[str, ...] = field(default=())

    @property
    def identifiable(self) -> bool:
        """True when the data determine every free parameter."""
        return not self.undetermined

    def summary(self) -> str:
        """A human-readable table of estimates, intervals and identifiability."""
        pct = f"{100 * self.confidence:g} %"
        lines = [
            f"{len(self.free)} free parameter(s), {len(self.fixed)} fixed; {self.n_obs} "
            f"residuals, rms {self.rms:.4g}; method {self.method}; {len(self.starts)} start(s)",
            f"  {'parameter':<12}{'estimate':>12}   {pct + ' interval':<28}note",
        ]
        for name, value in self.estimates.items():
            if name in self.fixed:
                lines.append(f"  {name:<12}{value:>12.5g}   {'':<28}fixed")
                continue
            iv = self.intervals.get(name)
            ivs = f"[{iv[0]:.5g}, {iv[1]:.5g}]" if iv else "-"
            note = (
                "at bound" if name in self.at_bound
                else "" if self.determined.get(name, True)
                else "undetermined (one of many equally good fits)"
            )
            lines.append(f"  {name:<12}{value:>12.5g}   {ivs:<28}{note}")
        if len(self.singular_values):
            sv = ", ".join(f"{s:.3g}" for s in self.singular_values)
            lines.append(f"  relative singular values of the sensitivity: {sv}")
        if self.determined_combinations:
            lines.append(
                "  determined: " + ", ".join(c.name for c in self.determined_combinations)
            )
        if self.undetermined:
            lines.append(
                "  NOT determined by the data: "
                + "; ".join(
                    f"{c.name} ({c.reason}"
                    + (f", relative singular value {c.singular_value:.2g})"
                       if c.singular_value is not None else ": equal fits disagree)")
                    for c in self.undetermined
                )
            )
        else:
            lines.append("  all free parameters are determined by the data")
        n_eq = sum(s.equivalent for s in self.starts)
        if len(self.starts) > 1:
            lines.append(f"  multi-start: {n_eq} of {len(self.starts)} starts reached an "
                         "equivalent fit; spread over them:")
            for name in self.free:
                lo, hi = self.spread[name]
                lines.append(f"    {name:<10} {lo:.5g} .. {hi:.5g}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """Plain JSON-ready dict."""
        return {
            "estimates": dict(self.estimates),
            "fixed": list(self.fixed),
            "free": list(self.free),
            "intervals": {k: (list(v) if v else None) for k, v in self.intervals.items()},
            "determined": dict(self.determined),
            "at_bound": list(self.at_bound),
            "rms": self.rms,
            "residual_std": self.residual_std,
            "singular_values": [float(s) for s in self.singular_values],
            "determined_combinations": [c.name for c in self.determined_combinations],
            "undetermined": [
                {"name": c.name, "exponents": c.exponents, "reason": c.reason,
                 "singular_value": c.singular_value}
                for c in self.undetermined
            ],
            "spread": {k: list(v) for k, v in self.spread.items()},
            "starts": [
                {"start": s.start, "estimate": s.estimate, "cost": s.cost,
                 "equivalent": s.equivalent}
                for s in self.starts
            ],
            "method": self.method,
        }


class _Params(dict):
    """The parameter dict handed to user code: an unknown name is a clear DataError."""

    def __init__(self, values, where):
        super().__init__(values)
        self._where = where

    def __missing__(self, key):
        raise DataError(
            f"{self._where} uses unknown parameter {key!r}; parameters are: "
            + ", ".join(sorted(self))
        )


# --------------------------------------------------------------------------- set-up


@dataclass(frozen=True)
class _Space:
    """Map between the free-parameter vector theta and the full parameter dict."""

    names: tuple[str, ...]
    free: tuple[str, ...]
    values: dict[str, float]
    log: np.ndarray
    scale: np.ndarray
    lower: np.ndarray  # in theta
    upper: np.ndarray

    def params(self, theta, where="model") -> _Params:
        p = dict(self.values)
        phys = np.where(self.log, np.exp(np.clip(theta, -700, 700)), theta * self.scale)
        p.update(zip(self.free, (float(v) for v in phys)))
        return _Params(p, where)

    def theta(self, p: Mapping[str, float]) -> np.ndarray:
        x = np.array([p[n] for n in self.free], dtype=float)
        with np.errstate(divide="ignore"):
            return np.where(self.log, np.log(np.where(self.log, x, 1.0)), x / self.scale)

    def dp_dtheta(self, theta) -> np.ndarray:
        return np.where(self.log, np.exp(theta), self.scale)


def _check_name_set(what, given: Iterable[str], names) -> None:
    unknown = [n for n in given if n not in names]
    if unknown:
        raise DataError(
            f"unknown parameter {unknown[0]!r} in {what}; parameters are: "
            + ", ".join(names)
        )


def _build_space(initial, bounds, fixed, log, scales=None) -> _Space:
    if not isinstance(initial, Mapping) or not initial:
        raise DataError("initial must be a non-empty mapping of parameter name to value")
    names = tuple(initial)
    values = {}
    for n in names:
        try:
            values[n] = float(initial[n])
        except (TypeError, ValueError):
            raise DataError(f"initial value of parameter {n!r} is not a number: "
                            f"{initial[n]!r}") from None
        if not math.isfinite(values[n]):
            raise DataError(f"initial value of parameter {n!r} is not finite")
    bounds = dict(bounds or {})
    _check_name_set("bounds", bounds, names)
    if isinstance(fixed, Mapping):
        _check_name_set("fixed", fixed, names)
        values.update({n: float(v) for n, v in fixed.items()})
        fixed_set = set(fixed)
    else:
        fixed = list(fixed or ())
        _check_name_set("fixed", fixed, names)
        fixed_set = set(fixed)
    log = dict(log or {})
    _check_name_set("log", log, names)
    scales = dict(scales or {})
    _check_name_set("scales", scales, names)
    for n, s in scales.items():
        if not (math.isfinite(float(s)) and float(s) > 0):
            raise DataError(f"scale of parameter {n!r} must be positive, got {s!r}")

    free, lo, hi, logs, scale_list = [], [], [], [], []
    for n in names:
        b = bounds.get(n, (-np.inf, np.inf))
        try:
            lower, upper = (float(b[0]) if b[0] is not None else -np.inf,
                            float(b[1]) if b[1] is not None else np.inf)
        except (TypeError, IndexError, ValueError):
            raise DataError(f"bounds of parameter {n!r} must be a (lower, upper) pair, "
                            f"got {b!r}") from None
        if lower > upper:
            raise DataError(f"bounds of parameter {n!r}: lower {lower:g} is above "
                            f"upper {upper:g}")
        if n in fixed_set:
            continue
        if lower == upper:  # a degenerate interval is a fixed parameter
            values[n] = lower
            continue
        v = values[n]
        if not lower <= v <= upper:
            raise DataError(f"initial value {v:g} of parameter {n!r} is outside its "
                            f"bounds [{lower:g}, {upper:g}]")
        use_log = log.get(n, lower >= 0 and v > 0)
        if use_log and (v <= 0 or lower < 0):
            raise DataError(f"parameter {n!r} cannot be log-scaled: it may be "
                            f"non-positive (initial {v:g}, lower bound {lower:g})")
        free.append(n)
        logs.append(bool(use_log))
        if use_log:
            scale_list.append(1.0)
            with np.errstate(divide="ignore"):
                lo.append(np.log(lower) if lower > 0 else -np.inf)
            hi.append(np.log(upper))
        else:
            width = upper - lower
            s = abs(v) if v != 0 else (width if np.isfinite(width) else 1.0)
            s = float(scales.get(n, s))
            scale_list.append(s)
            lo.append(lower / s)
            hi.append(upper / s)
    return _Space(names, tuple(free), values, np.array(logs, dtype=bool),
                  np.array(scale_list, dtype=float), np.array(lo, dtype=float),
                  np.array(hi, dtype=float))


def _check_constraints(constraints) -> tuple[Constraint, ...]:
    out = []
    for i, c in enumerate(constraints or ()):
        if not isinstance(c, Constraint):
            raise DataError(f"constraint {i} is not a plid.greybox.Constraint: {c!r}")
        if c.kind not in ("eq", "ineq"):
            raise DataError(f"constraint {c.name!r}: kind must be 'eq' or 'ineq', "
                            f"got {c.kind!r}")
        out.append(c)
    return tuple(out)


# --------------------------------------------------------------------------- numerics


def _fd_jacobian(fun, theta, f0, central=True, lower=None, upper=None) -> np.ndarray:
    """Finite-difference Jacobian in theta (already scale-free), staying inside bounds."""
    n = theta.size
    jac = np.empty((f0.size, n))
    h = 1e-5 * np.maximum(1.0, np.abs(theta)) if central else 1e-7 * np.maximum(1.0, np.abs(theta))
    for i in range(n):  # one model evaluation per parameter: nothing to vectorise over
        tp, tm = theta.copy(), theta.copy()
        up_ok = upper is None or theta[i] + h[i] <= upper[i]
        dn_ok = lower is None or theta[i] - h[i] >= lower[i]
        if central and up_ok and dn_ok:
            tp[i] += h[i]
            tm[i] -= h[i]
            jac[:, i] = (fun(tp) - fun(tm)) / (2 * h[i])
        elif up_ok:
            tp[i] += h[i]
            jac[:, i] = (fun(tp) - f0) / h[i]
        else:
            tm[i] -= h[i]
            jac[:, i] = (f0 - fun(tm)) / h[i]
    return jac


def _format_power(exps: Mapping[str, float], log_names, tol=INVOLVEMENT_TOL) -> str:
    """``{'R': 1, 'k': 1, 'b': -0.016}`` -> ``'R*k / b^0.016'`` (log parameters)."""

    def term(n, e):
        e = abs(e)
        r = round(e * 2) / 2  # halves read better than 0.499...
        if abs(e - r) < 0.02 and r > 0:
            e = r
        if e == 1:
            return n
        txt = f"{e:g}" if e in (0.5, 1.5, 2, 2.5, 3) else f"{e:.2g}"
        return f"{n}^{txt}"

    lin = [n for n, e in exps.items() if abs(e) >= tol and n not in log_names]
    if lin:  # a mixed/linear direction: name it as the weighted sum it is
        parts = []
        for n, e in exps.items():
            if abs(e) >= tol:
                coef = ("+" if e > 0 else "-") if abs(abs(e) - 1) < 1e-9 else f"{e:+.3g}*"
                parts.append(f"{coef}{'ln ' if n in log_names else ''}{n}")
        return " ".join(parts).lstrip("+")
    num = [term(n, e) for n, e in exps.items() if e >= tol]
    den = [term(n, e) for n, e in exps.items() if e <= -tol]
    if not num:
        return "1 / " + ("*".join(den) if len(den) == 1 else "(" + "*".join(den) + ")")
    s = "*".join(num)
    if den:
        s += " / " + (den[0] if len(den) == 1 else "(" + "*".join(den) + ")")
    return s


def _combination(direction, space: _Space, sv=None, reason="determined") -> Combination:
    d = np.asarray(direction, float)
    big = np.abs(d)
    lead = int(np.flatnonzero(big >= (1 - 1e-6) * big.max())[0])  # ties: the first one
    d = d / d[lead]  # largest component +1
    d[np.abs(d) < 1e-9] = 0.0
    exps = {n: float(e) for n, e in zip(space.free, d)}
    log_names = {n for n, lg in zip(space.free, space.log) if lg}
    return Combination(exps, _format_power(exps, log_names), sv, reason)


def _rref(rows: np.ndarray) -> np.ndarray:
    """Reduced row-echelon form of a basis (rows) of a subspace, for readable names.

    Written by hand because neither numpy nor scipy offers a numeric RREF; column-pivoted
    QR picks the pivots (the parameters most present in the subspace), so each row reads
    as "this parameter, times powers of the non-pivot ones".
    """
    if rows.shape[0] == 0:
        return rows
    _, _, piv = scipy.linalg.qr(rows, pivoting=True, mode="economic")
    cols = np.sort(piv[: rows.shape[0]])
    out = np.linalg.solve(rows[:, cols], rows)
    out[np.abs(out) < 1e-9] = 0.0
    return out


def _readable_basis(null: np.ndarray, n: int) -> np.ndarray:
    """Rows spanning the orthogonal complement of the columns of ``null`` (n x r), RREF."""
    if null.shape[1] == 0:
        return np.eye(n)
    return _rref(scipy.linalg.null_space(null.T).T)


def _sample_starts(space: _Space, theta0, n_starts, seed) -> np.ndarray:
    """Start 0 is the user's initial point; the rest a seeded Latin hypercube over the
    bounds (log-uniform for log parameters; +-1 decade or +-100 % where unbounded)."""
    n = theta0.size
    if n_starts <= 1 or n == 0:
        return theta0[None, :]
    span = np.where(space.log, np.log(10.0), 1.0)
    lo = np.where(np.isfinite(space.lower), space.lower, np.minimum(theta0, space.upper) - span)
    hi = np.where(np.isfinite(space.upper), space.upper, np.maximum(theta0, space.lower) + span)
    lo = np.where(np.isfinite(lo), lo, theta0 - span)
    hi = np.where(np.isfinite(hi), hi, theta0 + span)
    sample = qmc.LatinHypercube(d=n, rng=np.random.default_rng(seed)).random(n_starts - 1)
    pts = lo + sample * (hi - lo)
    return np.vstack([theta0, pts])


# --------------------------------------------------------------------------- fitting


def fit_parameters(
    residual: Callable[[Mapping[str, float]], np.ndarray],
    initial: Mapping[str, float],
    *,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    fixed: Iterable[str] | Mapping[str, float] = (),
    constraints: Sequence[Constraint] = (),
    log: Mapping[str, bool] | None = None,
    jac: Callable[[Mapping[str, float]], np.ndarray] | None = None,
    n_starts: int = 1,
    seed: int = 0,
    confidence: float = 0.95,
    ctol: float = 1e-6,
    min_obs: int | None = None,
    scales: Mapping[str, float] | None = None,
) -> GreyboxReport:
    """Fit named parameters by (constrained) nonlinear least squares, with multi-start.

    Parameters
    ----------
    residual : callable
        ``residual(p) -> ndarray`` (any shape; flattened) of the parameter dict ``p``.
        Weight it so that its entries have equal variance: the confidence intervals assume
        so.
    initial : mapping
        Every parameter name with its starting (or, when fixed, its given) value, in SI.
    bounds : mapping, optional
        ``name -> (lower, upper)``; ``None`` or +-inf for none. ``lower == upper`` fixes.
    fixed : iterable of names or mapping name -> value
        Parameters held at their value.
    constraints : sequence of Constraint
        Equality/inequality constraints; with any, SLSQP is used instead of
        ``least_squares``.
    log : mapping, optional
        ``name -> bool`` to force (or forbid) estimation in ``ln p``; default: log for
        parameters with lower bound >= 0 and positive initial value.
    jac : callable, optional
        ``jac(p) -> (n_residuals, n_free)`` derivative of the residual with respect to the
        free parameters (physical units, in the order of ``initial``); default: finite
        differences.
    n_starts : int
        Number of starts (the first is ``initial``, the rest a seeded Latin hypercube).
    seed : int
    confidence : float
        Level of the intervals.
    ctol : float
        Absolute tolerance on constraint values.
    min_obs : int, optional
        Fewest residual entries accepted (default ``n_free + 2``).
    scales : mapping, optional
        ``name -> typical magnitude`` of linear (not log) parameters, the unit in which
        they are estimated and judged "practically undetermined" (default: the initial
        magnitude; give one for parameters that start at or near zero).

    Returns
    -------
    GreyboxReport

    Raises
    ------
    DataError
        Unknown parameter name, lower bound above upper, initial value outside bounds,
        inconsistent constraints, too few residuals, a residual that is not finite at the
        start.
    """
    # Long: argument checks, scaling and the multi-start loop of one fit; the checks name
    # the user's parameters, which the scaled inner functions no longer see.
    space = _build_space(initial, bounds, fixed, log, scales)
    constraints = _check_constraints(constraints)
    n_free = len(space.free)
    if n_starts < 1:
        raise DataError(f"n_starts must be at least 1, got {n_starts}")

    def rfun(theta):
        r = np.asarray(residual(space.params(theta, "residual/model")), dtype=float).ravel()
        return r

    theta0 = space.theta(space.values)
    r0 = rfun(theta0)
    if not np.all(np.isfinite(r0)):
        bad = int(np.flatnonzero(~np.isfinite(r0))[0])
        raise DataError(f"the model gives a non-finite residual at the initial parameters "
                        f"(entry {bad})")
    n_obs = r0.size
    need = min_obs if min_obs is not None else n_free + 2
    if n_obs < need:
        raise DataError(f"data too short: {n_obs} residuals for {n_free} free parameters "
                        f"(need at least {need})")

    def safe_r(theta):
        r = rfun(theta)
        if r.shape != r0.shape:
            raise DataError(f"the residual changed length from {r0.size} to {r.size}")
        return np.where(np.isfinite(r), r, _PENALTY)

    def cvec(theta, kinds=("eq", "ineq")):
        p = None
        out = []
        for c in constraints:
            if c.kind in kinds:
                if p is None:
                    p = space.params(theta, "constraint")
                p._where = f"constraint {c.name!r}"
                out.append(np.atleast_1d(np.asarray(c.fun(p), dtype=float)).ravel())
        return np.concatenate(out) if out else np.zeros(0)

    if jac is not None:
        def jfun(theta):
            jp = np.asarray(jac(space.params(theta, "jacobian")), dtype=float)
            jp = jp.reshape(n_obs, -1)
            if jp.shape[1] != n_free:
                raise DataError(f"jac returned {jp.shape[1]} columns for {n_free} free "
                                "parameters")
            return jp * space.dp_dtheta(theta)
    else:
        jfun = None

    starts = _sample_starts(space, theta0, n_starts, seed)
    if constraints:
        starts = _feasible_starts(cvec, constraints, space, starts, ctol)

    results = []
    for th in starts:
        results.append(_solve(safe_r, jfun, cvec, space, th, bool(constraints), ctol,
                              r0 @ r0 / 2))

    def infeasible(theta):
        if not constraints:
            return False
        v = np.concatenate([cvec(theta, ("eq",)), np.minimum(cvec(theta, ("ineq",)), 0.0)])
        return bool(v.size and np.max(np.abs(v)) > 10 * ctol)

    # the best feasible end point (SLSQP may stop off the constraints from a bad start) ...
    best = min(range(len(results)), key=lambda i: (infeasible(results[i][0]), results[i][1]))
    # ... unless the fit from the user's own start is statistically as good: among equally
    # good fits (an undetermined combination) report the one the user's guess leads to, so
    # the representative point and the local analysis do not hinge on a random start.
    best_cost = results[best][1]
    s2 = 2 * best_cost / max(n_obs - n_free, 1)
    if (best != 0 and not infeasible(results[0][0])
            and results[0][1] - best_cost <= _equivalence_threshold(s2, n_free, best_cost)):
        best = 0
    theta = results[best][0]
    r = safe_r(theta)
    return _analyse(safe_r, jfun, cvec, space, theta, r, results, starts, constraints,
                    confidence, ctol, "slsqp" if constraints else "least_squares")


def _equivalence_threshold(s2, n_dims, best_cost, confidence=0.95):
    """Cost excess below which a fit is as good as the best: the likelihood-ratio
    threshold ``s^2 chi2_conf(n) / 2`` (cost is half the sum of squares)."""
    return max(0.5 * s2 * scipy.stats.chi2.ppf(confidence, max(n_dims, 1)),
               1e-9 * best_cost, 1e-300)


def _feasible_starts(cvec, constraints, space, starts, ctol):
    """Move each start to the nearest feasible point; fail clearly when none exists."""

    def viol(theta):
        return np.concatenate([cvec(theta, ("eq",)), np.minimum(cvec(theta, ("ineq",)), 0.0)])

    out, worst = [], None
    for th in starts:
        if space.free:
            sol = scipy.optimize.least_squares(
                viol, np.clip(th, space.lower, space.upper),
                bounds=(space.lower, space.upper), xtol=1e-14, ftol=1e-14, gtol=1e-14,
            )
            x = sol.x
        else:
            x = th
        v = viol(x)
        vmax = float(np.max(np.abs(v))) if v.size else 0.0
        if vmax <= ctol:
            out.append(x)
        elif worst is None or vmax < worst[1]:
            worst = (x, vmax)
    if not out:
        raise DataError(_inconsistency_message(constraints, space, worst[0], ctol))
    return np.array(out)


def _inconsistency_message(constraints, space, theta, ctol):
    """Name the constraints still violated at the least-violating point found."""
    p = space.params(theta, "constraint")
    bad = []
    for c in constraints:
        val = np.atleast_1d(np.asarray(c.fun(p), dtype=float))
        off = np.abs(val) if c.kind == "eq" else np.maximum(-val, 0.0)
        if np.max(off) > ctol:
            rel = "= 0" if c.kind == "eq" else ">= 0"
            bad.append(f"{c.name!r} (needs {rel}, best reachable {val[np.argmax(off)]:.3g})")
    return ("inconsistent constraints: no parameter values within the bounds satisfy "
            "them all; violated: " + ", ".join(bad or [c.name for c in constraints]))


def _solve(safe_r, jfun, cvec, space, th, constrained, ctol, cost0):
    """One local fit from ``th``; returns (theta, cost, success, message)."""
    lo, hi = space.lower, space.upper
    if not space.free:
        r = safe_r(th)
        return th, float(r @ r / 2), True, "no free parameters"
    if not constrained:
        sol = scipy.optimize.least_squares(
            safe_r, np.clip(th, lo, hi), jac=jfun if jfun is not None else "2-point",
            bounds=(lo, hi), method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12,
            max_nfev=200 * (th.size + 1),
        )
        return sol.x, float(sol.cost), bool(sol.success), str(sol.message)
    norm = max(cost0, 1e-300)  # SLSQP's tolerances are absolute: work on a unit-size cost

    def f_and_g(theta):
        r = safe_r(theta)
        jm = jfun(theta) if jfun is not None else _fd_jacobian(safe_r, theta, r, central=False,
                                                                 lower=lo, upper=hi)
        return 0.5 * (r @ r) / norm, (jm.T @ r) / norm

    cons = []
    if cvec(th, ("eq",)).size:
        cons.append({"type": "eq", "fun": lambda x: cvec(x, ("eq",))})
    if cvec(th, ("ineq",)).size:
        cons.append({"type": "ineq", "fun": lambda x: cvec(x, ("ineq",))})
    bnds = scipy.optimize.Bounds(lo, hi)
    sol = scipy.optimize.minimize(f_and_g, np.clip(th, lo, hi), jac=True, method="SLSQP",
                                  bounds=bnds, constraints=cons,
                                  options={"maxiter": 500, "ftol": 1e-14})
    r = safe_r(sol.x)
    return sol.x, float(r @ r / 2), bool(sol.success), str(sol.message)


def _analyse(safe_r, jfun, cvec, space, theta, r, results, starts, constraints,
             confidence, ctol, method) -> GreyboxReport:
    """Intervals and identifiability at the best estimate, plus the multi-start spread."""
    # Long: the identifiability analysis reads top to bottom (Jacobian rank, RREF, readable
    # combinations, power-product names); its steps share the scaled Jacobian and names.
    n_free = len(space.free)
    n_obs = r.size
    cost = float(r @ r / 2)
    est = dict(space.params(theta))
    free = space.free
    fixed = tuple(n for n in space.names if n not in free)
    log_names = tuple(n for n, lg in zip(free, space.log) if lg)

    if n_free:
        jm = jfun(theta) if jfun is not None else _fd_jacobian(
            safe_r, theta, r, central=True, lower=space.lower, upper=space.upper)
    else:
        jm = np.zeros((n_obs, 0))
    tol_b = 1e-7 * np.maximum(1.0, np.abs(theta))
    at_bound_mask = ((theta - space.lower) <= tol_b) | ((space.upper - theta) <= tol_b)

    # Active constraints (equalities, inequalities at zero, bounds) restrict the
    # directions the data have to determine to the tangent space Z.
    rows, active = [], []
    for c in constraints:
        def one(th, c=c):
            p = space.params(th, f"constraint {c.name!r}")
            return np.atleast_1d(np.asarray(c.fun(p), dtype=float)).ravel()
        val = one(theta)
        act = np.ones(val.size, bool) if c.kind == "eq" else np.abs(val) <= max(ctol, 1e-9)
        if np.any(act) and n_free:
            jc = _fd_jacobian(one, theta, val, central=True)
            rows.append(jc[act])
            active.append(c.name)
    for i in np.flatnonzero(at_bound_mask):
        e = np.zeros(n_free)
        e[i] = 1.0
        rows.append(e[None, :])
    a_mat = np.vstack(rows) if rows else np.zeros((0, n_free))
    z = scipy.linalg.null_space(a_mat) if a_mat.shape[0] else np.eye(n_free)
    n_eff = z.shape[1]

    dof = max(n_obs - n_eff, 1)
    s2 = 2 * cost / dof
    tq = float(scipy.stats.t.ppf(0.5 + confidence / 2, dof))
    sens = jm @ z
    if n_eff:
        _, sv, wt = np.linalg.svd(sens, full_matrices=False)
    else:
        sv, wt = np.zeros(0), np.zeros((0, 0))
    smax = sv[0] if sv.size and sv[0] > 0 else 1.0
    s_rel = sv / smax
    structural = s_rel < STRUCTURAL_RTOL
    with np.errstate(divide="ignore"):
        practical = ~structural & (tq * math.sqrt(s2) / np.where(sv > 0, sv, np.inf) > 1.0)
    undet = structural | practical
    null_dirs = z @ wt[undet].T if n_eff else np.zeros((n_free, 0))  # unit columns
    det_dirs = z @ wt[~undet].T if n_eff else np.zeros((n_free, 0))
    sd = sv[~undet]
    cov = s2 * (det_dirs / sd**2) @ det_dirs.T if sd.size else np.zeros((n_free, n_free))
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))

    # Starts whose fit is statistically indistinguishable from the best (likelihood-ratio
    # threshold): where they disagree, the data leave the parameters open, whatever the
    # local analysis at the best point says (a curved valley, or separate equal minima).
    best_cost = min(res[1] for res in results)
    thresh = _equivalence_threshold(s2, n_eff, best_cost, confidence)
    start_results, eq_thetas = [], []
    for th0, res in zip(starts, results):
        th, c, ok, msg = res
        feasible = True
        if constraints:
            v = np.concatenate([cvec(th, ("eq",)), np.minimum(cvec(th, ("ineq",)), 0.0)])
            feasible = not v.size or float(np.max(np.abs(v))) <= 10 * ctol
        eq = bool(feasible and c - best_cost <= thresh)
        start_results.append(StartResult(dict(space.params(th0)), dict(space.params(th)), c,
                                         ok, eq, msg))
        if eq:
            eq_thetas.append(th)
    eq_thetas = np.array(eq_thetas) if eq_thetas else theta[None, :]
    sp = np.array([[s.estimate[n] for n in free] for s in start_results if s.equivalent]
                  or [[est[n] for n in free]])
    spread = {n: (float(sp[:, i].min()), float(sp[:, i].max())) for i, n in enumerate(free)}

    def disagree(e, se_e):
        """Equivalent starts differ along ``e`` by more than 3 interval half-widths."""
        dev = np.abs((eq_thetas - theta) @ e)
        return bool(np.any(dev > 3 * tq * se_e + 1e-6))

    determined, intervals, std_errors, by_starts = {}, {}, {}, []
    for i, n in enumerate(free):
        ok = bool(np.all(np.abs(null_dirs[i]) <= INVOLVEMENT_TOL)) if null_dirs.size else True
        e = np.zeros(n_free)
        e[i] = 1.0
        if ok and disagree(e, se[i]):
            ok = False
            by_starts.append(n)
        determined[n] = ok
        if ok and not at_bound_mask[i]:
            lo_t, hi_t = theta[i] - tq * se[i], theta[i] + tq * se[i]
            if space.log[i]:
                intervals[n] = (float(np.exp(lo_t)), float(np.exp(hi_t)))
            else:
                intervals[n] = (float(lo_t * space.scale[i]), float(hi_t * space.scale[i]))
            std_errors[n] = float(se[i])
        else:
            intervals[n] = None
            std_errors[n] = None

    undetermined = []
    for reason, mask in (("structural", structural), ("practical", practical)):
        if np.any(mask):
            # several invisible directions: any basis is as true, the RREF one reads best
            basis = _rref((z @ wt[mask].T).T)
            largest = float(s_rel[mask].max())
            undetermined += [_combination(row, space, largest, reason) for row in basis]
    if not undetermined:  # ambiguity only the multi-start sees (e.g. separate minima)
        for n in by_starts:
            e = np.zeros(n_free)
            e[free.index(n)] = 1.0
            undetermined.append(_combination(e, space, None, "multi-start"))
    det_comb = []
    for row in (_readable_basis(null_dirs, n_free) if n_free else ()):
        e = row / np.linalg.norm(row)
        if not disagree(e, float(np.sqrt(max(e @ cov @ e, 0.0)))):
            det_comb.append(_combination(row, space))

    return GreyboxReport(
        estimates=est, fixed=fixed, free=free, log_scaled=log_names, intervals=intervals,
        std_errors=std_errors, determined=determined,
        at_bound=tuple(n for n, b in zip(free, at_bound_mask) if b), cost=cost,
        rms=float(np.sqrt(2 * cost / n_obs)), residual_std=float(np.sqrt(s2)), n_obs=n_obs,
        dof=dof, singular_values=s_rel, determined_combinations=tuple(det_comb),
        undetermined=tuple(undetermined), starts=tuple(start_results), spread=spread,
        method=method, confidence=confidence, active_constraints=tuple(active),
    )


# --------------------------------------------------------------------------- time domain


def simulate_continuous(system, t, u, hold: str = "zoh", x0=None) -> np.ndarray:
    """Response of a continuous-time system to sampled input.

    (Named apart from :func:`trussid.plid.experiment.simulate`, which runs a discrete model
    through python-control: this one samples a continuous model with the input's hold, and
    for the low orders of grey-box models runs the recursion in C through
    ``scipy.signal.lfilter``, which the fit's hundreds of calls need.)

    Parameters
    ----------
    system : control.StateSpace or control.TransferFunction
        Continuous-time model (anything ``control.ss`` accepts).
    t : (N,) array
        Uniformly spaced sample times [s].
    u : (N,) or (N, m) array
        Input samples.
    hold : {"zoh", "foh"}
        How the input behaves between samples: held constant (a DAC, a square wave
        generator) or linearly interpolated (a sampled smooth signal).
    x0 : (n,) array, optional
        State at ``t[0]`` in the coordinates of ``control.ss(system)`` (default zero).
        With ``hold="foh"`` it is the state of the sampled system, which differs from the
        continuous state by a multiple of ``u[0]``.

    Returns
    -------
    (N, p) array
        Output samples.
    """
    if hold not in ("zoh", "foh"):
        raise DataError(f"hold must be 'zoh' or 'foh', got {hold!r}")
    dt = check_time(t)
    u = as_2d(u, "u", len(t), finite=True)
    try:
        sysc = control.ss(system)
    except Exception as exc:  # noqa: BLE001 - any failure here is the user's model
        raise DataError(f"model did not return a state-space or transfer function: {exc}") from None
    if sysc.isdtime(strict=True):
        raise DataError("model must be continuous-time (dt = 0)")
    if sysc.ninputs != u.shape[1]:
        raise DataError(f"model has {sysc.ninputs} input(s) but u has {u.shape[1]} column(s)")
    sysd = control.sample_system(sysc, dt, method=hold)
    a, b, c, d = (np.asarray(m, dtype=float) for m in (sysd.A, sysd.B, sysd.C, sysd.D))
    n = a.shape[0]
    if x0 is not None:
        x0 = np.asarray(x0, dtype=float).ravel()
        if x0.size != n:
            raise DataError(f"initial state has {x0.size} entries for {n} model state(s)")
    y = u @ d.T
    if n == 0:
        return y
    if n <= 8:
        # lfilter runs the recursion in C; a transfer function per input is well
        # conditioned for the low orders grey-box models have.
        y = np.zeros((u.shape[0], c.shape[0]))
        for j in range(u.shape[1]):
            num, den = scipy.signal.ss2tf(a, b, c, d, input=j)
            for i in range(c.shape[0]):
                y[:, i] += scipy.signal.lfilter(num[i], den, u[:, j])
        if x0 is not None and np.any(x0):
            # free response C A^k x0: the impulse response of (A, x0, C, 0), one step on
            num, den = scipy.signal.ss2tf(a, x0[:, None], c, np.zeros((c.shape[0], 1)))
            imp = np.zeros(u.shape[0] + 1)
            imp[0] = 1.0
            for i in range(c.shape[0]):
                y[:, i] += scipy.signal.lfilter(num[i], den, imp)[1:]
        return y
    _, yd, _ = scipy.signal.dlsim((a, b, c, d, dt), u, x0=x0)
    return np.asarray(yd).reshape(u.shape[0], -1)


def fit_greybox(
    model: Callable[[Mapping[str, float]], object],
    t,
    u,
    y,
    initial: Mapping[str, float],
    *,
    hold: str = "zoh",
    initial_state: str = "zero",
    weights=None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    fixed: Iterable[str] | Mapping[str, float] = (),
    constraints: Sequence[Constraint] = (),
    log: Mapping[str, bool] | None = None,
    n_starts: int = 1,
    seed: int = 0,
    confidence: float = 0.95,
    ctol: float = 1e-6,
) -> GreyboxReport:
    """Fit a parametric continuous-time model to sampled input/output data.

    Parameters
    ----------
    model : callable
        ``model(p) -> control.StateSpace | control.TransferFunction``, continuous time,
        from the dict of named parameters (SI).
    t : (N,) array
        Uniform sample times [s]; the simulation starts from zero state at ``t[0]``.
    u : (N,) or (N, m) array
        Input.
    y : (N,) or (N, p) array
        Measured output.
    initial, bounds, fixed, constraints, log, n_starts, seed, confidence, ctol
        As in :func:`fit_parameters`.
    hold : {"zoh", "foh"}
        Inter-sample behaviour of the input (see :func:`simulate_continuous`).
    initial_state : {"zero", "fit"}
        Start the simulation from rest, or estimate the state at ``t[0]`` as extra
        (nuisance) parameters named ``x0[0]``, ``x0[1]``, ... in the state coordinates of
        ``control.ss(model(p))`` (give a state-space model with physical states, so that
        they mean something and do not move with the other parameters). Their starting
        values come from linear least squares at the initial parameters.
    weights : (p,) array, optional
        Residual weight per output; default 1 for one output, ``1 / std(y_i)`` for several
        (so that channels in different units count alike).

    Returns
    -------
    GreyboxReport
    """
    n = len(np.atleast_1d(t))
    check_time(t)
    u2 = as_2d(u, "u", n, finite=True)
    y2 = as_2d(y, "y", n, finite=True)
    space = _build_space(initial, bounds, fixed, log)
    need = len(space.free) + 2
    if n < need:
        raise DataError(f"data too short: {n} samples for {len(space.free)} free parameters "
                        f"(need at least {need})")
    if weights is None:
        sd = y2.std(axis=0)
        w = np.ones(y2.shape[1]) if y2.shape[1] == 1 else 1.0 / np.where(sd > 0, sd, 1.0)
    else:
        w = np.asarray(weights, dtype=float).ravel()
        if w.size != y2.shape[1]:
            raise DataError(f"weights has {w.size} entries for {y2.shape[1]} output(s)")

    if initial_state not in ("zero", "fit"):
        raise DataError(f"initial_state must be 'zero' or 'fit', got {initial_state!r}")
    x0_names: list[str] = []
    scales = None
    if initial_state == "fit":
        initial, log, scales = _initial_state_guess(model, space, t, u2, y2, w, hold,
                                                    initial, log)
        x0_names = [n for n in initial if n.startswith("x0[")]

    def residual(p):
        x0 = [p[n] for n in x0_names] if x0_names else None
        ys = simulate_continuous(model(p), t, u2, hold, x0)
        if ys.shape[1] != y2.shape[1]:
            raise DataError(f"model has {ys.shape[1]} output(s) but y has {y2.shape[1]} "
                            "column(s)")
        return ((ys - y2) * w).ravel()

    return fit_parameters(residual, initial, bounds=bounds, fixed=fixed,
                          constraints=constraints, log=log, n_starts=n_starts, seed=seed,
                          confidence=confidence, ctol=ctol, scales=scales)


def _initial_state_guess(model, space, t, u2, y2, w, hold, initial, log):
    """Add ``x0[i]`` parameters, started at the least-squares initial state: the output is
    linear in it, ``y = y_u + O x0`` with O the free responses to unit initial states."""
    sys0 = control.ss(model(space.params(space.theta(space.values), "model")))
    n = sys0.nstates
    names = [f"x0[{i}]" for i in range(n)]
    clash = [nm for nm in names if nm in initial]
    if clash:
        raise DataError(f"parameter name {clash[0]!r} is reserved for the fitted initial state")
    y_u = simulate_continuous(sys0, t, u2, hold)
    zero = np.zeros_like(u2)
    obs = np.column_stack([(simulate_continuous(sys0, t, zero, hold, np.eye(n)[i]) * w).ravel()
                           for i in range(n)])
    x0, *_ = np.linalg.lstsq(obs, ((y2 - y_u) * w).ravel(), rcond=None)
    initial = {**initial, **{nm: float(v) for nm, v in zip(names, x0)}}
    log = {**(log or {}), **{nm: False for nm in names}}
    # a state's natural unit: the state that alone explains the largest output seen
    gain = np.max(np.abs(obs), axis=0)
    ymax = float(np.max(np.abs(y2 * w)))
    scales = {nm: (ymax / g if g > 0 and ymax > 0 else 1.0) for nm, g in zip(names, gain)}
    return initial, log, scales
