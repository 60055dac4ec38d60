"""What model updating takes and gives: identified modes and the update report."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["IdentifiedModes", "UpdateReport"]


@dataclass(frozen=True)
class IdentifiedModes:
    """Modes extracted from an identified model (or given by the user).

    Attributes
    ----------
    frequencies_hz : (k,) float
        Natural frequencies [Hz], ascending.
    damping : (k,) float
        Damping ratios [-].
    shapes : (p, k) complex or None
        Mode shapes at the model's outputs (``C v``), unit norm.
    strength : (k,) float
        Peak modal contribution ``|C v| |w^H B| / |Re s|`` (largest singular value of the
        mode's residue over its half-power bandwidth), to tell real modes from noise modes.
    frequency_std_hz, damping_std : (k,) float or None
        Standard deviations of the estimates.
    output_names : tuple of str
    """

    frequencies_hz: np.ndarray
    damping: np.ndarray
    shapes: np.ndarray | None = None
    strength: np.ndarray | None = None
    frequency_std_hz: np.ndarray | None = None
    damping_std: np.ndarray | None = None
    output_names: tuple = ()

    def select(self, idx) -> "IdentifiedModes":
        """The modes at indices ``idx``."""
        idx = np.asarray(idx, dtype=int)

        def pick(a, axis=0):
            return None if a is None else np.take(a, idx, axis=axis)

        return IdentifiedModes(self.frequencies_hz[idx], self.damping[idx], pick(self.shapes, 1),
                               pick(self.strength), pick(self.frequency_std_hz), pick(self.damping_std),
                               self.output_names)


@dataclass
class UpdateReport:
    """Result of :func:`update_walls`.

    Attributes
    ----------
    walls, nominal : (6,) float
        Updated and nominal wall thicknesses [m].
    intervals : (6, 2) float
        ``confidence`` intervals [m]; NaN where none (wall on a bound, undetermined).
    std_log : (6,) float
        Standard error of ``ln t`` (NaN where none).
    interval_source : str
        ``"known sigma"`` (from ``frequency_std_hz``) or ``"residual scatter"``.
    measured_hz : (k,) float
        All measured frequencies given.
    used : (k,) bool
        Measured modes paired with a model mode (the others could not be reached).
    pairing : (k,) int
        Index (ascending order, at the updated walls) of the paired model mode; -1 unused.
    model_hz : (k,) float
        Paired model frequencies at the updated walls (NaN unused).
    nominal_hz : (k,) float
        Paired model frequencies at the nominal walls (NaN unused).
    labels : list of str
        Labels of the paired model modes (:func:`trussid.testbed.labels.label_testbed_modes`), "" unused.
    mac : (k,) float or None
        MAC of each pair when shapes were given.
    chi2, dof, birge : float, int, float
        ``sum r^2`` at the estimate (residuals in sigma units, or relative without sigma),
        degrees of freedom, ``sqrt(chi2 / dof)``.
    damping, damping_interval : float or None, (2,) or None
        Modal damping estimate and its interval.
    greybox : plid.greybox.GreyboxReport
        Stage-2 fit (full model).
    coarse : plid.greybox.GreyboxReport
        Stage-1 fit (reduced model, multi-start).
    confidence : float
    sigma_hz : (k,) float or None
        Frequency standard deviations used in the fit [Hz] (stated, with the
        unresolved-mode term), NaN for unused modes; None without stated sigmas.
    unresolved_hz : (k,) float or None
        The unresolved-close-mode part of ``sigma_hz``.
    """

    walls: np.ndarray
    nominal: np.ndarray
    intervals: np.ndarray
    std_log: np.ndarray
    interval_source: str
    measured_hz: np.ndarray
    used: np.ndarray
    pairing: np.ndarray
    model_hz: np.ndarray
    nominal_hz: np.ndarray
    labels: list
    mac: np.ndarray | None
    chi2: float
    dof: int
    birge: float
    damping: float | None
    damping_interval: tuple | None
    greybox: object
    coarse: object
    confidence: float = 0.95
    sigma_hz: np.ndarray | None = None
    unresolved_hz: np.ndarray | None = None
    info: dict = field(default_factory=dict)

    def covers(self, truth) -> np.ndarray:
        """Whether each interval contains ``truth`` (False where there is none)."""
        t = np.asarray(truth, float)
        lo, hi = self.intervals[:, 0], self.intervals[:, 1]
        return np.isfinite(lo) & (lo <= t) & (t <= hi)

    def table(self, truth=None) -> str:
        """Walls (in inches and relative to nominal) and the mode pairs, as text."""
        inch = 0.0254
        pct = f"{100 * self.confidence:g} %"
        head = f"{'strut':>5} {'nominal [in]':>13} {'updated [in]':>13} {pct + ' interval [in]':>26}"
        if truth is not None:
            head += f" {'true [in]':>11} {'rel. error':>11} {'covered':>8}"
        lines = [f"walls ({self.interval_source} intervals)", head]
        for i in range(6):
            lo, hi = self.intervals[i]
            iv = f"[{lo / inch:.5f}, {hi / inch:.5f}]" if np.isfinite(lo) else "-"
            row = f"{i:>5} {self.nominal[i] / inch:>13.5f} {self.walls[i] / inch:>13.5f} {iv:>26}"
            if truth is not None:
                t = float(np.asarray(truth)[i])
                row += (f" {t / inch:>11.5f} {self.walls[i] / t - 1:>+11.2e}"
                        f" {'yes' if self.covers(truth)[i] else 'NO':>8}")
            lines.append(row)
        lines.append("")
        lines.append(f"{'mode':>4} {'measured [Hz]':>14} {'nominal [Hz]':>13} {'updated [Hz]':>13}"
                     f"{'  MAC' if self.mac is not None else ''}  model mode")
        for k in range(len(self.measured_hz)):
            if not self.used[k]:
                lines.append(f"{k:>4} {self.measured_hz[k]:>14.4f} {'-':>13} {'-':>13}  not paired")
                continue
            mac = f" {self.mac[k]:.3f}" if self.mac is not None else ""
            lines.append(f"{k:>4} {self.measured_hz[k]:>14.4f} {self.nominal_hz[k]:>13.4f} "
                         f"{self.model_hz[k]:>13.4f}{mac}  {self.labels[k]}")
        lines.append(f"chi2 {self.chi2:.4g} on {self.dof} dof (Birge ratio {self.birge:.3g})")
        if self.damping is not None:
            iv = self.damping_interval
            lines.append(f"modal damping {100 * self.damping:.4f} % "
                         f"[{100 * iv[0]:.4f}, {100 * iv[1]:.4f}] %")
        amb = self.info.get("ambiguous_swaps") or []
        if amb:
            lines.append("exchanging the walls of struts " + ", ".join(f"{i}<->{j}" for i, j in amb)
                         + " fits as well: these modes do not tell those struts apart")
        und = getattr(self.greybox, "undetermined", ())
        if und:
            lines.append("NOT determined by these modes: " + "; ".join(c.name for c in und))
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        def fl(a):
            return [None if not np.isfinite(v) else float(v) for v in np.ravel(a)]

        return {
            "walls": fl(self.walls), "nominal": fl(self.nominal),
            "intervals": [fl(r) for r in self.intervals], "interval_source": self.interval_source,
            "measured_hz": fl(self.measured_hz), "used": [bool(u) for u in self.used],
            "pairing": [int(p) for p in self.pairing], "model_hz": fl(self.model_hz),
            "labels": list(self.labels), "chi2": self.chi2, "dof": self.dof, "birge": self.birge,
            "damping": self.damping,
            "damping_interval": None if self.damping_interval is None else list(self.damping_interval),
            "undetermined": [c.name for c in getattr(self.greybox, "undetermined", ())],
            "ambiguous_swaps": [list(ij) for ij in self.info.get("ambiguous_swaps") or []],
        }
