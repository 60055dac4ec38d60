"""Every figure trussid draws, in one style: Bode overlays, pole maps, convergence, traces.

Figures are :class:`matplotlib.figure.Figure` objects made without pyplot, so drawing one
selects no backend and registers nothing process-wide (a library must not call
``matplotlib.use``); the caller saves them (:func:`save_figure`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from trussid._util.files import atomic_path


def save_figure(fig: Figure, path, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` atomically (the format from the suffix)."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=str(path).rsplit(".", 1)[-1])


def bode_figure(curves, j: int, input_name: str, output_names, title: str = "",
                logx: bool = False):
    """Bode overlay of one input column: one row per output, magnitude and phase.

    Parameters
    ----------
    curves : list of (label, f [Hz], H (n_freq, p, m))
        Drawn in order: the first wide and grey (the reference), the last thin and blue
        (the model), any between in orange, so agreement shows as a blue line inside a grey
        band.
    j : int
        Input column.
    input_name : str
    output_names : list of str
    title : str
    logx : bool
        Logarithmic frequency axis (for bands spanning decades).

    Returns
    -------
    matplotlib.figure.Figure (not attached to pyplot: the caller saves it)
    """
    p = len(output_names)
    fig = Figure(figsize=(10, 2.4 * p + 0.6))
    axes = fig.subplots(p, 2, squeeze=False)
    ref, mid, last = dict(color="0.55", lw=2.4), dict(color="C1", lw=1.4), dict(color="C0", lw=1.0)
    styles = [last] if len(curves) == 1 else [ref] + [mid] * (len(curves) - 2) + [last]
    lo = min(float(np.min(c[1])) for c in curves)
    hi = max(float(np.max(c[1])) for c in curves)
    for i in range(p):
        ax_m, ax_p = axes[i]
        for (label, f, H), st in zip(curves, styles):
            ax_m.semilogy(f, np.abs(H[:, i, j]), label=label, **st)
            ax_p.plot(f, np.degrees(np.angle(H[:, i, j])), **st)
        ax_m.set_ylabel(f"|{output_names[i]}/{input_name}|")
        ax_p.set_ylabel("phase [deg]")
        ax_p.set_ylim(-190, 190)
        for ax in (ax_m, ax_p):
            ax.grid(True, which="both", alpha=0.3)
            if logx:
                ax.set_xscale("log")
            ax.set_xlim(lo, hi)
    axes[0, 0].legend(loc="best", fontsize=8)
    axes[-1, 0].set_xlabel("frequency [Hz]")
    axes[-1, 1].set_xlabel("frequency [Hz]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def pole_map_figure(systems, title: str = "poles (z-plane)"):
    """z-plane pole map with the unit circle; ``systems`` a list of (label, discrete model).

    The first system is drawn as open circles (the reference), later ones as crosses.
    """
    fig = Figure(figsize=(6, 6))
    ax = fig.subplots()
    th = np.linspace(0, 2 * np.pi, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.6", lw=0.8)
    for k, (label, sys_) in enumerate(systems):
        z = np.linalg.eigvals(np.asarray(sys_.A)) if sys_.nstates else np.array([])
        if k == 0 and len(systems) > 1:
            ax.plot(z.real, z.imag, "o", mfc="none", color="k", label=label)
        else:
            ax.plot(z.real, z.imag, "x", color=f"C{(k + 2) % 10}", label=label)
    ax.set_aspect("equal")
    ax.set_xlabel("Re z")
    ax.set_ylabel("Im z")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower left")
    ax.set_title(title)
    return fig


def plant_bode_figure(sys_, title: str = "", f=None):
    """Magnitude [dB] of every channel of a plant, one axis, log frequency.

    Parameters
    ----------
    sys_ : control.StateSpace
        Discrete (up to Nyquist) or continuous (up to twice its highest natural frequency).
    title : str
    f : array [Hz], optional
        Frequencies (default 2000 log-spaced).
    """
    dt = float(sys_.dt or 0.0)
    if f is None:
        w_max = np.max(np.abs(np.linalg.eigvals(np.asarray(sys_.A)))) if sys_.nstates else 1.0
        f_hi = 0.5 / dt if dt else max(2 * w_max / (2 * np.pi), 1.0)
        f = np.geomspace(f_hi * 1e-3, f_hi * 0.999, 2000)
    s = np.exp(2j * np.pi * f * dt) if dt else 2j * np.pi * f
    H = np.asarray(sys_(s)).reshape(sys_.noutputs, sys_.ninputs, -1)
    fig = Figure(figsize=(9, 5))
    ax = fig.subplots()
    for i, yo in enumerate(sys_.output_labels):
        for j, ui in enumerate(sys_.input_labels):
            ax.semilogx(f, 20 * np.log10(np.abs(H[i, j]) + 1e-300), lw=0.9,
                        label=f"{ui} -> {yo}")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("magnitude [dB, output units per input unit]")
    if title:
        ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=3)
    fig.tight_layout()
    return fig


def order_figure(rows, title: str = "order selection"):
    """Validation prediction ratio and FRF change against model order.

    Parameters
    ----------
    rows : list of :class:`trussid.plid.order.OrderRow`
    """
    n = [r.order for r in rows]
    fig = Figure(figsize=(7, 5.5))
    ax = fig.subplots(2, 1, sharex=True)
    ax[0].plot(n, [r.prediction_db for r in rows], "o-", color="C0")
    bad = [r for r in rows if r.unstable_poles]
    if bad:
        ax[0].plot([r.order for r in bad], [r.prediction_db for r in bad], "x", color="C3",
                   ms=10, label="unstable model")
        ax[0].legend(loc="best", fontsize=8)
    ax[0].set_ylabel("one-step prediction,\nvalidation data [dB]")
    ax[0].grid(True, alpha=0.3)
    ch = [(r.order, r.frf_change_db) for r in rows if r.frf_change_db is not None]
    if ch:
        ax[1].semilogy([c[0] for c in ch], [c[1] for c in ch], "s-", color="C1")
    ax[1].set_ylabel("FRF change from the\nprevious order [dB RMS]")
    ax[1].set_xlabel("model order (states)")
    ax[1].grid(True, which="both", alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    return fig
