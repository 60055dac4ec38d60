"""Mode shapes in 3-D in a web page that works offline: rotate, zoom, pick a mode, watch it move.

The page is one HTML file with plotly.js inline (no server, no network, no external
``src``/``href``): it opens from a laptop, an e-mail attachment or a CI artefact.

Why plotly (plotly.py's bundled plotly.js, inlined): measured for issue 36, a plotly page is
about 4.8 MB and renders from a local file in headless Chromium without network; pyvista's
trame exporter makes a smaller 3-D page (about 1 MB) but only for the 3-D scene, while the
report around it needs interactive line plots (Bode overlays with hover and zoom, pole
maps, stabilisation diagrams) too: one library for both keeps one script in the page. The
structure is drawn as lines (``scatter3d``), coloured by displacement magnitude, over a
faint ghost of the undeformed structure; the motion is one small script that rescales
precomputed displacements (``restyle`` of the coordinates about 20 times a second) rather
than plotly animation frames, which would store every frame of every mode in the file
(frames x modes copies of the geometry).

Beams bend between their nodes with the cubic Hermite shape functions
(:func:`trussid.fem.render_scene.hermite_beam_displacements`), as in the offscreen renderer.

Optional markers at sensors: the FE mode projected on each sensor's axis and, from
identified models, their modes at the sensors (complex shapes, scaled to the FE projection
by the least-squares modal scale factor, real part drawn) with the MAC against the FE mode.

Mode numbers are 1-based, as on the command line. ``#mode=3`` in the page's URL selects
mode 3; ``#mode=3&phase=0.25`` freezes the motion at a quarter period (for screenshots).
"""

from __future__ import annotations

import base64
import html
import json
from dataclasses import dataclass
from html.parser import HTMLParser
from typing import Sequence

import numpy as np
import plotly

from trussid._util.files import atomic_path
from trussid.fem.model import Model
from trussid.fem.errors import RenderError
from trussid.fem.render_scene import (DEFAULT_AMPLITUDE, check_mode_number, default_cmap,
                                      equivalent_radius, hermite_beam_displacements, node_displacements)

__all__ = ["SensorAxis", "IdentifiedMode", "mode_viewer_data", "viewer_fragment",
           "plotly_script", "html_page", "write_mode_viewer", "external_references",
           "VIEWER_JS"]


@dataclass(frozen=True)
class SensorAxis:
    """A single-axis sensor drawn in the viewer: output ``name`` at node ``node`` along the
    unit vector ``direction`` (global axes)."""

    name: str
    node: int
    direction: tuple


@dataclass(frozen=True)
class IdentifiedMode:
    """An identified mode matched to an FE mode.

    Attributes
    ----------
    model : str
        The identified model's name (e.g. ``"mimo"``).
    fe_mode : int
        1-based number of the FE mode it matches.
    frequency_hz, damping : float
        The identified mode's frequency [Hz] and damping ratio.
    mac : float
        MAC of the identified shape against the FE (true) one at the sensors.
    shape : sequence of complex
        The identified shape at the sensors, in the order of the viewer's ``sensors``.
    """

    model: str
    fe_mode: int
    frequency_hz: float
    damping: float
    mac: float
    shape: tuple


def _b64(a) -> str:
    """Float32 little-endian, base64: about 5.3 characters a number, a third of JSON text."""
    return base64.b64encode(np.ascontiguousarray(a, dtype="<f4").tobytes()).decode("ascii")


def _with_breaks(points: np.ndarray) -> np.ndarray:
    """(n, s, 3) polylines -> (n (s + 1), 3) with a NaN point after each (a gap in the line)."""
    n, s, _ = points.shape
    out = np.full((n, s + 1, 3), np.nan)
    out[:, :s] = points
    return out.reshape(-1, 3)


def mode_viewer_data(model: Model, modes, *, n_modes: int | None = None,
                     labels: Sequence[str] | None = None, sensors: Sequence[SensorAxis] = (),
                     identified: Sequence[IdentifiedMode] = (), title: str = "",
                     amplitude: float = DEFAULT_AMPLITUDE, n_samples: int = 5,
                     period_s: float = 1.6) -> dict:
    """The viewer's data (plain JSON-ready dict) for the first ``n_modes`` modes.

    Parameters
    ----------
    model : fem.Model
    modes : Modes-like
        ``shapes_full`` (6 n_nodes, n), ``frequencies_hz``, ``node_ids``.
    n_modes : int, optional
        Modes offered (default all).
    labels : sequence of str, optional
        Text after each mode's frequency (e.g. the testbed's energy labels).
    sensors : sequence of SensorAxis
    identified : sequence of IdentifiedMode
        ``shape`` ordered as ``sensors``.
    title : str
    amplitude : float
        Largest drawn displacement as a fraction of the bounding-box diagonal.
    n_samples : int
        Points per beam (>= 2) for the Hermite interpolation.
    period_s : float
        Playback duration of one period [s].

    Returns
    -------
    dict
        ``sets`` (drawn point sets with their undeformed coordinates and per-mode
        displacements, base64 float32, normalised so that the largest displacement of each
        mode is 1), ``modes`` (frequency, label, matches), ``ranges``, ``amplitude`` [m].
    """
    # Long: one data set assembled part by part (beams, rigid links, masses, supports,
    # sensors, identified modes), each a few lines over the same node displacements.
    freqs = np.asarray(modes.frequencies_hz, float)
    n_avail = np.asarray(modes.shapes_full).shape[1]
    n = n_avail if n_modes is None else int(n_modes)
    check_mode_number(n, n_avail)
    if n_samples < 2:
        raise RenderError(f"n_samples must be at least 2, got {n_samples}")
    xyz = model.xyz
    beams = model.beams
    xi = np.linspace(0.0, 1.0, n_samples)
    links = [(rb.master, s) for rb in model.rigid_bodies for s in rb.slaves]
    pm = model.point_masses
    has_mass = pm.mass > 0
    sensor_idx = (model.index_of(np.array([s.node for s in sensors], np.int64), what="a sensor")
                  if sensors else np.zeros(0, int))
    dirs = (np.array([np.asarray(s.direction, float) / np.linalg.norm(s.direction)
                      for s in sensors]) if sensors else np.zeros((0, 3)))
    ends = (model.index_of(beams.nodes, what=lambda k: f"beam {beams.ids[k // 2]}")
            if len(beams) else np.zeros((0, 2), int))
    ln = (model.index_of(np.array(links, np.int64), what="a rigid body") if links
          else np.zeros((0, 2), int))
    mass_idx = model.index_of(pm.nodes[has_mass], what="a point mass") if has_mass.any() \
        else np.zeros(0, int)
    if not (len(ends) or len(ln) or len(mass_idx)):
        raise RenderError("the model has nothing to draw (no beams, rigid bodies or masses)")

    lines_x0, lines_u, mass_u, sens_u, scales = None, [], [], [], []
    for k in range(1, n + 1):
        u_nodes = node_displacements(model, modes, k)
        parts_x, parts_u = [], []
        if len(ends):
            x, u = hermite_beam_displacements(xyz[ends[:, 0]], xyz[ends[:, 1]],
                                              u_nodes[ends[:, 0]], u_nodes[ends[:, 1]], xi,
                                              rod=beams.rod)
            parts_x.append(_with_breaks(x))
            parts_u.append(_with_breaks(u))
        if len(ln):
            x, u = hermite_beam_displacements(xyz[ln[:, 0]], xyz[ln[:, 1]], u_nodes[ln[:, 0]],
                                              u_nodes[ln[:, 1]], np.array([0.0, 1.0]),
                                              rod=np.ones(len(ln), bool))
            parts_x.append(_with_breaks(x))
            parts_u.append(_with_breaks(u))
        ux = np.concatenate(parts_u) if parts_u else np.zeros((0, 3))
        um = u_nodes[mass_idx, :3]
        us = u_nodes[sensor_idx, :3]
        scale = max(float(np.nanmax(np.linalg.norm(ux, axis=1))) if ux.size else 0.0,
                    float(np.max(np.linalg.norm(um, axis=1))) if um.size else 0.0)
        scale = scale if scale > 0 else 1.0
        if lines_x0 is None:
            lines_x0 = np.concatenate(parts_x) if parts_x else np.zeros((0, 3))
        lines_u.append(ux / scale)
        mass_u.append(um / scale)
        # the FE mode as each sensor sees it: the translation along its axis
        sens_u.append(np.sum(us * dirs, axis=1) / scale)
        scales.append(scale)

    pts = [lines_x0[np.isfinite(lines_x0[:, 0])], xyz[mass_idx], xyz[sensor_idx]]
    allpts = np.concatenate([p for p in pts if p.size])
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    diagonal = float(np.linalg.norm(hi - lo)) or 1.0
    amp = amplitude * diagonal
    pad = amp + 0.03 * diagonal
    radius = (float(np.median(equivalent_radius(beams.A, beams.Iy, beams.Iz, beams.J,
                                                 beams.rod))) if len(beams) else 0.0)

    sets = []
    if len(lines_x0):
        sets.append({"name": "structure", "kind": "lines", "x0": _b64(lines_x0),
                     "u": [_b64(u) for u in lines_u], "width": 5, "colour_by_motion": True})
    if len(mass_idx):
        sets.append({"name": "masses", "kind": "markers", "x0": _b64(xyz[mass_idx]),
                     "u": [_b64(u) for u in mass_u], "size": 5, "colour": "#555555",
                     "symbol": "circle"})
    mode_rows = [{"number": k + 1, "frequency_hz": float(freqs[k]),
                  "label": (labels[k] if labels is not None and k < len(labels) else ""),
                  "matches": []} for k in range(n)]
    if len(sensor_idx):
        sets.append({"name": "sensors: FE mode on the sensor axis", "kind": "markers",
                     "x0": _b64(xyz[sensor_idx]),
                     "u": [_b64(s[:, None] * dirs) for s in sens_u], "size": 7,
                     "colour": "#111111", "symbol": "circle-open",
                     "text": [s.name for s in sensors]})
        by_model: dict[str, list] = {}
        for m in identified:
            check_mode_number(int(m.fe_mode), n_avail)
            if m.fe_mode > n:
                continue
            by_model.setdefault(m.model, []).append(m)
        palette = ("#d62728", "#9467bd", "#2ca02c", "#ff7f0e", "#8c564b")
        for j, (name, rows) in enumerate(by_model.items()):
            per_mode = [None] * n
            for m in rows:
                psi = np.asarray(m.shape, complex)
                if psi.shape != (len(sensors),):
                    raise RenderError(f"identified mode of {name} at {m.frequency_hz:.4g} Hz: "
                                      f"{psi.size} sensor values for {len(sensors)} sensors")
                phi = sens_u[m.fe_mode - 1]
                # least-squares modal scale factor: the complex alpha minimising
                # |phi - alpha psi|, so the identified shape is drawn in the FE's scale
                den = float(np.vdot(psi, psi).real)
                alpha = np.vdot(psi, phi) / den if den > 0 else 0.0
                drawn = np.real(alpha * psi)
                per_mode[m.fe_mode - 1] = _b64(drawn[:, None] * dirs)
                mode_rows[m.fe_mode - 1]["matches"].append(
                    {"model": name, "frequency_hz": float(m.frequency_hz),
                     "damping": float(m.damping), "mac": float(m.mac)})
            sets.append({"name": f"identified ({name}) at the sensors", "kind": "markers",
                         "x0": _b64(xyz[sensor_idx]), "u": per_mode, "size": 6,
                         "colour": palette[j % len(palette)], "symbol": "diamond"})
    from_turbo = default_cmap()  # the offscreen renderer's colours, as plotly colour stops
    stops = [[float(v), "#%02x%02x%02x" % tuple(int(round(255 * c)) for c in from_turbo(v)[:3])]
             for v in np.linspace(0.0, 1.0, 11)]
    return {"title": title, "sets": sets, "colorscale": stops, "modes": mode_rows, "amplitude": amp,
            "period_s": float(period_s), "tube_radius_m": radius,
            "ranges": [[float(lo[i] - pad), float(hi[i] + pad)] for i in range(3)]}


#: The viewer's script, once per page: ``trussidModeViewer(id, data)`` draws into the element
#: ``id`` (made by :func:`viewer_fragment`). Displacements are precomputed per mode; a frame
#: is ``x0 + sin(2 pi t / T) a u``, restyled about 20 times a second while playing.
VIEWER_JS = r"""
window.trussidModeViewer = function (id, D) {
  var root = document.getElementById(id);
  var plot = root.querySelector('.tv-plot'), sel = root.querySelector('.tv-mode');
  var info = root.querySelector('.tv-info'), btn = root.querySelector('.tv-play');
  var ampIn = root.querySelector('.tv-amp');
  function dec(s) {
    if (s === null) return null;
    var b = atob(s), a = new Uint8Array(b.length);
    for (var i = 0; i < b.length; i++) a[i] = b.charCodeAt(i);
    return new Float32Array(a.buffer);
  }
  var sets = D.sets.map(function (s) {
    return {s: s, x0: dec(s.x0), u: s.u.map(dec)};
  });
  window.trussidModeCount = D.modes.length;
  var mode = 0, phase = 0.25, playing = true, gain = 1.0, t0 = performance.now(), last = 0;
  function xyz(k, f) {
    var s = sets[k], u = s.u[mode], n = s.x0.length / 3, X = [], Y = [], Z = [];
    var a = f * D.amplitude * gain;
    for (var i = 0; i < n; i++) {
      var x = s.x0[3 * i], y = s.x0[3 * i + 1], z = s.x0[3 * i + 2];
      if (u === null || isNaN(x)) { X.push(isNaN(x) || u === null ? null : x); Y.push(null); Z.push(null); continue; }
      X.push(x + a * u[3 * i]); Y.push(y + a * u[3 * i + 1]); Z.push(z + a * u[3 * i + 2]);
    }
    return [X, Y, Z];
  }
  function magnitude(k) {
    var u = sets[k].u[mode], n = u.length / 3, c = [];
    for (var i = 0; i < n; i++) {
      var m = Math.sqrt(u[3 * i] * u[3 * i] + u[3 * i + 1] * u[3 * i + 1] + u[3 * i + 2] * u[3 * i + 2]);
      c.push(isNaN(m) ? 0 : m);
    }
    return c;
  }
  var traces = [];
  var g = xyz(0, 0);
  traces.push({type: 'scatter3d', mode: 'lines', name: 'undeformed', x: g[0], y: g[1], z: g[2],
               line: {color: '#b0b0b0', width: 2}, hoverinfo: 'skip', connectgaps: false});
  sets.forEach(function (s, k) {
    var c = xyz(k, 0), t = {type: 'scatter3d', name: s.s.name, x: c[0], y: c[1], z: c[2],
                            connectgaps: false};
    if (s.s.kind === 'lines') {
      t.mode = 'lines';
      t.line = {width: s.s.width, color: magnitude(k), colorscale: D.colorscale, cmin: 0, cmax: 1,
                showscale: true, colorbar: {title: {text: '|u| / max'}, len: 0.6, thickness: 14}};
      t.hoverinfo = 'skip';
    } else {
      t.mode = s.s.text ? 'markers+text' : 'markers';
      t.text = s.s.text; t.textposition = 'top center';
      t.marker = {size: s.s.size, color: s.s.colour, symbol: s.s.symbol,
                  line: {color: s.s.colour, width: 2}};
    }
    traces.push(t);
  });
  var r = D.ranges;
  var span = Math.max(r[0][1] - r[0][0], r[1][1] - r[1][0], r[2][1] - r[2][0]);
  var layout = {
    margin: {l: 0, r: 0, t: 30, b: 0}, uirevision: 'keep', showlegend: true,
    legend: {x: 0, y: 0, bgcolor: 'rgba(255,255,255,0.7)'},
    title: {text: D.title, x: 0.01, y: 0.98, font: {size: 14}},
    scene: {aspectmode: 'manual',
            aspectratio: {x: (r[0][1] - r[0][0]) / span, y: (r[1][1] - r[1][0]) / span,
                          z: (r[2][1] - r[2][0]) / span},
            xaxis: {range: r[0], title: {text: 'x [m]'}}, yaxis: {range: r[1], title: {text: 'y [m]'}},
            zaxis: {range: r[2], title: {text: 'z [m]'}},
            camera: {eye: {x: 0.95, y: -1.5, z: 0.8}}}
  };
  Plotly.newPlot(plot, traces, layout, {responsive: true, displaylogo: false});
  function draw() {
    var f = Math.sin(2 * Math.PI * phase), X = [], Y = [], Z = [], idx = [];
    sets.forEach(function (s, k) { var c = xyz(k, f); X.push(c[0]); Y.push(c[1]); Z.push(c[2]); idx.push(k + 1); });
    Plotly.restyle(plot, {x: X, y: Y, z: Z}, idx);
  }
  function describe() {
    var m = D.modes[mode];
    var h = '<b>Mode ' + m.number + ': ' + m.frequency_hz.toFixed(2) + ' Hz</b>' +
            (m.label ? ' ' + m.label : '');
    if (m.matches.length) {
      h += '<br>identified: ' + m.matches.map(function (q) {
        return q.model + ' ' + q.frequency_hz.toFixed(2) + ' Hz, damping ' +
               (100 * q.damping).toFixed(3) + ' %, MAC ' + q.mac.toFixed(3);
      }).join('; ');
    } else if (sets.some(function (s) { return s.s.name.indexOf('identified') === 0; })) {
      h += '<br>no identified mode matched to this one';
    }
    info.innerHTML = h;
  }
  function setMode(k) {
    mode = Math.max(0, Math.min(D.modes.length - 1, k));
    sel.value = String(mode);
    sets.forEach(function (s, j) {
      if (s.s.kind === 'lines') Plotly.restyle(plot, {'line.color': [magnitude(j)]}, [j + 1]);
      else Plotly.restyle(plot, {visible: [s.u[mode] === null ? false : true]}, [j + 1]);
    });
    describe();
    draw();
  }
  D.modes.forEach(function (m, k) {
    var o = document.createElement('option');
    o.value = String(k);
    o.textContent = m.number + ': ' + m.frequency_hz.toFixed(2) + ' Hz' + (m.label ? ' ' + m.label : '') +
                    (m.matches.length ? '  [identified]' : '');
    sel.appendChild(o);
  });
  sel.addEventListener('change', function () { setMode(parseInt(sel.value, 10)); });
  btn.addEventListener('click', function () {
    playing = !playing; btn.textContent = playing ? 'pause' : 'play';
    t0 = performance.now() - phase * D.period_s * 1000;
    if (root.trussidStart) root.trussidStart();
  });
  ampIn.addEventListener('input', function () { gain = parseFloat(ampIn.value); draw(); });
  function fromHash() {
    var q = new URLSearchParams(location.hash.slice(1));
    if (q.has('phase')) { phase = parseFloat(q.get('phase')) % 1; playing = false; btn.textContent = 'play'; }
    if (q.has('mode')) setMode(parseInt(q.get('mode'), 10) - 1); else draw();
  }
  window.addEventListener('hashchange', fromHash);
  setMode(0);
  fromHash();
  // The loop runs only while playing and while the viewer is on screen: a page of many
  // figures stays responsive, and a paused view (#phase=...) is still for screenshots.
  var visible = true, looping = false;
  function tick(now) {
    if (!playing || !visible) { looping = false; return; }
    if (now - last > 50) {
      last = now;
      phase = ((now - t0) / 1000 / D.period_s) % 1;
      draw();
    }
    requestAnimationFrame(tick);
  }
  function start() {
    if (!looping && playing && visible) { looping = true; requestAnimationFrame(tick); }
  }
  if (window.IntersectionObserver) {
    new IntersectionObserver(function (entries) {
      visible = entries[0].isIntersecting;
      t0 = performance.now() - phase * D.period_s * 1000;
      start();
    }).observe(plot);
  }
  root.trussidStart = start;
  start();
};
"""

#: With ``probe`` in the URL's fragment, the page reports at its load event what it fetched
#: (the browser's resource timing: an offline page lists nothing), its load time and where
#: its plots are, in ``<pre id="probe">`` (JSON): tests read it with ``chromium --dump-dom``.
PROBE_JS = r"""
window.addEventListener('load', function () {
  if (location.hash.indexOf('probe') < 0) return;
  var nav = performance.getEntriesByType('navigation')[0];
  function rect(el) { var r = el.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; }
  var p = document.createElement('pre');
  p.id = 'probe';
  p.textContent = JSON.stringify({
    resources: performance.getEntriesByType('resource').map(function (e) { return e.name; }),
    load_ms: nav ? nav.loadEventStart : null,
    viewer: Array.prototype.map.call(document.querySelectorAll('.tv-plot'), rect),
    figures: Array.prototype.map.call(document.querySelectorAll('.fig'), rect),
    modes: window.trussidModeCount || null
  });
  document.body.appendChild(p);
});
"""

VIEWER_CSS = """
.tv-controls { display: flex; gap: 1em; align-items: center; flex-wrap: wrap; margin: .3em 0; }
.tv-plot { width: 100%; height: 640px; border: 1px solid #ddd; }
.tv-info { margin: .3em 0; min-height: 2.6em; }
"""


def viewer_fragment(data: dict, div_id: str = "modes3d") -> str:
    """The viewer as an HTML fragment (controls, plot area, the call that draws it); the page
    must hold plotly.js (:func:`plotly_script`) and :data:`VIEWER_JS` before it."""
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    return (f'<div id="{html.escape(div_id)}" class="tv">\n<div class="tv-controls">'
            '<label>mode <select class="tv-mode"></select></label>'
            '<button class="tv-play" type="button">pause</button>'
            '<label>amplitude <input class="tv-amp" type="range" min="0" max="3" step="0.05" '
            'value="1"></label>'
            '<span>drag to rotate, scroll to zoom; <code>#mode=K</code> in the address picks '
            'mode K</span></div>\n'
            '<div class="tv-info"></div><div class="tv-plot"></div></div>\n'
            # drawn once the page has loaded: the text is readable at once, WebGL comes after
            f'<script>(function () {{ var d = {payload}; window.addEventListener("load", '
            f'function () {{ setTimeout(function () {{ trussidModeViewer("{html.escape(div_id)}", '
            'd); }, 0); }); })();</script>\n')


def plotly_script() -> str:
    """plotly.js, inline (``<script>`` element): the page needs no network."""
    return f'<script type="text/javascript">{plotly.offline.get_plotlyjs()}</script>'


def html_page(title: str, body: str, css: str = "") -> str:
    """A whole page: plotly.js and the viewer's script inline, then ``body``."""
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{html.escape(title)}</title>\n<style>\nbody {{ font-family: sans-serif; "
            "margin: 1em 2em; max-width: 1400px; }}\n" + VIEWER_CSS + css + "</style>\n"
            + plotly_script() + f"\n<script>{VIEWER_JS}{PROBE_JS}</script>\n</head>\n<body>\n" + body
            + "\n</body>\n</html>\n")


def write_mode_viewer(model: Model, modes, out, *, n_modes: int | None = None,
                      labels: Sequence[str] | None = None, title: str = "",
                      sensors: Sequence[SensorAxis] = (),
                      amplitude: float = DEFAULT_AMPLITUDE, first_mode: int = 1) -> int:
    """Write a self-contained page with the 3-D viewer of ``model``'s modes to ``out``
    (atomically), ``first_mode`` selected. Returns the file's size [bytes].

    A bad ``first_mode`` raises :class:`trussid.fem.errors.RenderError` before anything is
    written.
    """
    n_avail = np.asarray(modes.shapes_full).shape[1]
    n = n_avail if n_modes is None else n_modes
    check_mode_number(first_mode, n)
    data = mode_viewer_data(model, modes, n_modes=n, labels=labels, sensors=sensors,
                            title=title, amplitude=amplitude)
    select = (f"<script>if (!location.hash) location.hash = 'mode={first_mode}';</script>\n"
              if first_mode != 1 else "")
    body = (f"<h1>{html.escape(title or 'mode shapes')}</h1>\n" + viewer_fragment(data)
            + select)
    text = html_page(title or "mode shapes", body)
    with atomic_path(out) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return len(text.encode("utf-8"))


class _Refs(HTMLParser):
    """Collects every ``src``/``href``-like attribute of the page's elements (script
    contents are not markup and are not parsed as such)."""

    def __init__(self):
        super().__init__()
        self.refs = []

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if name in ("src", "href", "srcset", "data", "poster", "action", "xlink:href") \
                    and value:
                self.refs.append((tag, name, value))


def external_references(text: str) -> list:
    """The ``(tag, attribute, value)`` of every reference in the page ``text`` that leaves
    the file: anything but a fragment (``#...``) or inline data (``data:``). An offline page
    has none."""
    p = _Refs()
    p.feed(text)
    return [r for r in p.refs if not r[2].startswith(("#", "data:"))]
