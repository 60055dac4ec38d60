"""A finished study as plots and a short markdown page (``trussid study DIR --report``).

- ``modes``: natural frequencies against each varied wall (median over the other
  parameters, min-max band), each mode coloured by its most frequent label;
- ``sensitivities``: median ``df_k/dt_i`` per mode and strut as a map;
- ``identify``: FRF RMS error against noise level and against order, per method;
- ``plant``: peak gain and H2 norm per channel against each varied parameter;

and always the failures (reason and count) and timing per worker. Figures are
:class:`matplotlib.figure.Figure` objects without pyplot (no backend chosen here), saved
atomically by :func:`trussid.plots.save_figure`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from trussid._util.files import atomic_path
from trussid.plots import save_figure
from trussid.study.spec import spec_from_dict
from trussid.study.store import read_study
from trussid.testbed.model import N_STRUTS

MM = 1e-3


def _varied(spec, df, numeric=True):
    out = []
    for a in spec.parameters:
        if a.fixed or a.name not in df:
            continue
        if numeric and not pd.api.types.is_numeric_dtype(df[a.name]):
            continue
        out.append(a.name)
    return out


def _ok(df):
    """The rows of the points that were computed (status "ok")."""
    return df[df["status"] == "ok"] if len(df) else df


def modes_figure(df, walls: list[str], n_modes: int, fmax: float = 400.0, slice_at: dict | None = None,
                 title: str | None = None) -> Figure:
    """Every design's frequencies [Hz] against each wall in ``walls`` [mm], by label.

    One panel per wall ``i``: a dot per design and mode (suspension modes and modes above
    ``fmax`` left out), red when the mode's label names strut ``i``, blue for UDF rigid-body
    modes, grey otherwise; the red line is the median, per wall level, of strut ``i``'s
    lowest own mode. Modes are coloured by their own label in each design (not by their
    index: the strut modes reorder as walls change). ``slice_at`` (``{wall: value}``)
    keeps, in panel ``i``, only the designs whose *other* walls take those values (a
    one-at-a-time sweep).
    """
    ok = _ok(df)
    nc = min(3, len(walls))
    nr = int(np.ceil(len(walls) / nc))
    fig = Figure(figsize=(4.4 * nc + 0.6, 3.6 * nr + 0.9))
    axes = np.atleast_1d(fig.subplots(nr, nc, sharey=True, squeeze=False)).ravel()
    has_labels = "label1" in ok
    F = ok[[f"f{k}" for k in range(1, n_modes + 1)]].to_numpy()
    L = ok[[f"label{k}" for k in range(1, n_modes + 1)]].to_numpy().astype(str) if has_labels else \
        np.full(F.shape, "", dtype=object).astype(str)
    for ax, w in zip(axes, walls):
        i = int(w[4:])
        keep = np.ones(len(ok), bool)
        for other, v in (slice_at or {}).items():
            if other != w and other in ok:
                keep &= np.isclose(ok[other].to_numpy(), v, rtol=1e-12, atol=0.0)
        x = ok[w].to_numpy()[keep] / MM
        f, lab = F[keep], L[keep]
        shown = (f <= fmax) & (lab != "suspension")
        own = np.char.startswith(lab, f"strut {i} ")
        udf = np.char.find(lab, "UDF") >= 0
        xx = np.broadcast_to(x[:, None], f.shape)
        for sel, c, z, ms in ((shown & ~own & ~udf, "0.6", 1, 2.5), (shown & udf, "C0", 2, 2.5),
                              (shown & own, "C3", 3, 4.5)):
            ax.plot(xx[sel], f[sel], ".", ms=ms, color=c, alpha=0.6, zorder=z)
        lowest = np.where(own, f, np.inf).min(axis=1)
        levels = np.unique(x)
        med = [np.median(lowest[(x == v) & np.isfinite(lowest)]) if np.isfinite(lowest[x == v]).any()
               else np.nan for v in levels]
        ax.plot(levels, med, "-", color="C3", lw=1.0, alpha=0.8, zorder=4, label=f"strut {i}: lowest own mode (median)")
        ax.set_xlabel(f"strut {i} wall thickness [mm]")
        ax.set_title(f"strut {i}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    for ax in axes[len(walls):]:
        ax.set_visible(False)
    for ax in axes[::nc]:
        ax.set_ylabel("natural frequency [Hz]")
    fig.suptitle(title or f"Natural frequencies of {len(ok)} designs against each wall (suspension modes "
                 "left out)\nred: modes of that strut, blue: UDF rigid-body, grey: other modes", fontsize=10)
    fig.tight_layout()
    return fig


def sensitivities_figure(df, n_modes: int) -> Figure:
    """Median ``df_k/dt_i`` [Hz per 0.01 mm] as a mode x strut map."""
    ok = _ok(df)
    S = np.array([[ok[f"dfdt{k}_{i}"].median() for i in range(6)] for k in range(1, n_modes + 1)]) * 0.01 * MM
    fig = Figure(figsize=(6.5, 0.32 * n_modes + 1.8))
    ax = fig.subplots()
    lim = np.nanmax(np.abs(S)) or 1.0
    im = ax.imshow(S, cmap="RdBu_r", vmin=-lim, vmax=lim, aspect="auto")
    ax.set_xticks(range(N_STRUTS), [f"strut {i}" for i in range(N_STRUTS)])
    f = [ok[f"f{k}"].median() for k in range(1, n_modes + 1)]
    ax.set_yticks(range(n_modes), [f"{k + 1}: {f[k]:.1f} Hz" for k in range(n_modes)])
    fig.colorbar(im, ax=ax, label="df/dt [Hz per 0.01 mm of wall]")
    ax.set_title(f"Frequency sensitivity to each wall (median of {len(ok)} designs)")
    fig.tight_layout()
    return fig


def _noise_key(v: str) -> float:
    if v.endswith("dB"):
        return float(v[:-2])
    return {"none": np.inf, "12bit": 72.0}.get(v, 0.0)


def identify_figure(df, spec) -> Figure:
    """FRF RMS error [dB] against noise level and order, one series per method."""
    ok = _ok(df)
    by = [c for c in ("noise", "order", "n_samples") if c in _varied(spec, df, numeric=False)] or ["seed"]
    if "seed" not in df:
        by = by if by != ["seed"] else ["point"]
    methods = sorted(ok["method"].unique()) if "method" in ok else [spec.options.get("method", "plid-subspace")]
    fig = Figure(figsize=(5.0 * len(by) + 0.6, 4.2))
    axes = np.atleast_1d(fig.subplots(1, len(by), squeeze=False)).ravel()
    for ax, col in zip(axes, by):
        levels = sorted(ok[col].unique(), key=_noise_key if col == "noise" else None)
        pos = {v: j for j, v in enumerate(levels)}
        for m, method in enumerate(methods):
            sel = ok[ok["method"] == method] if "method" in ok else ok
            x = np.array([pos[v] for v in sel[col]], float) + 0.12 * (m - (len(methods) - 1) / 2)
            ax.semilogy(x, sel["rms_db"], "o", ms=3.5, alpha=0.6, color=f"C{m}")
            med = [sel[sel[col] == v]["rms_db"].median() for v in levels]
            ax.semilogy(np.arange(len(levels)) + 0.12 * (m - (len(methods) - 1) / 2), med, "-",
                        color=f"C{m}", label=method)
        ax.set_xticks(range(len(levels)), [str(v) for v in levels], rotation=30 if len(levels) > 8 else 0)
        ax.set_xlabel(col)
        ax.set_ylabel("FRF magnitude error, RMS over the band [dB]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.suptitle(f"Identification error: {len(ok)} fits (points; line: median)", fontsize=10)
    fig.tight_layout()
    return fig


def plant_figure(df, params: list[str]) -> Figure:
    """Peak gain and H2 norm per channel against each varied parameter."""
    ok = _ok(df)
    fig = Figure(figsize=(4.2 * max(1, len(params)) + 0.6, 7.0))
    axes = fig.subplots(2, max(1, len(params)), squeeze=False)
    for j, p in enumerate(params):
        x = ok[p] / MM if p.startswith("wall") else ok[p]
        for c in (1, 2, 3):
            axes[0, j].semilogy(x, ok[f"peak_gain_ch{c}"], "o", ms=3, color=f"C{c - 1}", label=f"ch{c}")
            axes[1, j].semilogy(x, ok[f"h2_ch{c}"], "o", ms=3, color=f"C{c - 1}", label=f"ch{c}")
        axes[1, j].set_xlabel(f"{p} [mm]" if p.startswith("wall") else p)
        for ax in axes[:, j]:
            ax.grid(alpha=0.3, which="both")
    axes[0, 0].set_ylabel("peak gain [V/V]")
    axes[1, 0].set_ylabel("H2 norm (discrete)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"Testbed plant metrics: {len(ok)} designs", fontsize=10)
    fig.tight_layout()
    return fig


def write_report(out) -> Path:
    """Plots and ``report.md`` of the study in ``out``, under ``out/_report``; its path."""
    meta, df = read_study(out)
    spec = spec_from_dict(meta.spec)
    rdir = Path(out) / "_report"
    rdir.mkdir(exist_ok=True)
    figs = []
    if len(_ok(df)):
        n_modes = spec.options.get("n_modes", 20 if spec.evaluate == "modes" else 12)
        walls = [w for w in _varied(spec, df) if w.startswith("wall")]
        if spec.evaluate == "modes" and walls:
            figs.append(("frequencies.png", "Natural frequencies against each wall",
                         modes_figure(df, walls, n_modes)))
        if spec.evaluate == "sensitivities":
            figs.append(("sensitivities.png", "Wall sensitivities", sensitivities_figure(df, n_modes)))
            if walls:
                figs.append(("frequencies.png", "Natural frequencies against each wall",
                             modes_figure(df, walls, n_modes)))
        if spec.evaluate == "identify":
            figs.append(("identification.png", "Identification error", identify_figure(df, spec)))
        if spec.evaluate == "plant" and _varied(spec, df):
            figs.append(("plant.png", "Plant metrics", plant_figure(df, _varied(spec, df))))
    for name, _, fig in figs:
        save_figure(fig, rdir / name)
    n = len(df)
    ok = len(_ok(df)) if n else 0
    lines = [f"# Study {spec.name}", "",
             f"- evaluate: `{spec.evaluate}`, sampling `{spec.sample}`, spec hash `{meta.hash}`",
             f"- points: {meta.points}; rows saved {n}: {ok} ok, {n - ok} failed"
             + (f", {meta.points - n} missing (run the study again to compute them)" if n < meta.points else ""),
             "- varied: " + (", ".join(f"`{a.name}`" for a in spec.parameters if not a.fixed) or "nothing"), ""]
    if n:
        s = df["seconds"]
        lines += [f"Seconds per point: median {s.median():.4g}, mean {s.mean():.4g}, max {s.max():.4g}; "
                  f"total {s.sum():.4g} s of evaluation on {df['worker'].nunique()} worker process(es).", ""]
    if n - ok:
        lines += ["| failures | reason |", "|---:|---|"]
        for reason, c in df[df["status"] != "ok"]["error"].value_counts().items():
            lines.append(f"| {c} | {reason} |")
        lines.append("")
    for name, title, _ in figs:
        lines += [f"## {title}", "", f"![{title}]({name})", ""]
    path = rdir / "report.md"
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines))
    return path


__all__ = ["write_report", "modes_figure", "sensitivities_figure", "identify_figure", "plant_figure"]
