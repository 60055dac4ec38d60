"""DC-motor parameters from speed response data, in two stages (after Adewusi 2016).

Model: ``J dw/dt = k i - b w`` and, with the armature inductance neglected,
``R i = V - k w``, so that speed follows voltage through the first-order model

    w(s) / V(s) = G / (T s + 1),   T = J R / (b R + k^2),   G = k / (b R + k^2).

Stage 1 fits (T, G) to the data: the 63.2 % rule on the first step of the input gives the
starting guess (a first-order ARX fit when the input has no clean step), least squares on
the whole record refines it, for any input.

Stage 2 fits the physical parameters. The data see only (T, G): two numbers. With J given,
three unknowns (b, R, k) remain, so one combination of them is free whatever the
optimiser says -- the paper's constrained optimisation returned one point of a curve of
equally good answers, chosen by its starting values. Here the report names that free
combination (close to the product ``R*k``: ``R/k = J G / T`` and ``b R/k + k = 1/G`` are
what the data fix) and a multi-start shows the spread. With R also given, b and k follow
uniquely and get confidence intervals.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import control
import numpy as np

from trussid.plid.errors import DataError
from trussid.plid._validate import as_2d, check_time
from trussid.plid.greybox import GreyboxReport, fit_greybox

__all__ = [
    "DCMotorResult",
    "DEFAULT_BOUNDS",
    "first_order_from_physical",
    "first_order_model",
    "fit_first_order",
    "identify_dc_motor",
    "physical_model",
    "step_guess",
]

#: Broad physical bounds for the second stage (SI: N m s/rad, ohm, N m/A).
DEFAULT_BOUNDS = {"b": (1e-9, 1e2), "R": (1e-3, 1e4), "k": (1e-6, 1e2)}


def first_order_from_physical(J: float, b: float, R: float, k: float) -> tuple[float, float]:
    """Time constant T [s] and gain G [rad/s per V] of the motor with L neglected."""
    den = b * R + k * k
    return J * R / den, k / den


def first_order_model(p: Mapping[str, float]) -> control.StateSpace:
    """``G / (T s + 1)`` from ``p = {"T": ..., "G": ...}``; the state is the speed."""
    return control.ss([[-1.0 / p["T"]]], [[p["G"] / p["T"]]], [[1.0]], [[0.0]])


def physical_model(p: Mapping[str, float]) -> control.StateSpace:
    """``k / (J R s + b R + k^2)`` from ``p = {"J", "b", "R", "k"}`` (SI); the state is
    the speed, so a fitted initial state is the initial speed whatever the parameters."""
    jr = p["J"] * p["R"]
    return control.ss([[-(p["b"] * p["R"] + p["k"] ** 2) / jr]], [[p["k"] / jr]], [[1.0]],
                      [[0.0]])


def step_guess(t, u, y) -> tuple[float, float] | None:
    """(T, G) from the first step of the input by the 63.2 % rule, or None without a step.

    The step is the first sample where ``u`` moves by more than half its range; the
    segment lasts until the input moves again. ``G = (y_end - y_0) / (u_after - u_before)``
    with ``y_end`` the mean of the last tenth of the segment, and ``T`` the time the
    response takes to cover 63.2 % of that change. A segment too short to settle gives a
    rough guess, which is all a starting value has to be.
    """
    t = np.asarray(t, float)
    u = np.asarray(u, float).ravel()
    y = np.asarray(y, float).ravel()
    rng = np.ptp(u)
    if rng == 0:
        return None
    jumps = np.flatnonzero(np.abs(np.diff(u)) > 0.5 * rng)
    if jumps.size == 0:
        return None
    k0 = jumps[0] + 1
    k1 = jumps[1] + 1 if jumps.size > 1 else u.size
    if k1 - k0 < 5:
        return None
    du = u[k0] - u[k0 - 1]
    y0 = y[max(k0 - 1, 0)] if k0 < 3 else float(np.mean(y[max(0, k0 - 3):k0]))
    tail = max(1, (k1 - k0) // 10)
    y_end = float(np.mean(y[k1 - tail:k1]))
    dy = y_end - y0
    if dy == 0:
        return None
    frac = (y[k0:k1] - y0) / dy
    hit = np.flatnonzero(frac >= 0.632)
    if hit.size == 0:
        return None
    T = float(t[k0 + hit[0]] - t[k0 - 1])
    return max(T, t[1] - t[0]), dy / du


def _arx_guess(t, u, y) -> tuple[float, float]:
    """First-order ARX fit ``y[n+1] = a y[n] + c u[n]`` by linear least squares."""
    dt = t[1] - t[0]
    reg = np.column_stack([y[:-1], u[:-1]])
    (a, c), *_ = np.linalg.lstsq(reg, y[1:], rcond=None)
    if not 0 < a < 1:
        raise DataError("cannot find a starting guess: the data do not look like a stable "
                        "first-order response (no step in u, and an ARX fit is unstable)")
    return float(-dt / np.log(a)), float(c / (1 - a))


def fit_first_order(t, u, y, *, hold: str = "zoh", initial_state: str = "fit",
                    confidence: float = 0.95) -> GreyboxReport:
    """Stage 1: fit ``G / (T s + 1)`` to the data (parameters ``T`` [s], ``G``).

    The starting guess is the 63.2 % rule on the first input step (or an ARX fit), the
    refinement least squares over the whole record. With ``initial_state="fit"``
    (default) the speed at ``t[0]`` is estimated too (parameter ``x0[0]``), so a record
    need not start at rest; ``"zero"`` assumes it does.
    """
    n = len(np.atleast_1d(t))
    check_time(t)
    u1 = as_2d(u, "u", n, finite=True)
    y1 = as_2d(y, "y", n, finite=True)
    if u1.shape[1] != 1 or y1.shape[1] != 1:
        raise DataError(f"the DC motor has one input and one output; got u with "
                        f"{u1.shape[1]} and y with {y1.shape[1]} column(s)")
    if n < 10:
        raise DataError(f"data too short: {n} samples (need at least 10)")
    t = np.asarray(t, float)
    guess = step_guess(t, u1[:, 0], y1[:, 0])
    if guess is None or not (guess[0] > 0 and guess[1] != 0):
        guess = _arx_guess(t, u1[:, 0], y1[:, 0])
    T0, G0 = guess
    return fit_greybox(first_order_model, t, u1, y1, {"T": T0, "G": G0}, hold=hold,
                       initial_state=initial_state, bounds={"T": (0.0, np.inf)},
                       log={"G": False}, confidence=confidence)


@dataclass(frozen=True)
class DCMotorResult:
    """Both stages of the DC-motor identification.

    Attributes
    ----------
    T, G : float
        Time constant [s] and gain [rad/s per V] from stage 1.
    T_interval, G_interval : (float, float)
        Their 95 % intervals.
    parameters : dict
        ``J, b, R, k``: value when the data (with what was given) determine it, ``None``
        when it is undetermined.
    representative : dict
        One best-fitting physical parameter set (all four), e.g. for simulation; for
        undetermined parameters it is one of many equally good choices.
    initial_speed : float or None
        Fitted speed at ``t[0]`` [rad/s] (None when the record was assumed to start at
        rest).
    intervals : dict
        95 % interval per parameter (``None`` for given ones and undetermined ones).
    given : tuple of str
        Parameters that were given rather than estimated.
    undetermined : tuple of str
        Named parameter combinations the data do not determine (empty when all are).
    first_order, physical : GreyboxReport
        The full reports of the two stages.
    """

    T: float
    G: float
    T_interval: tuple[float, float]
    G_interval: tuple[float, float]
    parameters: dict[str, float | None]
    representative: dict[str, float]
    initial_speed: float | None
    intervals: dict[str, tuple[float, float] | None]
    given: tuple[str, ...]
    undetermined: tuple[str, ...]
    first_order: GreyboxReport
    physical: GreyboxReport

    def to_dict(self) -> dict:
        """JSON-ready dict (the ``trussid greybox dc-motor --json`` schema)."""
        return {
            "T": self.T,
            "G": self.G,
            "T_interval": list(self.T_interval),
            "G_interval": list(self.G_interval),
            "parameters": dict(self.parameters),
            "intervals": {k: (list(v) if v else None) for k, v in self.intervals.items()},
            "given": list(self.given),
            "undetermined": list(self.undetermined),
            "representative": dict(self.representative),
            "initial_speed": self.initial_speed,
            "spread": {k: list(v) for k, v in self.physical.spread.items()},
            "n_starts": len(self.physical.starts),
            "rms": self.physical.rms,
        }

    def summary(self) -> str:
        units = {"J": "kg m^2", "b": "N m s/rad", "R": "ohm", "k": "N m/A"}
        lines = [
            f"first-order model: T = {self.T:.5g} s  [{self.T_interval[0]:.5g}, "
            f"{self.T_interval[1]:.5g}],  G = {self.G:.5g} rad/s/V  "
            f"[{self.G_interval[0]:.5g}, {self.G_interval[1]:.5g}]  (95 %)",
            "physical parameters:",
        ]
        if self.initial_speed is not None:
            lines.insert(1, f"initial speed (fitted): {self.initial_speed:.4g} rad/s")
        for n in ("J", "b", "R", "k"):
            v = self.parameters[n]
            iv = self.intervals[n]
            if n in self.given:
                lines.append(f"  {n} = {v:.5g} {units[n]}  (given)")
            elif v is None:
                lo, hi = self.physical.spread[n]
                lines.append(f"  {n} undetermined: equally good fits range "
                             f"{lo:.3g} .. {hi:.3g} {units[n]} over the multi-start")
            else:
                lines.append(f"  {n} = {v:.5g} {units[n]}  [{iv[0]:.5g}, {iv[1]:.5g}]")
        if self.undetermined:
            J = self.parameters["J"]
            lines.append(
                f"the data determine only T and G, i.e. R/k = J G / T = {J * self.G / self.T:.4g}"
                f" ohm A/(N m) and b R/k + k = 1/G = {1 / self.G:.4g} V s/rad;"
            )
            lines.append("NOT determined: " + "; ".join(self.undetermined)
                         + " (give R as well to pin down b and k)")
        else:
            lines.append("all parameters determined")
        return "\n".join(lines)


def identify_dc_motor(
    t,
    u,
    y,
    *,
    J: float,
    R: float | None = None,
    hold: str = "zoh",
    initial_state: str = "fit",
    n_starts: int = 8,
    seed: int = 0,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    confidence: float = 0.95,
) -> DCMotorResult:
    """Identify a DC motor: stage 1 (T, G), then the physical parameters.

    Parameters
    ----------
    t, u, y : arrays
        Uniform sample times [s], armature voltage [V], angular speed [rad/s].
    J : float
        Total rotating inertia [kg m^2] (e.g. from :mod:`trussid.geometry.flywheel`).
    R : float, optional
        Armature resistance [ohm], when measured separately. Without it, b, R and k are
        not all determined and the result says so.
    hold : {"zoh", "foh"}
    initial_state : {"fit", "zero"}
        Estimate the speed at ``t[0]`` (default) or assume the record starts at rest.
    n_starts : int
        Starts of the physical stage (seeded Latin hypercube, log-uniform in ``bounds``).
    seed : int
    bounds : mapping, optional
        Bounds for ``b``, ``R``, ``k`` (default :data:`DEFAULT_BOUNDS`).
    confidence : float
        Level of the parameters' confidence intervals [-].

    Returns
    -------
    DCMotorResult
    """
    for name, val in (("J", J), ("R", R)):
        if val is not None and not (np.isfinite(val) and val > 0):
            raise DataError(f"{name} must be a positive number, got {val!r}")
    if bounds:
        unknown = [n for n in bounds if n not in ("b", "R", "k")]
        if unknown:
            raise DataError(f"unknown parameter {unknown[0]!r} in bounds; the DC motor "
                            "has b, R, k (J is given)")
    fo = fit_first_order(t, u, y, hold=hold, initial_state=initial_state,
                         confidence=confidence)
    T, G = fo.estimates["T"], fo.estimates["G"]
    if G <= 0:
        raise DataError(f"the fitted gain G = {G:.3g} is not positive: is the speed "
                        "measured with the sign of the voltage?")
    # A starting point on the curve of exact (T, G) solutions: R/k = J G / T and
    # b = (k/G - k^2)/R, from a nominal R (or the given one).
    R0 = R if R is not None else 1.0
    k0 = J * G * R0 / T
    b0 = max((k0 / G - k0**2) / R0, 1e-6)
    initial = {"J": J, "b": b0, "R": R0, "k": k0}
    given = ("J",) if R is None else ("J", "R")
    bnds = dict(DEFAULT_BOUNDS)
    if bounds:
        bnds.update(bounds)
    for n in given:
        bnds.pop(n, None)
    for n, (lo, hi) in bnds.items():
        if n in initial and n not in given:
            initial[n] = float(np.clip(initial[n], lo, hi)) if lo <= hi else initial[n]
    rep = fit_greybox(physical_model, t, u, y, initial, hold=hold,
                      initial_state=initial_state, bounds=bnds, fixed=given,
                      n_starts=n_starts, seed=seed, confidence=confidence)
    params, intervals = {}, {}
    for n in ("J", "b", "R", "k"):
        if n in given:
            params[n] = float(rep.estimates[n])
            intervals[n] = None
        elif rep.determined[n] and n not in rep.at_bound:
            params[n] = float(rep.estimates[n])
            intervals[n] = rep.intervals[n]
        else:
            params[n] = None
            intervals[n] = None
    return DCMotorResult(
        T=T, G=G, T_interval=fo.intervals["T"], G_interval=fo.intervals["G"],
        parameters=params,
        representative={n: float(rep.estimates[n]) for n in ("J", "b", "R", "k")},
        initial_speed=rep.estimates.get("x0[0]"), intervals=intervals,
        given=given, undetermined=tuple(c.name for c in rep.undetermined),
        first_order=fo, physical=rep,
    )
