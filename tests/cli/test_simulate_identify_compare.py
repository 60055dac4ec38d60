"""``trussid simulate``, ``identify`` and ``compare``: a small plant end to end, and bad input
ending in one line on stderr, exit status 2, no traceback and no output file."""

import json
import subprocess
import sys

import control
import numpy as np
import pytest

from trussid.plid.datafile import IOData, read_data, write_data
from trussid.plid.metrics import prediction_ratio_db
from trussid.plid.modelfile import load_model, save_model
from trussid.cli import main

FS = 1000.0
MODES = [(60.0, 0.02), (210.0, 0.02)]


def small_plant():
    """Two modes, 1 input, 2 outputs (continuous and its ZOH equivalent at 1 kHz)."""
    A = np.zeros((4, 4))
    for i, (f, z) in enumerate(MODES):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-w**2, -2 * z * w]]
    B = np.array([[0], [1.0], [0], [0.7]])
    C = np.array([[4e4, 0, 6e4, 0], [1e5, 0, -3e4, 0]])
    sc = control.ss(A, B, C, np.zeros((2, 1)))
    return sc, control.c2d(sc, 1 / FS)


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "trussid", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd)


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    d = tmp_path_factory.mktemp("sic")
    sc, sd = small_plant()
    save_model(d / "plant.npz", sd, input_names=["pzt"], output_names=["acc1", "acc2"],
               continuous=sc)
    return d


def assert_clean_failure(res, cmd, *absent, match=None):
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith(f"trussid {cmd}: error: ")
    assert "Traceback" not in res.stderr
    if match:
        assert match in lines[0], lines[0]
    for path in absent:
        assert not path.exists(), path


# ------------------------------------------------------------------ success path


@pytest.fixture(scope="module")
def simulated(work):
    res = run("simulate", work / "plant.npz", "--out", work / "data.npz", "--samples", 2000,
              "--snr-db", 40, "--bits", 16, "--full-scale", 20, "--seed", 3, "--json")
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


def test_simulate_writes_data_with_the_plant_channels_and_reports_clipping(work, simulated):
    data = read_data(work / "data.npz")
    assert data.u.shape == (2000, 1) and data.y.shape == (2000, 2)
    assert data.fs == FS
    assert data.input_names == ["pzt"] and data.output_names == ["acc1", "acc2"]
    assert simulated["clipping"] == {"dac": [0], "adc": [0, 0]}
    # 40 dB sensor noise on top of the noise-free response that the file also carries
    noise = data.y - data.y_clean
    snr = 20 * np.log10(np.sqrt(np.mean(data.y_clean**2, 0) / np.mean(noise**2, 0)))
    np.testing.assert_allclose(snr, 40.0, atol=0.3)  # 16-bit quantisation adds a little


def test_simulate_counts_clipping_in_its_report(work, capsys):
    out = work / "clipped.csv"
    assert main(["simulate", str(work / "plant.npz"), "--out", str(out), "--samples", "500",
                 "--bits", "12", "--full-scale", "1.0", "--rms", "1.0"]) == 0
    captured = capsys.readouterr()
    stdout = captured.out
    d = read_data(out)
    expected = int(np.sum(np.abs(d.u[:, 0]) >= 1.0 - 2 / 4096))  # samples at the end codes
    assert f"D/A: 12 bits, +-1 V; clipped samples: {expected} of 500" in stdout
    assert expected > 100  # a 1 V-rms Gaussian exceeds +-1 V in a third of the samples
    assert "trussid simulate: warning: the converters clipped" in captured.err


def test_simulate_warns_when_outputs_drown_in_quantisation_and_auto_ranges(tmp_path, capsys):
    sc, sd = small_plant()
    tiny = tmp_path / "tiny.npz"
    save_model(tiny, sd * 1e-6, output_names=["acc1", "acc2"])  # microvolt outputs
    out = tmp_path / "d.npz"
    assert main(["simulate", str(tiny), "--out", str(out), "--samples", "300",
                 "--bits", "12"]) == 0
    stderr = capsys.readouterr().err
    assert "warning: output acc1 has RMS" in stderr and "under 4 A/D LSB" in stderr
    assert not read_data(out).y.any()  # all zero: the warning was deserved
    assert main(["simulate", str(tiny), "--out", str(out), "--samples", "300", "--bits", "12",
                 "--adc-full-scale", "auto"]) == 0
    stdout = capsys.readouterr().out
    assert "A/D: 12 bits, auto (+-4 RMS per output)" in stdout and "under 4" not in stdout
    y = read_data(out).y
    assert np.unique(y[:, 0]).size > 100  # the record now resolves the signal


@pytest.fixture(scope="module")
def identified(work, simulated):
    res = run("identify", work / "data.npz", "--order", 4, "--out", work / "model.npz", "--json")
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


def test_identify_json_lists_each_mode_with_its_95_percent_intervals(identified):
    # one entry per complex pair, the interval around the estimate; the true values within
    # twice the half-width (a single record: the 95 % coverage itself is measured over 210
    # records by benchmarks/bench_uncertainty.py)
    modes = identified["modes"]
    assert len(modes) == len(MODES)
    for mo, (f, z) in zip(modes, MODES):
        assert set(mo) == {"frequency_hz", "frequency_ci95_hz", "damping_ratio",
                           "damping_ratio_ci95"}
        lo, hi = mo["frequency_ci95_hz"]
        zl, zh = mo["damping_ratio_ci95"]
        assert lo < mo["frequency_hz"] < hi and zl < mo["damping_ratio"] < zh
        assert 0 < hi - lo < 0.01 * f
        assert abs(mo["frequency_hz"] - f) < (hi - lo)
        assert abs(mo["damping_ratio"] - z) < (zh - zl)


def test_identify_finds_the_modes_and_reports_the_prediction_ratio(work, identified):
    model, meta = load_model(work / "model.npz")
    assert model.nstates == 4 and model.dt == pytest.approx(1 / FS)
    assert meta.K is not None and meta.output_names == ["acc1", "acc2"]
    freqs = [p["frequency_hz"] for p in identified["poles"]]
    np.testing.assert_allclose(freqs, [60.0, 210.0], rtol=2e-3)
    # The reported ratio is the documented metric of the saved model on the same data.
    data = read_data(work / "data.npz")
    r = prediction_ratio_db(model, data.u, data.y, K=meta.K,
                            skip=identified["prediction_skip_samples"])
    assert identified["signal_to_prediction_error_db"] == pytest.approx(r.overall, rel=1e-9)
    assert identified["signal_to_prediction_error_db"] > 20.0


def test_identify_via_higher_orders_keeps_the_best_predicting_candidate(work, simulated):
    out = work / "model_via.npz"
    res = run("identify", work / "data.npz", "--order", 4, "--out", out, "--via", "8",
              "--json")
    assert res.returncode == 0, res.stderr
    summary = json.loads(res.stdout)
    assert summary["via"] == [8]
    labels = [c["label"] for c in summary["candidates"]]
    assert labels[0].startswith("direct 4") and any(lab.startswith("via 8") for lab in labels)
    scored = [c for c in summary["candidates"] if c["identification_ratio_db"] is not None]
    assert summary["chosen"] == max(scored, key=lambda c: c["identification_ratio_db"])["label"]
    model, meta = load_model(out)
    assert model.nstates == 4
    data = read_data(work / "data.npz")
    r = prediction_ratio_db(model, data.u, data.y, K=meta.K,
                            skip=summary["prediction_skip_samples"])
    assert summary["signal_to_prediction_error_db"] == pytest.approx(r.overall, rel=1e-9)


@pytest.mark.parametrize("via, match", [("5", "multiples of the 2 outputs"),
                                        ("2", "must exceed --order 4"),
                                        ("six", "comma-separated orders")])
def test_identify_refuses_bad_via_orders(work, simulated, tmp_path, via, match):
    out = tmp_path / "m.npz"
    res = run("identify", work / "data.npz", "--order", 4, "--out", out, "--via", via)
    assert_clean_failure(res, "identify", out, match=match)


def test_compare_with_the_plant_writes_plots_and_metrics(work, identified):
    out = work / "cmp_plant"
    res = run("compare", work / "model.npz", work / "plant.npz", "--out", out,
              "--band", 20, 400)
    assert res.returncode == 0, res.stderr
    names = sorted(p.name for p in out.iterdir())
    assert names == ["bode_pzt.png", "metrics.json", "poles.png"]
    for png in ("bode_pzt.png", "poles.png"):
        raw = (out / png).read_bytes()
        assert raw[:8] == b"\x89PNG\r\n\x1a\n" and len(raw) > 20_000
    m = json.loads((out / "metrics.json").read_text())
    assert m["reference_kind"] == "plant" and m["band"] == [20.0, 400.0]
    assert m["frf"]["rms_db"] < 1.0 and m["stable"]
    true_f = [row["true_frequency_hz"] for row in m["poles"]]
    np.testing.assert_allclose(true_f, [60.0, 210.0], rtol=1e-9)


def test_compare_with_validation_data(work, identified, capsys):
    out = work / "cmp_data"
    assert main(["compare", str(work / "model.npz"), str(work / "data.npz"), "--out", str(out),
                 "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m == json.loads((out / "metrics.json").read_text())
    assert m["reference_kind"] == "data"
    assert m["simulation"]["against"] == "noise-free outputs"
    assert m["prediction"]["overall"] > 20.0


def test_compare_without_a_band_measures_over_the_plants_modes_and_prints_it(work, identified):
    # Issue 34: from 0 Hz to Nyquist the headline maximum sits at anti-resonances and far
    # from the modes; the default band is the plant's modes' band, printed with the figure.
    out = work / "cmp_default_band"
    res = run("compare", work / "model.npz", work / "plant.npz", "--out", out)
    assert res.returncode == 0, res.stderr
    m = json.loads((out / "metrics.json").read_text())
    lo, hi = MODES[0][0] / 1.25, MODES[-1][0] * 1.25
    np.testing.assert_allclose(m["band"], [lo, hi], rtol=1e-3)   # the modes' discrete image
    assert "plant's modes" in m["band_source"]
    assert f"FRF error over {lo:.4g}-{hi:.4g} Hz (the plant's modes" in res.stdout
    full = work / "cmp_full_band"
    assert run("compare", work / "model.npz", work / "plant.npz", "--out", full,
               "--band", 0, FS / 2).returncode == 0
    mf = json.loads((full / "metrics.json").read_text())
    assert mf["band_source"] == "--band" and mf["frf"]["max_db"] >= m["frf"]["max_db"]


def test_compare_with_data_and_no_band_measures_over_the_excited_band(work, identified, capsys):
    out = work / "cmp_data_band"
    assert main(["compare", str(work / "model.npz"), str(work / "data.npz"), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    m = json.loads((out / "metrics.json").read_text())
    assert "excited band" in m["band_source"] and "(the excited band" in text
    # the simulated record is white: the excited band is (nearly) all of 0-Nyquist
    assert m["band"][0] < 0.05 * FS / 2 and m["band"][1] > 0.95 * FS / 2


# ------------------------------------------------------------------ bad input (subprocess)


def test_simulate_missing_plant_fails_cleanly(tmp_path):
    out = tmp_path / "d.csv"
    res = run("simulate", tmp_path / "nope.npz", "--out", out)
    assert_clean_failure(res, "simulate", out, match="no such model file")


def test_identify_order_not_multiple_of_outputs_fails_cleanly_in_the_shift_basis(work, simulated,
                                                                                tmp_path):
    out = tmp_path / "m.npz"
    res = run("identify", work / "data.npz", "--order", 3, "--out", out, "--start", "plain")
    assert_clean_failure(res, "identify", out, match="try order 2 or 4")


def test_identify_reaches_an_order_not_multiple_of_outputs_by_reduction(work, simulated, tmp_path):
    out = tmp_path / "m3.npz"
    res = run("identify", work / "data.npz", "--order", 3, "--out", out, "--json")
    assert res.returncode == 0, res.stderr
    summary = json.loads(res.stdout)
    assert "reduced to 3 states" in summary["structure"]
    assert load_model(out)[0].nstates == 3


def test_identify_json_says_whether_it_estimated_a_direct_term(work, simulated, tmp_path):
    # the simulated plant is strictly proper (D = 0): auto keeps D = 0, --direct yes forces it
    out = tmp_path / "md.npz"
    auto = json.loads(run("identify", work / "data.npz", "--order", 4, "--out", out,
                          "--json").stdout)
    assert auto["direct_term"]["mode"] == "auto" and not auto["direct_term"]["estimated"]
    assert auto["direct_term"]["test"]["held_out_nmse_with"] > 0
    assert isinstance(auto["K_source"], str)
    forced = json.loads(run("identify", work / "data.npz", "--order", 4, "--out", out,
                            "--direct", "yes", "--json").stdout)
    assert forced["direct_term"]["estimated"] and forced["direct_term"]["mode"] is True
    assert np.shape(load_model(out)[0].D) == (2, 1)


def test_identify_text_names_the_prior_a_direct_term_fit_started_from(work, simulated,
                                                                       tmp_path):
    # with D estimated, the summary says which prior PLID started from, as the JSON does
    out = tmp_path / "md.npz"
    args = ("identify", work / "data.npz", "--order", 4, "--out", out, "--direct", "yes")
    start = json.loads(run(*args, "--json").stdout)["direct_term"]["start"]
    text = run(*args).stdout
    assert "direct term D: estimated" in text
    assert (f"PLID started from: {start}" in text) if start else ("started from" not in text)


def test_compare_model_and_data_of_different_sizes_fails_cleanly(work, tmp_path):
    rng = np.random.default_rng(0)
    data = write_data(IOData(u=rng.standard_normal((300, 1)), y=rng.standard_normal((300, 3)),
                             fs=FS), tmp_path / "three.npz")
    out = tmp_path / "cmp"
    res = run("compare", work / "plant.npz", data, "--out", out)
    assert_clean_failure(res, "compare", out,
                         match="the model has 1 input(s) and 2 output(s) but the data has 1 "
                               "and 3")


# ------------------------------------------------------------------ bad input (in process)


def cli(capsys, *args):
    code = main([str(a) for a in args])
    err = capsys.readouterr().err.strip().splitlines()
    return code, err


@pytest.mark.parametrize("case", ["wrong_shape_plant", "continuous_only", "bad_suffix"])
def test_simulate_refuses_bad_plants_and_outputs(work, tmp_path, capsys, case):
    plant = work / "plant.npz"
    if case == "wrong_shape_plant":
        plant = tmp_path / "bad.npz"
        np.savez(plant, A=np.eye(2), B=np.ones((3, 1)), C=np.ones((1, 2)), D=np.zeros((1, 1)),
                 dt=1e-3)
        expect = "array 'B' has shape (3, 1), needs 2 rows"
    elif case == "continuous_only":
        plant = tmp_path / "c.npz"
        save_model(plant, small_plant()[0])
        expect = "a discrete one is needed"
    else:
        expect = "the data file type must be one of .csv, .npz, .mat"
    out = tmp_path / ("d.txt" if case == "bad_suffix" else "d.npz")
    code, err = cli(capsys, "simulate", plant, "--out", out)
    assert code == 2 and len(err) == 1 and expect in err[0], err
    assert not out.exists()


def test_identify_names_the_bad_sample_and_writes_nothing(tmp_path, capsys):
    rng = np.random.default_rng(1)
    data = write_data(IOData(u=rng.standard_normal((200, 1)), y=rng.standard_normal((200, 1)),
                             fs=FS), tmp_path / "d.csv")
    text = data.read_text().splitlines()
    fields = text[19].split(",")
    fields[2] = "nan"
    text[19] = ",".join(fields)  # sample 18 (line 20)
    data.write_text("\n".join(text) + "\n")
    out = tmp_path / "m.npz"
    code, err = cli(capsys, "identify", data, "--order", 2, "--out", out)
    assert code == 2 and len(err) == 1
    assert "column 'y1' has a non-finite value (nan) at sample 18" in err[0]
    assert not out.exists()


def test_identify_refuses_too_few_samples_and_unknown_columns(work, simulated, tmp_path,
                                                              capsys):
    out = tmp_path / "m.npz"
    rng = np.random.default_rng(2)
    short = write_data(IOData(u=rng.standard_normal((20, 1)), y=rng.standard_normal((20, 2)),
                              fs=FS), tmp_path / "short.npz")
    code, err = cli(capsys, "identify", short, "--order", 8, "--out", out)
    assert code == 2 and "only 20 samples for 24 parameters" in err[0], err
    code, err = cli(capsys, "identify", work / "data.npz", "--order", 4, "--out", out,
                    "--outputs", "acc3")
    assert code == 2 and "unknown column 'acc3'; did you mean" in err[0], err
    code, err = cli(capsys, "identify", tmp_path / "absent.csv", "--order", 4, "--out", out)
    assert code == 2 and "no such data file" in err[0], err
    assert not out.exists()


def test_compare_refuses_foreign_files_and_rates(work, tmp_path, capsys):
    out = tmp_path / "cmp"
    junk = tmp_path / "junk.npz"
    np.savez(junk, q=np.ones(3))
    code, err = cli(capsys, "compare", work / "plant.npz", junk, "--out", out)
    assert code == 2 and "neither a model file" in err[0], err
    other = tmp_path / "fast.npz"
    save_model(other, control.c2d(small_plant()[0], 1 / 2000))
    code, err = cli(capsys, "compare", work / "plant.npz", other, "--out", out)
    assert code == 2 and "the model samples at 1000 Hz but the plant at 2000 Hz" in err[0], err
    code, err = cli(capsys, "compare", tmp_path / "none.npz", work / "plant.npz", "--out", out)
    assert code == 2 and "no such model file" in err[0], err
    assert not out.exists()


def test_simulate_offers_exactly_the_excitations_and_formats_plid_has():
    from trussid.plid.datafile import SUFFIXES
    from trussid.plid.experiment import EXCITATIONS
    from trussid.cli.commands import simulate

    assert simulate.EXCITATIONS == EXCITATIONS
    assert simulate.SUFFIXES == SUFFIXES
