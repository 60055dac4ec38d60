"""Every figure trussid draws, in one style: Bode overlays, pole maps, convergence, traces.

Figures are :class:`matplotlib.figure.Figure` objects made without pyplot, so drawing one
selects no backend and registers nothing process-wide (a library must not call
``matplotlib.use``); the caller saves them (:func:`save_figure`).
"""

from __future__ import annotations

import control
import numpy as np
from matplotlib.figure import Figure

from trussid._util.files import atomic_path
from trussid.plid.evaluate import frf_grid
from trussid.plid.frf import frequency_response
from trussid.plid.metrics import modal_parameters, one_step_predict
from trussid.plid.uncertainty import Z95


def save_figure(fig: Figure, path, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` atomically (the format from the suffix)."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=str(path).rsplit(".", 1)[-1])


def bode_figure(curves, j: int, input_name: str, output_names, title: str = "",
                logx: bool = False, excited=None, unit: str = ""):
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
    excited : (float, float), optional
        The excited band [Hz], shaded; outside it a nonparametric estimate is noise.
    unit : str
        Unit of the magnitude (e.g. ``"V/V"``), on its axis; empty: "(model units)".

    Returns
    -------
    matplotlib.figure.Figure (not attached to pyplot: the caller saves it)

    Notes
    -----
    Drawn here rather than with :func:`control.bode_plot`: that function lays a MIMO system
    out as one grid of every input/output pair on pyplot's current figure, while a report
    wants one figure per input with a nonparametric estimate on its own frequency grid
    overlaid, on a linear frequency axis, without touching pyplot's state.
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
        ax_m.set_ylabel(f"|{output_names[i]}/{input_name}| [{unit or 'model units'}]")
        ax_p.set_ylabel("phase [deg]")
        ax_p.set_ylim(-190, 190)
        for ax in (ax_m, ax_p):
            ax.grid(True, which="both", alpha=0.3)
            if excited is not None:
                ax.axvspan(*excited, color="C2", alpha=0.06, lw=0,
                           label="excited band" if ax is axes[0, 0] else None)
            if logx:
                ax.set_xscale("log")
            ax.set_xlim(lo, hi)
    axes[-1, 0].set_xlabel("frequency [Hz]")
    axes[-1, 1].set_xlabel("frequency [Hz]")
    if title:
        fig.suptitle(title)
    # one legend above the panels: inside, "best" still lands on a resonance peak
    handles, labels = axes[0, 0].get_legend_handles_labels()
    top = 1.0 - 0.55 / fig.get_figheight()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, top), ncol=4,
               fontsize=8, frameon=False)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, top - 0.25 / fig.get_figheight()))
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


def bode_overlay(truth, estimate, model, input_names, output_names, band, title, excited=None,
                 unit: str = ""):
    """One Bode overlay figure per input: true plant, nonparametric estimate, model.

    Parameters
    ----------
    truth, model : control.StateSpace
        Same inputs and outputs.
    estimate : trussid.plid.frf.FRF
        E.g. the H1 estimate of the identification record.
    input_names, output_names : list of str
    band : (float, float)
        Plotted band [Hz].
    title : str
    excited : (float, float), optional
        The excited band [Hz], shaded: outside it the estimate is noise.
    unit : str
        Unit of the magnitude (e.g. ``"V/V"``).
    """
    f = frf_grid(truth, band, 1500)
    Ht = frequency_response(truth, f)
    Hm = frequency_response(model, f)
    h1_est = estimate
    keep = (h1_est.f >= band[0]) & (h1_est.f <= band[1])
    figs = []
    for j, name in enumerate(input_names):
        curves = [("true plant", f, Ht), (f"H1 estimate ({h1_est.n_averages} averages)",
                                          h1_est.f[keep], h1_est.H[keep]),
                  ("identified model", f, Hm)]
        figs.append(bode_figure(curves, j, name, output_names, title=f"{title}, input {name}",
                                excited=excited, unit=unit))
    return figs


def pole_zero_figure(model, truth, band, title, collocated: int = 0, excited=None):
    """z-plane poles and zeros near the unit circle, and a frequency-damping map.

    The frequency-damping map runs to Nyquist, so that lightly damped poles outside the
    band are seen too; ``excited`` (Hz) is shaded there.

    Zeros are those of the collocated channel (the first input to output ``collocated``),
    the transfer function whose zeros interlace its poles; poles are those of the whole
    model. ``truth`` has the model's inputs and outputs.
    """
    fig = Figure(figsize=(12, 5.6))
    ax, ax2 = fig.subplots(1, 2)
    dt = model.dt
    tcols = truth
    zp_t = np.linalg.eigvals(np.asarray(tcols.A))
    zp_m = np.linalg.eigvals(np.asarray(model.A))
    j = collocated
    with np.errstate(all="ignore"):  # zeros at infinity of the strictly proper channel
        zz_t = np.asarray(control.zeros(control.ss(tcols.A, tcols.B[:, :1], tcols.C[j:j + 1],
                                                   tcols.D[j:j + 1, :1], dt)))
        zz_m = np.asarray(control.zeros(control.ss(model.A, model.B[:, :1], model.C[j:j + 1],
                                                   model.D[j:j + 1, :1], dt)))
    th = np.linspace(0, 2 * np.pi * band[1] * dt, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.6", lw=0.8, label="unit circle (0-%g Hz)" % band[1])
    ax.plot(zp_t.real, zp_t.imag, "o", mfc="none", color="0.35", ms=8, label="true poles")
    ax.plot(zz_t.real, zz_t.imag, "s", mfc="none", color="C2", ms=7,
            label=f"true zeros (ch{j + 1} to acc{j + 1})")
    ax.plot(zp_m.real, zp_m.imag, "x", color="C3", ms=7, label="identified poles")
    ax.plot(zz_m.real, zz_m.imag, "+", color="C0", ms=9, label="identified zeros")
    # The lightly damped modes sit on the unit circle between 0 and the band's edge: zoom,
    # wide enough that no marker of the upper half near the circle is cut by the frame.
    a_hi = 2 * np.pi * band[1] * dt
    pts = np.concatenate([zp_t, zz_t, zp_m, zz_m])
    pts = pts[np.isfinite(pts) & (pts.imag >= -0.05) & (np.abs(pts) < 1.3)]
    x_lo = min(min(np.cos(a_hi), 0.2) - 0.15, float(pts.real.min(initial=0.0)) - 0.08)
    y_hi = max(np.sin(min(a_hi, np.pi / 2)) + 0.15, float(pts.imag.max(initial=0.0)) + 0.08)
    ax.set_xlim(x_lo, max(1.12, float(pts.real.max(initial=0.0)) + 0.08))
    ax.set_ylim(-0.12, y_hi)
    ax.set_aspect("equal")
    ax.set_xlabel("Re z")
    ax.set_ylabel("Im z")
    ax.grid(True, alpha=0.3)
    # below the plane: inside, the legend covered poles of the zoomed half-circle
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=3, fontsize=8,
              frameon=False)
    ax.set_title("z-plane, upper half near the unit circle")
    ft, zt, _ = modal_parameters(tcols)
    fm, zm, _ = modal_parameters(model)
    nyq = 0.5 / dt
    sel_t = (ft > 1) & (ft <= nyq)
    sel_m = (fm > 1) & (fm <= nyq)
    if excited is not None:
        ax2.axvspan(*excited, color="C2", alpha=0.08, lw=0, label="excited band")
    # a margin on each side: a marker at 0 Hz, at Nyquist or at the extreme damping would
    # be cut in half by the frame
    ax2.set_xlim(-0.02 * nyq, 1.02 * nyq)
    zt_, zm_ = np.maximum(zt[sel_t], 1e-5), np.clip(zm[sel_m], 1e-5, None)
    ax2.semilogy(ft[sel_t], zt_, "o", mfc="none", color="0.35", ms=8, label="true modes")
    ax2.semilogy(fm[sel_m], zm_, "x", color="C3", ms=7, label="identified")
    zs = np.concatenate([zt_, zm_])
    if zs.size:
        ax2.set_ylim(zs.min() / 2.0, zs.max() * 2.0)
    ax2.set_xlabel("frequency [Hz]")
    ax2.set_ylabel("damping ratio")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(loc="upper right", fontsize=8)
    ax2.set_title("modes: frequency and damping")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def convergence_figure(fits: dict, fs: float, y_rms: dict):
    """Innovations (moving RMS relative to the output RMS) and parameter change per sample.

    Parameters
    ----------
    fits : dict
        Name -> object with ``innovations`` (N, p), ``theta_history`` (k, q) and
        ``history_index`` (k,) of a PLID pass.
    fs : float
        Sample rate [Hz].
    y_rms : dict
        Name -> RMS of each output over the record.
    """
    fig = Figure(figsize=(10, 7))
    a1, a2 = fig.subplots(2, 1, sharex=True)
    w = max(int(round(0.1 * fs)), 1)  # 0.1 s windows
    for k, (name, fit) in enumerate(fits.items()):
        e = fit.innovations
        if e.size:
            nwin = e.shape[0] // w
            ms = np.mean((e[: nwin * w] ** 2).reshape(nwin, w, -1), axis=1)
            rel = np.mean(ms / y_rms[name][None, :] ** 2, axis=1)
            t = (np.arange(nwin) + 0.5) * w / fs
            a1.plot(t, 10 * np.log10(rel), color=f"C{k}", label=name)
        h, idx = fit.theta_history, fit.history_index
        if h.shape[0] >= 2:
            step = np.diff(idx)
            change = np.linalg.norm(np.diff(h, axis=0), axis=1) / step
            scale = max(np.linalg.norm(h[-1]), 1e-300)
            a2.semilogy(idx[1:] / fs, np.maximum(change / scale, 1e-18), color=f"C{k}",
                        lw=0.8, label=name)
    a1.set_ylabel("innovation / output power [dB]")
    a1.grid(True, alpha=0.3)
    a1.legend(loc="upper right", fontsize=8)
    a1.set_title("PLID convergence on the identification records: innovation power in 0.1 s "
                 "windows", fontsize=11)
    a2.set_ylabel("parameter change per sample")
    a2.set_title(r"relative change $\|\theta_k - \theta_{k-10}\| \,/\, (10\, \|\theta_{final}\|)$",
                 fontsize=11)
    a2.set_xlabel("time in the record [s]")
    a2.grid(True, which="both", alpha=0.3)
    a2.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig


def trace_figure(model, K, data, cols, title: str, seconds=(2.0, 2.25)):
    """Measured versus one-step predicted sensor signals on (validation) data.

    ``data`` is a :class:`trussid.plid.data.IOData`; ``cols`` the inputs the model has.
    """
    d = data
    yhat = one_step_predict(model, d.u[:, cols], d.y, K=K)
    k0, k1 = int(seconds[0] * d.fs), int(seconds[1] * d.fs)
    k0, k1 = min(k0, d.n_samples - 2), min(k1, d.n_samples)
    t = np.arange(k0, k1) / d.fs
    p = d.y.shape[1]
    fig = Figure(figsize=(10, 2.3 * p + 0.6))
    axes = fig.subplots(p, 1, sharex=True, squeeze=False)
    for i in range(p):
        ax = axes[i, 0]
        ax.plot(t, d.y[k0:k1, i], color="0.5", lw=2.2, label="measured (A/D)")
        ax.plot(t, yhat[k0:k1, i], color="C0", lw=1.0, label="one-step predicted")
        ax.plot(t, 10 * (d.y - yhat)[k0:k1, i], color="C3", lw=0.8,
                label="prediction error x 10")
        ax.set_ylabel(f"{d.output_names[i]} [V]")
        ax.grid(True, alpha=0.3)
    # above the first panel: inside it, the legend covered the signals
    axes[0, 0].legend(loc="lower right", bbox_to_anchor=(1.0, 1.02), fontsize=8, ncol=3,
                      frameon=False)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def order_figure(rows):
    """One-step prediction ratio and FRF change against model order.

    ``rows`` are :class:`trussid.plid.order.OrderRow` (``order``, ``prediction_db``,
    ``frf_change_db``).
    """
    n = [r.order for r in rows]
    fig = Figure(figsize=(6, 5))
    ax = fig.subplots(2, 1, sharex=True)
    ax[0].plot(n, [r.prediction_db for r in rows], "o-")
    ax[0].set_ylabel("one-step [dB]")
    ax[0].set_title("one-step prediction ratio", fontsize=10)
    ax[0].grid(True, alpha=0.3)
    ch = [(r.order, r.frf_change_db) for r in rows if r.frf_change_db is not None]
    if ch:
        ax[1].plot([c[0] for c in ch], [c[1] for c in ch], "s-")  # dB: already logarithmic
    ax[1].set_ylabel("RMS change [dB]")
    ax[1].set_title("FRF change from the previous order", fontsize=10)
    ax[1].set_xlabel("order")
    ax[1].grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def plant_bode_figure(plant: control.StateSpace, title: str = ""):
    """Magnitude [dB] and unwrapped phase of every channel of a discrete plant, 1 Hz to
    Nyquist on a log axis, channels labelled by their signal names."""
    fs = 1.0 / plant.dt
    f = np.geomspace(1.0, 0.5 * fs, 3000)
    H = frequency_response(plant, f)  # (nf, p, m)
    fig = Figure(figsize=(9, 6.5))
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    for i, yo in enumerate(plant.output_labels):
        for j, ui in enumerate(plant.input_labels):
            ax1.semilogx(f, 20 * np.log10(np.abs(H[:, i, j])), lw=0.9, label=f"{ui} -> {yo}")
            ax2.semilogx(f, np.degrees(np.unwrap(np.angle(H[:, i, j]))), lw=0.9)
    ax1.set_ylabel("magnitude [dB]")
    ax2.set_ylabel("phase [deg]")
    ax2.set_xlabel("frequency [Hz]")
    ax1.set_title(title or f"plant, ZOH at {fs:g} Hz")
    ax1.legend(fontsize=7, ncol=3)
    for ax in (ax1, ax2):
        ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
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
    stab : trussid.plid.stabilisation_diagram.Stabilisation
    frf : (f [Hz], H (n_freq, p, m)), optional
        Drawn behind the poles as the sum over channels of ``|H|`` [dB] (right axis), so that
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
    # 95 % frequency intervals as horizontal error bars (no caps: they would be lines)
    stds = getattr(stab, "frequency_std", None) or []
    bars = False
    for n, modes, fstd in zip(stab.orders, stab.modes, stds):
        ok = np.isfinite(fstd)
        if np.any(ok):
            ax.errorbar(modes.frequencies_hz[ok], np.full(int(ok.sum()), n),
                        xerr=Z95 * fstd[ok], fmt="none", ecolor="0.35", elinewidth=0.9,
                        capsize=0, zorder=1,
                        label=None if bars else "95 % frequency interval")
            bars = True
    ax.set_xlim(0, fmax or top * 1.02 or 1.0)
    ax.set_ylim(min(stab.orders) - 1, max(stab.orders) + 1)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order (states)")
    tol = stab.tolerances
    ax.set_title(f"{title}\nstable: frequency within {100 * tol.get('f', 0):g} %, damping "
                 f"within {100 * tol.get('damping', 0):g} %, MAC >= {tol.get('mac', 0):g} "
                 "against the order below", fontsize=10)
    ax.grid(True, alpha=0.3)
    # below the axes: inside, it hides the poles of the highest orders
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=5, fontsize=8,
              frameon=False)
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
