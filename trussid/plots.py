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


def sigma_figure(curves, title: str = "", ylabel: str = "largest singular value"):
    """Largest singular value against frequency; ``curves`` a list of (label, f [Hz],
    H (n_freq, p, m)). The first is drawn grey and wide (open loop), the others in colour."""
    fig = Figure(figsize=(9, 4))
    ax = fig.subplots()
    for k, (label, f, H) in enumerate(curves):
        s = np.linalg.svd(H, compute_uv=False)[:, 0]
        st = dict(color="0.55", lw=2.2) if k == 0 else dict(color=f"C{k - 1}", lw=1.1)
        ax.semilogy(f, s, label=label, **st)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    return fig


def decay_figure(curves, title: str = "", ylabel: str = "impulse response RMS over outputs [dB]"):
    """Decay of impulse responses: ``curves`` a list of (label, t [s], envelope [dB])."""
    fig = Figure(figsize=(9, 4))
    ax = fig.subplots()
    for k, (label, t, e) in enumerate(curves):
        st = dict(color="0.55", lw=1.8) if k == 0 else dict(color=f"C{k - 1}", lw=1.0)
        ax.plot(t, e, label=label, **st)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    return fig


def damping_map_figure(sets, title: str = "poles: frequency and damping",
                       band=(0.0, 800.0)):
    """Poles as frequency [Hz] against damping ratio [%] (log), the view where a 0.25 %
    mode and a 5 % one are far apart. ``sets``: list of (label, frequency_hz, damping,
    marker), drawn in order."""
    fig = Figure(figsize=(9, 5))
    ax = fig.subplots()
    for k, (label, f, z, marker) in enumerate(sets):
        f, z = np.asarray(f), np.asarray(z)
        keep = (f >= band[0]) & (f <= band[1]) & (z > 0)
        kw = dict(mfc="none") if marker == "o" else {}
        ax.semilogy(f[keep], 100 * z[keep], marker, label=label, color=f"C{k}" if k else "k",
                    ms=6 if marker == "o" else 5, **kw)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("damping ratio [%]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    return fig
