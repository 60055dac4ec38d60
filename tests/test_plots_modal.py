"""The modal figures: stabilisation diagram and MAC matrix (drawn, saved, labelled)."""

import numpy as np
import pytest

from trussid.plid.data import ModeShapes
from trussid.plid.modal import mac
from trussid.plid.stabilisation_diagram import Stabilisation
from trussid.plots import mac_figure, save_figure, stabilisation_figure


def _stab():
    modes, status, runs = [], [], []
    for n, extra in ((4, []), (6, [80.0]), (8, [95.0])):
        f = np.array([10.0, 40.0] + extra)
        modes.append(ModeShapes(f, np.full(f.size, 0.01), np.eye(3)[:, :f.size]))
        st = np.array(["new"] * f.size if n == 4 else ["s", "fd"] + ["new"] * len(extra),
                      dtype=object)
        status.append(st)
        runs.append((st == "s").astype(int))
    return Stabilisation(orders=[4, 6, 8], modes=modes, status=status, runs=runs,
                         tolerances={"f": 0.01, "damping": 0.05, "mac": 0.98})


def test_stabilisation_diagram_puts_every_pole_at_its_order_and_frequency(tmp_path):
    f = np.linspace(0, 100, 201)
    H = (1 / (1 - (f / 10) ** 2 + 0.02j * f / 10))[:, None, None]
    fig = stabilisation_figure(_stab(), frf=(f, H))
    ax = fig.axes[0]
    points = sorted((float(x), float(y)) for line in ax.lines
                    for x, y in zip(line.get_xdata(), line.get_ydata()))
    assert points == sorted([(10, 4), (40, 4), (10, 6), (40, 6), (80, 6), (10, 8), (40, 8),
                             (95, 8)])
    labels = ax.get_legend_handles_labels()[1]
    assert labels == ["new pole", "d: + damping stable", "s: all stable"]
    assert ax.get_xlabel() == "frequency [Hz]" and "order" in ax.get_ylabel()
    assert fig.axes[1].get_ylabel() == "sum of |FRF| [dB]"
    save_figure(fig, tmp_path / "stab.png")
    assert (tmp_path / "stab.png").read_bytes()[:4] == b"\x89PNG"


def test_stabilisation_diagram_draws_the_95_percent_intervals_as_error_bars():
    from trussid.plid.uncertainty import Z95

    stab = _stab()
    stab.frequency_std = [np.full(m.n_modes, np.nan) for m in stab.modes]
    stab.frequency_std[2] = np.array([0.1, 0.5, np.nan])      # order 8: two poles with one
    fig = stabilisation_figure(stab)
    ax = fig.axes[0]
    bars = [c for c in ax.collections if len(c.get_segments())]
    assert len(bars) == 1
    segs = sorted((float(s[0][0]), float(s[1][0]), float(s[0][1])) for s in bars[0].get_segments())
    np.testing.assert_allclose(segs, [(10 - Z95 * 0.1, 10 + Z95 * 0.1, 8),
                                      (40 - Z95 * 0.5, 40 + Z95 * 0.5, 8)])
    assert "95 % frequency interval" in ax.get_legend_handles_labels()[1]
    # the poles themselves are where they were
    points = sorted((float(x), float(y)) for line in ax.lines
                    for x, y in zip(line.get_xdata(), line.get_ydata()))
    assert len(points) == 8


def test_mac_plot_shows_each_value_and_the_frequencies(tmp_path, rng):
    phi = rng.standard_normal((5, 3))
    M = mac(phi, phi)
    fig = mac_figure(M, [10.0, 20.0, 30.5], [10.1, 20.2, 30.4], "PLID", "FE")
    ax = fig.axes[0]
    assert sorted(t.get_text() for t in ax.texts if t.get_text() == "1.00") == ["1.00"] * 3
    assert [t.get_text() for t in ax.get_yticklabels()] == ["1: 10.0", "2: 20.0", "3: 30.5"]
    assert ax.get_xlabel() == "FE (mode: Hz)"
    np.testing.assert_allclose(ax.images[0].get_array(), M)
    save_figure(fig, tmp_path / "mac.png")
    assert (tmp_path / "mac.png").stat().st_size > 1000
