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


#: Marker of each stability status in the stabilisation diagram (as modal-analysis software
#: draws them: o new, f frequency, d damping, v vector (shape), s all stable).
STABILITY_MARKERS = {
    "new": dict(marker="o", ms=3.5, mfc="none", color="0.6", label="new pole"),
    "f": dict(marker="_", ms=7, color="C0", label="f: frequency stable"),
    "fd": dict(marker="x", ms=4.5, color="C2", label="d: + damping stable"),
    "fv": dict(marker="^", ms=4, mfc="none", color="C1", label="v: + shape stable (MAC)"),
    "s": dict(marker="+", ms=7, mew=1.6, color="C3", label="s: all stable"),
}


def stabilisation_figure(stab, frf=None, title: str = "stabilisation diagram",
                         fmax: float | None = None):
    """Stabilisation diagram: every pole of every order at its frequency, marked by stability.

    Parameters
    ----------
    stab : trussid.plid.modal.Stabilisation
    frf : (f [Hz], H (n_freq, p, m)), optional
        Drawn behind the poles as the sum over channels of |H| [dB] (right axis), so that
        stable columns can be checked against the resonance peaks.
    title : str
    fmax : float, optional
        Upper frequency limit [Hz] (default: the largest pole or FRF frequency).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = Figure(figsize=(10, 6))
    ax = fig.subplots()
    top = 0.0
    if frf is not None:
        f, H = frf
        ax2 = ax.twinx()
        level = 20 * np.log10(np.sum(np.abs(H), axis=(1, 2)) + 1e-300)
        ax2.plot(f, level, color="0.75", lw=1.0, zorder=0)
        ax2.set_ylabel("sum of |FRF| [dB]", color="0.45")
        ax2.tick_params(axis="y", colors="0.45")
        top = float(np.max(f))
        ax.set_zorder(ax2.get_zorder() + 1)
        ax.patch.set_visible(False)
    seen = set()
    for n, modes, status in zip(stab.orders, stab.modes, stab.status):
        for key, style in STABILITY_MARKERS.items():
            sel = status == key
            if not np.any(sel):
                continue
            st = dict(style)
            label = st.pop("label")
            label = label if key not in seen else None
            seen.add(key)
            ax.plot(modes.frequencies_hz[sel], np.full(int(sel.sum()), n), ls="none",
                    label=label, **st)
            top = max(top, float(np.max(modes.frequencies_hz[sel])))
    ax.set_xlim(0, fmax or top * 1.02 or 1.0)
    ax.set_ylim(min(stab.orders) - 1, max(stab.orders) + 1)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order (states)")
    tol = stab.tolerances
    ax.set_title(f"{title}\nstable: frequency within {100 * tol.get('f', 0):g} %, damping "
                 f"within {100 * tol.get('damping', 0):g} %, MAC >= {tol.get('mac', 0):g} "
                 "against the order below", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8, framealpha=0.9)
    fig.tight_layout()
    return fig


def mac_figure(M, freqs_a=None, freqs_b=None, name_a: str = "set A", name_b: str = "set B",
               title: str = "MAC"):
    """MAC matrix as a colour map with the value in each cell.

    Parameters
    ----------
    M : ndarray, shape (n_a, n_b)
        MAC values (:func:`trussid.plid.modal.mac`).
    freqs_a, freqs_b : array_like, optional
        Frequencies [Hz] of the modes, for the tick labels.
    name_a, name_b : str
        What each set is (axis labels).
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    M = np.asarray(M, dtype=float)
    na, nb = M.shape
    size = max(4.0, 0.45 * max(na, nb) + 2.5)
    fig = Figure(figsize=(size + 1.2, size))
    ax = fig.subplots()
    im = ax.imshow(M, vmin=0.0, vmax=1.0, cmap="viridis", origin="upper", aspect="equal")
    fig.colorbar(im, ax=ax, label="MAC", shrink=0.8)
    if max(na, nb) <= 30:
        for i in range(na):
            for j in range(nb):
                ax.text(j, i, f"{M[i, j]:.2f}", ha="center", va="center", fontsize=7,
                        color="black" if M[i, j] > 0.6 else "white")

    def ticks(freqs, n):
        return [f"{k + 1}" if freqs is None else f"{k + 1}: {freqs[k]:.1f}" for k in range(n)]

    ax.set_yticks(range(na), ticks(freqs_a, na), fontsize=7)
    ax.set_xticks(range(nb), ticks(freqs_b, nb), fontsize=7, rotation=90)
    ax.set_ylabel(f"{name_a} (mode: Hz)")
    ax.set_xlabel(f"{name_b} (mode: Hz)")
    ax.set_title(title)
    fig.tight_layout()
    return fig
