"""The demo's report as one page to explore (``report.html``, beside ``report.md``).

Made from the same typed summary (:class:`trussid.campaign.summary.DemoSummary`) as
``report.md``: the page holds the report's own Markdown rendered as HTML (every number and
table of ``report.md``), with each figure replaced by the same figure drawn interactively
(zoom, pan, hover readouts, legend entries that hide a curve), and in front of it:

- the structure in 3-D (:mod:`trussid.fem.render_html`): pick a mode, watch it move, rotate
  and zoom; the FE modes and, at the sensors, the identified modes with their MAC against
  the FE ones (the summary's ``mode_checks``, shapes from the model files);
- a Bode explorer: per channel pair, the true plant, the H1 estimate of every record that
  drives the input and every identified model that has it, from the files the demo wrote
  (``plant_true.npz``, ``model_*.npz``, ``data_*_ide.npz``);
- the identified modes with their 95 % intervals as error bars (the summary's
  ``mode_checks``).

One self-contained file (plotly.js inline, no ``src``/``href`` outside the file): it opens
offline, from an e-mail attachment or a CI artefact. The figures are drawn when they
scroll into view, after the page's load event (the 3-D view too), so the page opens in about
the time the browser needs to parse plotly.js and the data, and the figures follow.

Why convert the report's own matplotlib figures (:func:`figure_data`) instead of drawing
every figure twice: the page then shows exactly the curves of ``report.md``'s PNGs, the
closed-loop and adaptive sections' figures included, with one drawing code per figure.
plotly's own converter (``plotly.tools.mpl_to_plotly``) is unmaintained and fails on current
matplotlib, hence the small converter here for what the report draws (lines, markers,
shaded spans, log axes).
"""

from __future__ import annotations

import base64
import html
import json
import re
from pathlib import Path

import numpy as np
from markdown_it import MarkdownIt
from matplotlib.colors import to_hex

from trussid._util.files import atomic_path
from trussid.campaign.summary import DemoSummary
from trussid.fem.render_html import (IdentifiedMode, SensorAxis, html_page, mode_viewer_data,
                                     viewer_fragment)
from trussid.plid.datafile import read_data
from trussid.plid.evaluate import frf_grid
from trussid.plid.frf import frequency_response, h1
from trussid.plid.modal import modal_table
from trussid.plid.modelfile import load_model
from trussid.testbed.labels import label_testbed_modes
from trussid.testbed.plant import TestbedPlant, accelerometers

__all__ = ["figure_data", "bode_explorer", "interval_figure", "structure_viewer",
           "report_html", "write_report_html"]

#: matplotlib marker -> plotly symbol (the markers trussid.plots uses).
_SYMBOLS = {"o": "circle", "x": "x-thin", "+": "cross-thin", "s": "square", "^": "triangle-up",
            "v": "triangle-down", "_": "line-ew", "|": "line-ns", "D": "diamond", ".": "circle",
            "d": "diamond"}
_DASHES = {"-": "solid", "--": "dash", ":": "dot", "-.": "dashdot"}


def _typed(a) -> dict:
    """A numeric array as plotly.js's typed-array spec (base64 float32): a third of the size
    of JSON numbers, and parsed without a number parser."""
    a = np.ascontiguousarray(np.asarray(a, dtype=float), dtype="<f4")
    return {"dtype": "f4", "bdata": base64.b64encode(a.tobytes()).decode("ascii")}


def _axis_range(lim, log: bool):
    lo, hi = sorted(float(v) for v in lim)
    if log:
        lo, hi = np.log10(max(lo, 1e-300)), np.log10(max(hi, 1e-300))
    return [float(lo), float(hi)]


def _line_trace(line, k: int, xlabel: str, ylabel: str) -> dict | None:
    x = np.asarray(line.get_xdata(), dtype=float)
    y = np.asarray(line.get_ydata(), dtype=float)
    if x.size == 0:
        return None
    label = str(line.get_label())
    colour = to_hex(line.get_color())
    ls, marker = line.get_linestyle(), line.get_marker()
    has_line = ls not in ("None", "none", "", " ")
    has_marker = marker not in (None, "None", "none", "", " ")
    t = {"type": "scatter", "x": _typed(x), "y": _typed(y), "xaxis": f"x{k}", "yaxis": f"y{k}",
         "mode": "+".join(m for m, on in (("lines", has_line), ("markers", has_marker)) if on)
         or "lines",
         "hovertemplate": f"{html.escape(xlabel or 'x')}: %{{x:.5g}}<br>"
                          f"{html.escape(ylabel or 'y')}: %{{y:.5g}}<extra>"
                          f"{html.escape(label if not label.startswith('_') else '')}</extra>"}
    if has_line:
        t["line"] = {"color": colour, "width": max(0.6, 1.2 * line.get_linewidth()),
                     "dash": _DASHES.get(ls, "solid")}
    if has_marker:
        sym = _SYMBOLS.get(str(marker), "circle")
        face = line.get_markerfacecolor()
        hollow = isinstance(face, str) and face.lower() == "none"
        if hollow and sym in ("circle", "square", "triangle-up", "triangle-down", "diamond"):
            sym += "-open"
        t["marker"] = {"symbol": sym, "size": max(4.0, 1.2 * line.get_markersize()),
                       "color": colour, "line": {"color": colour,
                                                 "width": max(1.0, line.get_markeredgewidth())}}
    if not label.startswith("_"):
        t["name"], t["legendgroup"] = label, label
    else:
        t["showlegend"] = False
    return t


def _span_shapes(ax, k: int) -> list:
    """Shaded spans (``axvspan``) as plotly shapes over the full height of the axes."""
    shapes = []
    for p in ax.patches:
        verts = p.get_transform().transform(p.get_path().vertices)
        if not len(verts):
            continue
        data = ax.transData.inverted().transform(verts)
        x0, x1 = float(np.nanmin(data[:, 0])), float(np.nanmax(data[:, 0]))
        face = p.get_facecolor()
        shapes.append({"type": "rect", "xref": f"x{k}", "yref": f"y{k} domain", "x0": x0,
                       "x1": x1, "y0": 0, "y1": 1, "line": {"width": 0},
                       "fillcolor": to_hex(face), "opacity": float(face[3]), "layer": "below"})
    return shapes


def figure_data(fig) -> dict:
    """A matplotlib figure of :mod:`trussid.plots` as a plotly figure (``{"data", "layout"}``):
    each axes at its place in the figure, its lines and markers with their colours and
    labels, log axes, limits, axis labels and titles, shaded spans; curves with the same
    legend label are one legend entry (clicking it hides them in every panel)."""
    # Long: one pass over the axes, each converted in the same few steps.
    data, layout, shapes, notes = [], {}, [], []
    seen = set()
    axes = [a for a in fig.axes if a.get_visible() and not hasattr(a, "_colorbar")]
    for k, ax in enumerate(axes, start=1):
        bb = ax.get_position()
        xl, yl = ax.get_xlabel(), ax.get_ylabel()
        xlog, ylog = ax.get_xscale() == "log", ax.get_yscale() == "log"
        sfx = "" if k == 1 else str(k)
        layout[f"xaxis{sfx}"] = {"domain": [max(bb.x0, 0.0), min(bb.x1, 1.0)],
                                 "anchor": f"y{k}" if k > 1 else "y",
                                 "type": "log" if xlog else "linear",
                                 "range": _axis_range(ax.get_xlim(), xlog),
                                 "title": {"text": xl, "standoff": 4}, "showgrid": True,
                                 "zeroline": False, "automargin": False}
        layout[f"yaxis{sfx}"] = {"domain": [max(bb.y0, 0.0), min(bb.y1, 1.0)],
                                 "anchor": f"x{k}" if k > 1 else "x",
                                 "type": "log" if ylog else "linear",
                                 "range": _axis_range(ax.get_ylim(), ylog),
                                 "title": {"text": yl.replace("\n", "<br>"), "standoff": 4},
                                 "showgrid": True, "zeroline": False, "exponentformat": "power"}
        if ax.get_aspect() == 1.0 and not (xlog or ylog):
            layout[f"yaxis{sfx}"]["scaleanchor"] = f"x{k}" if k > 1 else "x"
        title = ax.get_title()
        if title:
            notes.append({"text": title.replace("\n", "<br>"), "xref": "paper", "yref": "paper",
                          "x": 0.5 * (bb.x0 + bb.x1), "y": bb.y1, "yanchor": "bottom",
                          "showarrow": False, "font": {"size": 12}})
        for line in ax.get_lines():
            t = _line_trace(line, k, xl, yl)
            if t is None:
                continue
            if t.get("name") in seen:
                t["showlegend"] = False
            seen.add(t.get("name"))
            data.append(t)
        shapes += _span_shapes(ax, k)
    for t in data:  # plotly names the first axes "x"/"y", not "x1"/"y1"
        t["xaxis"] = "x" if t["xaxis"] == "x1" else t["xaxis"]
        t["yaxis"] = "y" if t["yaxis"] == "y1" else t["yaxis"]
    for s in shapes:
        s["xref"] = "x" if s["xref"] == "x1" else s["xref"]
        s["yref"] = s["yref"].replace("y1 ", "y ")
    sup = getattr(fig, "_suptitle", None)
    w_in, h_in = fig.get_size_inches()
    layout.update({"height": int(max(320, 90 * h_in)), "shapes": shapes, "annotations": notes,
                   "hovermode": "closest", "plot_bgcolor": "white",
                   "margin": {"l": 10, "r": 10, "t": 60 if sup else 30, "b": 10},
                   "legend": {"orientation": "h", "x": 0, "y": 1.0, "yanchor": "bottom",
                              "xanchor": "left", "font": {"size": 11}},
                   "showlegend": any(t.get("showlegend", True) and "name" in t for t in data)})
    if sup is not None and sup.get_text():
        layout["title"] = {"text": sup.get_text(), "x": 0.01, "y": 0.995, "yanchor": "top",
                           "font": {"size": 14}}
        layout["legend"]["y"] = 1.0
    for key, ax_ in layout.items():
        if key.startswith(("xaxis", "yaxis")):
            ax_.update({"gridcolor": "#e5e5e5", "linecolor": "#888", "mirror": True,
                        "showline": True, "ticks": "outside"})
    # leave the figure's own margins to its axes: matplotlib placed them with room for labels
    layout["margin"] = {"l": 0, "r": 0, "t": 70 if sup else 40, "b": 0}
    return {"data": data, "layout": layout}


# --------------------------------------------------------------------------- from the files


def _units(summary: DemoSummary) -> str:
    return ("V/V" if summary.plant.structure == "the default testbed"
            else "output / input, in the IO file's units")


def bode_explorer(summary: DemoSummary, out: Path) -> dict:
    """Bode overlays per channel pair (dropdown): the true plant, the H1 estimate of every
    identification record that drives the input and every model that has it, from the
    report's files; magnitude on a log axis with the plant's units, phase in degrees."""
    # Long: gathers every curve of every pair, then one dropdown entry per pair.
    truth, _ = load_model(out / "plant_true.npz")
    st = summary.settings
    f = frf_grid(truth, st.plot_band, 1200)
    Ht = frequency_response(truth, f)
    ins, outs = list(truth.input_labels), list(truth.output_labels)
    curves = {}  # (i, j) -> list of (label, f, H_ij, style)
    for i in range(len(outs)):
        for j in range(len(ins)):
            curves[(i, j)] = [("true plant", f, Ht[:, i, j], {"color": "#8c8c8c", "width": 4})]
    palette = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b", "#e377c2"]
    for k, m in enumerate(summary.models):
        rec = read_data(out / f"data_{m.name}_ide.npz")
        est = h1(rec.u, rec.y, rec.fs, nperseg=st.h1_nperseg)
        keep = (est.f >= st.plot_band[0]) & (est.f <= st.plot_band[1])
        sys_, _ = load_model(out / f"model_{m.name}.npz")
        Hm = frequency_response(sys_, f)
        for jj, name in enumerate(m.input_names):
            j = ins.index(name)
            for i, oname in enumerate(m.output_names):
                ii = outs.index(oname)
                curves[(ii, j)].append((f"H1, {m.name} record", est.f[keep], est.H[keep, i, jj],
                                        {"color": palette[k % len(palette)], "width": 1.2,
                                         "dash": "dot"}))
                curves[(ii, j)].append((f"model {m.name} ({m.states} states)", f, Hm[:, i, jj],
                                        {"color": palette[k % len(palette)], "width": 1.4}))
    data, buttons, pairs = [], [], list(curves)
    for n, (i, j) in enumerate(pairs):
        first = len(data)
        for label, ff, H, style in curves[(i, j)]:
            common = {"type": "scatter", "mode": "lines", "name": label, "legendgroup": label,
                      "visible": n == 0, "line": style, "x": _typed(ff)}
            data.append({**common, "y": _typed(np.abs(H)), "xaxis": "x", "yaxis": "y",
                         "hovertemplate": "%{x:.2f} Hz<br>|H| %{y:.4g}<extra>" + label
                                          + "</extra>"})
            data.append({**common, "y": _typed(np.degrees(np.angle(H))), "xaxis": "x2",
                         "yaxis": "y2", "showlegend": False,
                         "hovertemplate": "%{x:.2f} Hz<br>%{y:.1f} deg<extra>" + label
                                          + "</extra>"})
        buttons.append({"label": f"{ins[j]} -> {outs[i]}", "method": "update",
                        "args": [{"visible": None}, {"yaxis.title.text":
                                                     f"|{outs[i]}/{ins[j]}| [{_units(summary)}]"}],
                        "_range": (first, len(data))})
    for b in buttons:
        lo, hi = b.pop("_range")
        b["args"][0]["visible"] = [lo <= q < hi for q in range(len(data))]
    lo, hi = st.excitation_band
    layout = {
        "height": 620, "hovermode": "x unified", "plot_bgcolor": "white",
        "margin": {"l": 80, "r": 20, "t": 70, "b": 50},
        "xaxis": {"domain": [0, 1], "anchor": "y", "matches": "x2", "showticklabels": False,
                  "range": list(st.plot_band)},
        "yaxis": {"domain": [0.42, 1.0], "type": "log", "exponentformat": "power",
                  "title": {"text": f"|{outs[0]}/{ins[0]}| [{_units(summary)}]"}},
        "xaxis2": {"domain": [0, 1], "anchor": "y2", "title": {"text": "frequency [Hz]"},
                   "range": list(st.plot_band)},
        "yaxis2": {"domain": [0, 0.36], "range": [-190, 190], "dtick": 90,
                   "title": {"text": "phase [deg]"}},
        "shapes": [{"type": "rect", "xref": ax, "yref": f"{ay} domain", "x0": lo,
                    "x1": min(hi, st.plot_band[1]), "y0": 0, "y1": 1, "line": {"width": 0},
                    "fillcolor": "#2ca02c", "opacity": 0.06, "layer": "below"}
                   for ax, ay in (("x", "y"), ("x2", "y2"))],
        "updatemenus": [{"buttons": buttons, "direction": "down", "x": 0.0, "y": 1.02,
                         "xanchor": "left", "yanchor": "bottom", "showactive": True}],
        "legend": {"orientation": "h", "x": 0.16, "y": 1.02, "yanchor": "bottom"},
    }
    for key in ("xaxis", "yaxis", "xaxis2", "yaxis2"):
        layout[key].update({"gridcolor": "#e5e5e5", "showline": True, "mirror": True,
                            "linecolor": "#888"})
    return {"data": data, "layout": layout}


def interval_figure(summary: DemoSummary) -> dict | None:
    """The identified modes of every model with their 95 % intervals as error bars
    (frequency on one panel, damping against frequency on the other), the true modes in the
    band as vertical lines; None when no model has a matched mode."""
    rows = [(m, c) for m in summary.models for c in m.mode_checks]
    if not rows:
        return None
    names = [f"{m.name} ({m.states} states)" for m in summary.models]
    data = []
    palette = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b"]
    for k, m in enumerate(summary.models):
        cs = m.mode_checks
        if not cs:
            continue
        f = np.array([c.frequency_hz for c in cs])
        fi = np.array([c.frequency_ci95_hz or [np.nan, np.nan] for c in cs], dtype=float)
        z = np.array([next((r.damping for r in m.poles if r.frequency_hz is not None
                            and abs(r.frequency_hz - c.frequency_hz) < 1e-9), np.nan)
                      for c in cs], dtype=float)
        zi = np.array([c.damping_ratio_ci95 or [np.nan, np.nan] for c in cs], dtype=float)
        macs = [c.mac for c in cs]
        text = [f"{c.frequency_hz:.2f} Hz (true {c.true_frequency_hz:.2f}), MAC {c.mac:.3f}"
                for c in cs]
        style = {"color": palette[k % len(palette)], "symbol": "cross-thin", "size": 10,
                 "line": {"width": 2, "color": palette[k % len(palette)]}}
        data.append({"type": "scatter", "mode": "markers", "name": names[k],
                     "legendgroup": names[k], "x": f.tolist(), "y": [names[k]] * len(f),
                     "error_x": {"type": "data", "symmetric": False,
                                 "array": np.nan_to_num(fi[:, 1] - f).tolist(),
                                 "arrayminus": np.nan_to_num(f - fi[:, 0]).tolist(),
                                 "thickness": 2, "width": 6},
                     "marker": style, "text": text, "customdata": macs,
                     "hovertemplate": "%{text}<extra>" + names[k] + "</extra>"})
        data.append({"type": "scatter", "mode": "markers", "name": names[k],
                     "legendgroup": names[k], "showlegend": False, "x": f.tolist(),
                     "y": (100 * z).tolist(), "xaxis": "x2", "yaxis": "y2",
                     "error_y": {"type": "data", "symmetric": False,
                                 "array": np.nan_to_num(100 * (zi[:, 1] - z)).tolist(),
                                 "arrayminus": np.nan_to_num(100 * (z - zi[:, 0])).tolist(),
                                 "thickness": 1.5, "width": 4},
                     "error_x": {"type": "data", "symmetric": False,
                                 "array": np.nan_to_num(fi[:, 1] - f).tolist(),
                                 "arrayminus": np.nan_to_num(f - fi[:, 0]).tolist(),
                                 "thickness": 1.5, "width": 4},
                     "marker": style, "text": text,
                     "hovertemplate": "%{text}<br>damping %{y:.3f} %<extra>" + names[k]
                                      + "</extra>"})
    true_f = sorted({c.true_frequency_hz for _, c in rows})
    shapes = [{"type": "line", "xref": ax, "yref": f"{ay} domain", "x0": v, "x1": v, "y0": 0,
               "y1": 1, "line": {"color": "#999", "width": 1, "dash": "dot"}}
              for v in true_f for ax, ay in (("x", "y"), ("x2", "y2"))]
    lo, hi = summary.settings.frf_band
    layout = {
        "height": 640, "plot_bgcolor": "white", "hovermode": "closest",
        "margin": {"l": 150, "r": 20, "t": 50, "b": 50},
        "xaxis": {"domain": [0, 1], "anchor": "y", "matches": "x2", "range": [lo, hi],
                  "showticklabels": False},
        "yaxis": {"domain": [0.62, 1.0], "type": "category", "title": {"text": "model"}},
        "xaxis2": {"domain": [0, 1], "anchor": "y2", "title": {"text": "frequency [Hz]"},
                   "range": [lo, hi]},
        "yaxis2": {"domain": [0, 0.55], "type": "log", "title": {"text": "damping ratio [%]"}},
        "shapes": shapes, "legend": {"orientation": "h", "x": 0, "y": 1.06, "yanchor": "bottom"},
    }
    for key in ("xaxis", "yaxis", "xaxis2", "yaxis2"):
        layout[key].update({"gridcolor": "#e5e5e5", "showline": True, "mirror": True,
                            "linecolor": "#888"})
    return {"data": data, "layout": layout}


def structure_viewer(tp, summary: DemoSummary, out: Path) -> dict | None:
    """The 3-D viewer's data for the campaign's plant ``tp`` (a testbed plant or a deck's
    :class:`trussid.campaign.structure.CampaignPlant`): its FE modes, its sensors and, per
    identified model, the modes matched to FE ones (``mode_checks``: frequency, MAC; shape
    at the sensors from the model file). None when the plant carries no FE model."""
    if isinstance(tp, TestbedPlant):
        fe, sensors = tp.tbm.model, accelerometers(tp.tbm)
        labels = label_testbed_modes(tp.tbm, tp.modes).labels
    else:
        fe, sensors, labels = getattr(tp, "model", None), getattr(tp, "sensors", ()), None
    if fe is None:
        return None
    outputs = list(tp.discrete.output_labels)
    axes = [SensorAxis(s.name, int(s.node), tuple(np.asarray(s.direction, float)))
            for s in sensors if s.name in outputs]
    freqs = np.asarray(tp.modes.frequencies_hz, float)
    n = int(np.sum(freqs < 0.5 * summary.plant.sample_rate_hz)) or len(freqs)
    identified = []
    for m in summary.models:
        if not m.mode_checks or not axes:
            continue
        sys_, _ = load_model(out / f"model_{m.name}.npz")
        table = modal_table(sys_)
        order = [m.output_names.index(a.name) for a in axes if a.name in m.output_names]
        if len(order) != len(axes):
            continue
        for c in m.mode_checks:
            k = int(np.argmin(np.abs(freqs[:n] - c.true_frequency_hz)))
            q = int(np.argmin(np.abs(table.frequencies_hz - c.frequency_hz)))
            if abs(freqs[k] - c.true_frequency_hz) > 0.01 * c.true_frequency_hz:
                continue
            identified.append(IdentifiedMode(m.name, k + 1, float(c.frequency_hz),
                                             float(table.damping[q]), float(c.mac),
                                             tuple(table.shapes[order, q])))
    title = (f"{summary.plant.structure}: FE modes" + (" and identified modes at the sensors"
                                                       if identified else ""))
    return mode_viewer_data(fe, tp.modes, n_modes=n, labels=labels, sensors=axes,
                            identified=identified, title=title)


# --------------------------------------------------------------------------- the page

#: Draws each figure when it comes near the viewport (a page of 60 figures opens at once).
_LAZY_JS = r"""
(function () {
  function draw(el) {
    if (el.dataset.drawn) return;
    el.dataset.drawn = '1';
    var fig = JSON.parse(document.getElementById(el.dataset.src).textContent);
    Plotly.newPlot(el, fig.data, fig.layout, {responsive: true, displaylogo: false});
  }
  // after the load event: the page (text and tables) opens first, the figures follow
  window.addEventListener('load', function () {
    var io = new IntersectionObserver(function (entries) {
      entries.forEach(function (e) { if (e.isIntersecting) { draw(e.target); io.unobserve(e.target); } });
    }, {rootMargin: '600px'});
    document.querySelectorAll('.fig').forEach(function (el) { io.observe(el); });
  });
  window.trussidDrawAll = function () { document.querySelectorAll('.fig').forEach(draw); };
})();
"""

_CSS = """
table { border-collapse: collapse; margin: .5em 0; font-size: 90%; }
th, td { border: 1px solid #ccc; padding: 2px 6px; }
th { background: #f3f3f3; }
.fig { width: 100%; min-height: 300px; margin: .6em 0 1.2em 0; }
nav a { margin-right: 1em; }
code { background: #f5f5f5; }
"""


def _figure_block(fig: dict, n: int, caption: str = "") -> str:
    payload = json.dumps(fig, separators=(",", ":"), allow_nan=False,
                         default=float).replace("</", "<\\/")
    return (f'<script type="application/json" id="figdata{n}">{payload}</script>'
            f'<div class="fig" id="fig{n}" data-src="figdata{n}" title="{html.escape(caption)}"'
            f' style="height:{int(fig["layout"].get("height", 450))}px"></div>')


def _clean(obj):
    """NaN and infinities -> None (JSON has neither), in nested lists and dicts."""
    if isinstance(obj, float):
        return obj if np.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_clean(v) for v in obj]
    return obj


def report_html(summary: DemoSummary, markdown: str, out: Path, figures: dict,
                viewer: dict | None = None) -> str:
    """The page: the 3-D viewer, the Bode explorer, the intervals, then the report's
    Markdown with each figure (``figures``: file name -> matplotlib Figure) drawn
    interactively in its place; a figure not given stays the PNG, embedded in the page."""
    n = [0]

    def block(fig, caption=""):
        n[0] += 1
        return _figure_block(_clean(fig), n[0], caption)

    md = MarkdownIt("commonmark").enable("table")
    body = md.render(markdown)

    def replace(mt):
        src, alt = html.unescape(mt.group(1)), html.unescape(mt.group(2))
        if src in figures:
            return block(figure_data(figures[src]), f"{alt} ({src})")
        png = out / src
        if png.is_file():  # embedded: the page must not reach outside itself
            b64 = base64.b64encode(png.read_bytes()).decode("ascii")
            return f'<img src="data:image/png;base64,{b64}" alt="{html.escape(alt)}">'
        return f"<em>[{html.escape(alt)}: {html.escape(src)} not written]</em>"

    body = re.sub(r'<img src="([^"]+)" alt="([^"]*)"\s*/?>', replace, body)
    parts = ['<nav><a href="#structure">structure in 3-D</a><a href="#bode">Bode explorer</a>'
             '<a href="#intervals">identified modes, 95 % intervals</a>'
             '<a href="#report">report</a></nav>']
    if viewer is not None:
        parts += ['<h2 id="structure">The structure in 3-D</h2>',
                  "<p>Pick a mode, watch it move; drag to rotate, scroll to zoom. The open "
                  "circles are the sensors moving with the FE mode along their axes; the "
                  "diamonds, where a model identified that mode, are its shape at the sensors "
                  "(scaled to the FE shape by the least-squares modal scale factor), with the "
                  "MAC against the FE mode above the plot.</p>",
                  viewer_fragment(viewer, "modes3d")]
    parts += ['<h2 id="bode">Bode explorer</h2>',
              "<p>Pick a channel pair; drag to zoom (double-click to reset), hover for the "
              "values, click a legend entry to hide a curve. Shaded: the excited band; "
              "outside it the H1 estimates are noise.</p>",
              block(bode_explorer(summary, out), "Bode explorer")]
    iv = interval_figure(summary)
    if iv is not None:
        parts += ['<h2 id="intervals">Identified modes with 95 % intervals</h2>',
                  "<p>Each model's identified modes in the FRF band with the 95 % intervals "
                  "of frequency and damping as error bars (first-order propagation of the "
                  "PLID pass's parameter covariance, <code>plid.uncertainty</code>); the "
                  "dotted lines are the true modes. The campaign keeps one model per record "
                  "(the summary holds no poles of the other orders tried), so this is one "
                  "row per model rather than a full stabilisation diagram over orders: "
                  "<code>trussid identify --stabilisation</code> draws that.</p>",
                  block(iv, "intervals")]
    parts += ['<div id="report">', body, "</div>",
              f"<script>{_LAZY_JS}</script>"]
    title = markdown.splitlines()[0].lstrip("# ").strip() if markdown else "trussid report"
    return html_page(title, "\n".join(parts), _CSS)


def write_report_html(out, summary: DemoSummary, markdown: str, figures: dict,
                      tp=None) -> Path:
    """Write ``report.html`` into the report directory ``out`` (atomically), from the summary,
    the report's Markdown, its figures (file name -> matplotlib Figure) and the plant ``tp``
    (for the 3-D view; None leaves it out)."""
    out = Path(out)
    viewer = structure_viewer(tp, summary, out) if tp is not None else None
    text = report_html(summary, markdown, out, figures, viewer)
    path = out / "report.html"
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path
