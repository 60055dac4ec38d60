"""``report.html`` (:mod:`trussid.campaign.html_report`): the report as a page to explore.

- The figure converter keeps the curves of the report's figures (the numbers drawn are the
  numbers of the matplotlib figure), its log axes, shaded bands and legend entries.
- The quick demo's page (slow tier) holds every number of ``report.md`` and the typed
  summary's, refers to nothing outside itself, and in headless Chromium without network it
  loads with no request, draws the 3-D view and the Bode explorer, and changes its 3-D view
  when another mode is selected. The screenshots are kept in ``build/test-artefacts/``.
"""

from __future__ import annotations

import base64
import html
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from trussid import plots
from trussid._util.browser import find_chromium, open_page
from trussid.campaign.demo import demo_settings, run_demo
from trussid.campaign.html_report import figure_data
from trussid.campaign.structure import STRUCTURAL_DAMPING_MAX
from trussid.fem.render_html import external_references

ROOT = Path(__file__).resolve().parents[2]
ARTEFACTS = ROOT / "build" / "test-artefacts" / "report_html"


def _values(typed):
    return np.frombuffer(base64.b64decode(typed["bdata"]), dtype="<f4").astype(float)


def test_a_bode_figure_becomes_the_same_curves_interactive():
    f = np.linspace(10.0, 400.0, 300)
    s = 2j * np.pi * f
    H = (1.0 / (s**2 / (2 * np.pi * 120) ** 2 + 0.01 * s / (2 * np.pi * 120) + 1))[:, None, None]
    H = np.concatenate([H, 2 * H], axis=1)  # two outputs, one input
    fig = plots.bode_figure([("true plant", f, H), ("H1", f, 1.1 * H), ("model", f, 0.9 * H)],
                            0, "ch1", ["acc1", "acc2"], "test", excited=(0.0, 300.0), unit="V/V")
    d = figure_data(fig)
    assert len(d["data"]) == 3 * 2 * 2  # 3 curves x 2 outputs x (magnitude, phase)
    mags = [t for t in d["data"] if t["yaxis"] in ("y", "y3")]
    np.testing.assert_allclose(_values(mags[0]["y"]), np.abs(H[:, 0, 0]), rtol=1e-6)
    np.testing.assert_allclose(_values(mags[0]["x"]), f, rtol=1e-6)
    lay = d["layout"]
    assert lay["yaxis"]["type"] == "log" and lay["yaxis2"]["type"] == "linear"
    assert lay["yaxis"]["title"]["text"] == "|acc1/ch1| [V/V]"
    assert lay["yaxis"]["range"] == pytest.approx(np.log10(fig.axes[0].get_ylim()))
    # one legend entry per curve, shared by the four panels (a click hides it everywhere)
    shown = [t["name"] for t in d["data"] if t.get("showlegend", True) and "name" in t]
    assert shown == ["true plant", "H1", "model"]
    assert {t["legendgroup"] for t in d["data"] if "legendgroup" in t} == set(shown)
    # the excited band shaded in every panel, 0-300 Hz
    assert len(lay["shapes"]) == 4
    assert all(s["x0"] == pytest.approx(0.0) and s["x1"] == pytest.approx(300.0)
               for s in lay["shapes"])
    assert lay["title"]["text"] == "test"  # the figure's own title


# --------------------------------------------------------------------------- the quick demo


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    """The quick demo's report directory and summary (a few CPU minutes: slow tier)."""
    out = tmp_path_factory.mktemp("demo") / "report"
    summary = run_demo(out, demo_settings(True), progress=None)
    return out, summary


def _text(page: str) -> str:
    """The page's visible text: markup and scripts removed, entities decoded."""
    body = re.sub(r"<script.*?</script>", " ", page, flags=re.S)
    return html.unescape(re.sub(r"<[^>]+>", " ", body))


@pytest.mark.slow
def test_every_number_of_report_md_is_in_report_html(quick_report):
    out, s = quick_report
    md = (out / "report.md").read_text()
    text = _text((out / "report.html").read_text())
    numbers = set(re.findall(r"(?<![\w.])-?\d+(?:\.\d+)?(?![\w.])", md))
    missing = sorted(n for n in numbers if n not in text)
    assert missing == []
    # and from the typed summary itself: each model's headline figures and mode checks
    for m in s.models:
        for v in (m.signal_to_prediction_error_db, m.frf_max_error_db, m.frf_rms_error_db):
            assert f"{v:.2f}" in text, m.name
        lo, hi = s.settings.frf_band
        # the report's table: a row per structural true pole in the FRF band (the lab's
        # filter poles are counted, not listed), with the mode check of the same (true,
        # identified) pair where there is one
        rows = {(round(r.true_frequency_hz, 9), round(r.frequency_hz, 9)) for r in m.poles
                if r.true_frequency_hz is not None and r.frequency_hz is not None
                and lo <= r.true_frequency_hz <= hi
                and r.true_damping <= STRUCTURAL_DAMPING_MAX}
        for c in m.mode_checks:
            if (round(c.true_frequency_hz, 9), round(c.frequency_hz, 9)) in rows:
                assert f"{c.mac:.3f}" in text and f"{c.frequency_hz:.2f}" in text
    assert f"{s.plant.sample_rate_hz:g} Hz" in text
    if s.control is not None and "nominal" in s.control.summary.rows:
        assert "Closed loop: active damping" in text


@pytest.mark.slow
def test_report_html_is_one_file_that_reaches_nothing_outside(quick_report):
    out, s = quick_report
    page = (out / "report.html").read_text()
    assert external_references(page) == []
    assert "Plotly.newPlot" in page and "trussidModeViewer(" in page
    # every figure of report.md is drawn on the page (interactive, or the PNG embedded)
    for name in s.files.figures:
        assert f"({name})" in page, name
    assert "Bode explorer" in page and "95 % intervals" in page


def _crop_std(png, rect):
    from PIL import Image

    im = np.asarray(Image.open(png).convert("L"), dtype=float)
    x, y, w, h = (int(round(v)) for v in rect)
    return im[y:y + h, x:x + w]


@pytest.mark.slow
@pytest.mark.skipif(find_chromium() is None or shutil.which("unshare") is None,
                    reason="needs chromium and unshare (scripts/setup.sh test)")
def test_report_html_in_headless_chromium_without_network(quick_report):
    """Opened from the file with no network: nothing is requested (the browser's resource
    timing lists nothing and its log names no failed request), the 3-D view and the Bode
    explorer are drawn (pixel variance in their areas), and selecting mode 3 instead of 1
    changes the 3-D view (while the same mode twice gives the same picture)."""
    out, _ = quick_report
    page = out / "report.html"
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    run = open_page(page, "probe&mode=1&phase=0.25", dump_dom=True)
    assert run.probe is not None, run.log
    assert run.probe["resources"] == []
    assert not [ln for ln in run.log if "net::ERR_" in ln or "Failed to load" in ln]
    viewer, bode = run.probe["viewer"][0], run.probe["figures"][0]
    shots = {}
    for name, frag in (("mode1", "mode=1&phase=0.25"), ("mode3", "mode=3&phase=0.25"),
                       ("mode1_again", "mode=1&phase=0.25")):
        png = ARTEFACTS / f"report_{name}.png"
        png.unlink(missing_ok=True)
        shot = open_page(page, frag, screenshot=png)
        assert not [ln for ln in shot.log if "net::ERR_" in ln]
        shots[name] = png
    v1, v3, v1b = (_crop_std(shots[k], viewer) for k in ("mode1", "mode3", "mode1_again"))
    assert v1.std() > 8.0 and v3.std() > 8.0            # the 3-D view is drawn
    assert _crop_std(shots["mode1"], bode).std() > 8.0  # so is the Bode explorer
    changed = np.mean(np.abs(v1 - v3) > 24)
    same = np.mean(np.abs(v1 - v1b) > 24)
    assert changed > 0.005 and same < changed / 5, (changed, same)
