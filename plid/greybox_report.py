"""What a grey-box fit returns and takes: :class:`GreyboxReport` (estimates, intervals,
identifiability, multi-start spread) with its :class:`StartResult` and :class:`Combination`
rows, and the :class:`Constraint` a fit may be given (:mod:`trussid.plid.greybox`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Constraint", "Combination", "StartResult", "GreyboxReport", "STRUCTURAL_RTOL",
           "INVOLVEMENT_TOL"]

#: Relative singular value below which a direction counts as structurally undetermined
#: (finite-difference noise of an exactly invisible direction sits near 1e-8).
STRUCTURAL_RTOL = 1e-6
#: A parameter whose component in a unit null direction exceeds this is undetermined.
INVOLVEMENT_TOL = 1e-2


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
