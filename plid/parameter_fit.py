"""Fit named parameters to any residual function, honestly: :func:`fit_parameters` (bounds,
fixed parameters, constraints, seeded multi-start; Jacobian intervals, identifiability
analysis and the multi-start spread in its :class:`trussid.plid.greybox_report.GreyboxReport`).
The conventions (log coordinates, naming of undetermined combinations, constraints) are in
:mod:`trussid.plid.greybox`'s module docstring.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.stats

from trussid.plid._parameter_space import (build_space, check_constraints, combination_of,
                                           fd_jacobian, readable_basis, rref, sample_starts)
from trussid.plid.errors import DataError
from trussid.plid.greybox_report import (INVOLVEMENT_TOL, STRUCTURAL_RTOL, Constraint,
                                         GreyboxReport, StartResult)

__all__ = ["fit_parameters"]

#: Penalty residual used when the model fails (non-finite output) away from the start.
_PENALTY = 1e6


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
    space = build_space(initial, bounds, fixed, log, scales)
    constraints = check_constraints(constraints)
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

    starts = sample_starts(space, theta0, n_starts, seed)
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
        jm = jfun(theta) if jfun is not None else fd_jacobian(safe_r, theta, r, central=False,
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
        jm = jfun(theta) if jfun is not None else fd_jacobian(
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
            jc = fd_jacobian(one, theta, val, central=True)
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
            basis = rref((z @ wt[mask].T).T)
            largest = float(s_rel[mask].max())
            undetermined += [combination_of(row, space, largest, reason) for row in basis]
    if not undetermined:  # ambiguity only the multi-start sees (e.g. separate minima)
        for n in by_starts:
            e = np.zeros(n_free)
            e[free.index(n)] = 1.0
            undetermined.append(combination_of(e, space, None, "multi-start"))
    det_comb = []
    for row in (readable_basis(null_dirs, n_free) if n_free else ()):
        e = row / np.linalg.norm(row)
        if not disagree(e, float(np.sqrt(max(e @ cov @ e, 0.0)))):
            det_comb.append(combination_of(row, space))

    return GreyboxReport(
        estimates=est, fixed=fixed, free=free, log_scaled=log_names, intervals=intervals,
        std_errors=std_errors, determined=determined,
        at_bound=tuple(n for n, b in zip(free, at_bound_mask) if b), cost=cost,
        rms=float(np.sqrt(2 * cost / n_obs)), residual_std=float(np.sqrt(s2)), n_obs=n_obs,
        dof=dof, singular_values=s_rel, determined_combinations=tuple(det_comb),
        undetermined=tuple(undetermined), starts=tuple(start_results), spread=spread,
        method=method, confidence=confidence, active_constraints=tuple(active),
    )
