"""The parameter space of a grey-box fit (:func:`trussid.plid.parameter_fit.fit_parameters`):
scaled and log coordinates, bounds and fixed parameters, finite-difference Jacobians, seeded
multi-start points and the readable naming of parameter combinations (module docstring of
:mod:`trussid.plid.greybox`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.stats import qmc

from trussid.plid.errors import DataError
from trussid.plid.greybox_report import INVOLVEMENT_TOL, Combination, Constraint




class Params(dict):
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
class ParameterSpace:
    """Map between the free-parameter vector theta and the full parameter dict."""

    names: tuple[str, ...]
    free: tuple[str, ...]
    values: dict[str, float]
    log: np.ndarray
    scale: np.ndarray
    lower: np.ndarray  # in theta
    upper: np.ndarray

    def params(self, theta, where="model") -> Params:
        p = dict(self.values)
        phys = np.where(self.log, np.exp(np.clip(theta, -700, 700)), theta * self.scale)
        p.update(zip(self.free, (float(v) for v in phys)))
        return Params(p, where)

    def theta(self, p: Mapping[str, float]) -> np.ndarray:
        x = np.array([p[n] for n in self.free], dtype=float)
        with np.errstate(divide="ignore"):
            return np.where(self.log, np.log(np.where(self.log, x, 1.0)), x / self.scale)

    def dp_dtheta(self, theta) -> np.ndarray:
        return np.where(self.log, np.exp(theta), self.scale)


def check_name_set(what, given: Iterable[str], names) -> None:
    unknown = [n for n in given if n not in names]
    if unknown:
        raise DataError(
            f"unknown parameter {unknown[0]!r} in {what}; parameters are: "
            + ", ".join(names)
        )


def build_space(initial, bounds, fixed, log, scales=None) -> ParameterSpace:
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
    check_name_set("bounds", bounds, names)
    if isinstance(fixed, Mapping):
        check_name_set("fixed", fixed, names)
        values.update({n: float(v) for n, v in fixed.items()})
        fixed_set = set(fixed)
    else:
        fixed = list(fixed or ())
        check_name_set("fixed", fixed, names)
        fixed_set = set(fixed)
    log = dict(log or {})
    check_name_set("log", log, names)
    scales = dict(scales or {})
    check_name_set("scales", scales, names)
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
    return ParameterSpace(names, tuple(free), values, np.array(logs, dtype=bool),
                  np.array(scale_list, dtype=float), np.array(lo, dtype=float),
                  np.array(hi, dtype=float))


def check_constraints(constraints) -> tuple[Constraint, ...]:
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


def fd_jacobian(fun, theta, f0, central=True, lower=None, upper=None) -> np.ndarray:
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


def format_power(exps: Mapping[str, float], log_names, tol=INVOLVEMENT_TOL) -> str:
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


def combination_of(direction, space: ParameterSpace, sv=None, reason="determined") -> Combination:
    d = np.asarray(direction, float)
    big = np.abs(d)
    lead = int(np.flatnonzero(big >= (1 - 1e-6) * big.max())[0])  # ties: the first one
    d = d / d[lead]  # largest component +1
    d[np.abs(d) < 1e-9] = 0.0
    exps = {n: float(e) for n, e in zip(space.free, d)}
    log_names = {n for n, lg in zip(space.free, space.log) if lg}
    return Combination(exps, format_power(exps, log_names), sv, reason)


def rref(rows: np.ndarray) -> np.ndarray:
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


def readable_basis(null: np.ndarray, n: int) -> np.ndarray:
    """Rows spanning the orthogonal complement of the columns of ``null`` (n x r), RREF."""
    if null.shape[1] == 0:
        return np.eye(n)
    return rref(scipy.linalg.null_space(null.T).T)


def sample_starts(space: ParameterSpace, theta0, n_starts, seed) -> np.ndarray:
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
