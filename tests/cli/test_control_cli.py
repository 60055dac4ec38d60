"""``trussid control`` and ``trussid closed-loop``: files in, files out, one-line errors."""

import json
import subprocess
import sys

import numpy as np
import pytest

from trussid.geometry.lab import LabSpec, lab_record
from trussid.plid.datafile import IOData, write_data
from trussid.plid.modelfile import load_model, save_model

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1] / "lqg"))
from conftest import modal_structure  # noqa: E402  (the small structure of tests/lqg)


def run(*args):
    return subprocess.run([sys.executable, "-m", "trussid", *map(str, args)],
                          capture_output=True, text=True)


class _Res:
    def __init__(self, code, err):
        self.returncode, self.stderr = code, err


def run_here(capsys, *args):
    """The command line in this process (a subprocess pays seconds of imports)."""
    from trussid.cli import main

    code = main([*map(str, args)])
    return _Res(code, capsys.readouterr().err)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    import control

    d = tmp_path_factory.mktemp("ctl")
    plant = modal_structure()
    rng = np.random.default_rng(4)
    u = rng.normal(size=(3000, 3))
    y = control.forced_response(plant, U=u.T).outputs.T
    y = y + 0.01 * np.std(y) * rng.normal(size=y.shape)
    save_model(d / "model.npz", plant)
    write_data(IOData(u, y, 1600.0, ["ch1", "ch2", "ch3"], ["acc1", "acc2", "acc3"]),
               d / "id.npz")
    return d


@pytest.mark.slow
def test_control_writes_a_named_controller_and_closed_loop_reports_on_a_plant_file(files):
    d = files
    res = run("control", d / "model.npz", "--data", d / "id.npz", "--out", d / "ctrl.npz",
              "--no-baselines")
    assert res.returncode == 0, res.stderr
    c, meta = load_model(d / "ctrl.npz")
    assert meta.input_names == ["acc1", "acc2", "acc3"]
    assert meta.output_names == ["ch1", "ch2", "ch3"]
    assert c.dt == pytest.approx(1 / 1600)
    assert "design_json" in meta.extra
    res = run("closed-loop", d / "ctrl.npz", d / "model.npz", "--out", d / "rep",
              "--samples", 500)
    assert res.returncode == 0, res.stderr
    for name in ("report.md", "summary.json", "sigma.png", "impulse.png", "poles.png",
                 "bode_ch1.png"):
        assert (d / "rep" / name).stat().st_size > 1000, name
    assert "| model | yes |" in (d / "rep" / "report.md").read_text()
    assert "model.npz records no lab" in res.stderr  # so the default testbed's, said
    # a plant file that records its lab: the loop runs behind those converters
    lab = LabSpec.from_dict({"daq": {"bits": 16, "full_scale": 5.0}})
    plant, _ = load_model(d / "model.npz")
    save_model(d / "plant16.npz", plant, extra=lab_record(lab))
    res = run("closed-loop", d / "ctrl.npz", d / "plant16.npz", "--out", d / "rep16",
              "--samples", 500)
    assert res.returncode == 0, res.stderr
    assert "records no lab" not in res.stderr
    conv = json.loads((d / "rep16" / "summary.json").read_text())["rows"]["plant16"]["converters"]
    assert conv["dac_lsb_v"] == [10.0 / 2**16] * 3 and conv["adc_lsb_v"] == [10.0 / 2**16] * 3
    assert (conv["bits"], conv["full_scale_v"], conv["sample_rate_hz"]) == (16, 5.0, 1600.0)
    assert "closed-loop simulation (16-bit converters)" in (d / "rep16" / "report.md").read_text()


@pytest.mark.parametrize("args, message", [
    (["--target-damping", "1.5"], "--target-damping must lie in (0, 1)"),
    (["--target-damping", "0"], "--target-damping must lie in (0, 1)"),
    (["--band", "400", "500"], "band 400-500 Hz holds no lightly damped mode"),
])
def test_control_bad_requests_fail_in_one_line_without_output(files, args, message, capsys):
    d = files
    out = d / "bad.npz"
    res = run_here(capsys, "control", d / "model.npz", "--data", d / "id.npz", "--out", out, *args)
    assert res.returncode == 2
    assert message in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_control_refuses_unstable_and_continuous_models(files, tmp_path, capsys):
    import control

    d = files
    p = modal_structure()
    with pytest.warns(Warning, match="unstable"):  # save_model warns; control refuses
        save_model(tmp_path / "unstable.npz", control.ss(1.01 * np.asarray(p.A), p.B, p.C, p.D,
                                                         p.dt, inputs=["ch1", "ch2", "ch3"],
                                                         outputs=["acc1", "acc2", "acc3"]))
    save_model(tmp_path / "cont.npz", control.ss(-np.eye(2), np.ones((2, 3)), np.ones((3, 2)),
                                                 np.zeros((3, 3)), inputs=["ch1", "ch2", "ch3"],
                                                 outputs=["acc1", "acc2", "acc3"]))
    for name, message in (("unstable.npz", "unstable"), ("cont.npz", "continuous")):
        res = run_here(capsys, "control", tmp_path / name, "--data", d / "id.npz", "--out", tmp_path / "c.npz")
        assert res.returncode == 2 and message in res.stderr, res.stderr
        assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "c.npz").exists()


def test_closed_loop_refuses_a_plant_whose_names_do_not_match(files, tmp_path, capsys):
    from trussid.lqg import decentralised

    d = files
    p = modal_structure()
    save_model(tmp_path / "ctrl.npz", decentralised("static", 0.1, p.dt, ["acc1", "acc2", "acc3"],
                                                    ["ch1", "ch2", "ch3"]))
    save_model(tmp_path / "other.npz", p, input_names=["a", "b", "c"],
               output_names=["acc1", "acc2", "acc3"])
    res = run_here(capsys, "closed-loop", tmp_path / "ctrl.npz", tmp_path / "other.npz", "--out",
                   tmp_path / "rep")
    assert res.returncode == 2
    assert "other: controller output 'ch1' is not a plant input" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "rep").exists()


def test_closed_loop_margins_equal_a_frequency_by_frequency_computation_on_numpy_2(files,
                                                                                   capsys):
    """Issue 30: the `closed-loop` command's disk margins failed on numpy 2. Its MIMO and
    loop-at-a-time margins (summary.json) against 2-D numpy at each frequency and a
    D-scaled mu (tests/lqg/conftest.py), on the command's own frequency grid."""
    from conftest import reference_disk_margins

    from trussid.lqg.evaluate import margin_grid

    assert int(np.__version__.split(".")[0]) >= 2
    d = files
    assert run_here(capsys, "control", d / "model.npz", "--data", d / "id.npz", "--out",
                    d / "c_np2.npz", "--no-baselines").returncode == 0
    res = run_here(capsys, "closed-loop", d / "c_np2.npz", d / "model.npz", "--out",
                   d / "rep_np2", "--samples", 1000)
    assert res.returncode == 0, res.stderr
    (row,) = json.loads((d / "rep_np2" / "summary.json").read_text())["rows"].values()
    m = row["margins"]
    plant, _ = load_model(d / "model.npz")
    ctrl, _ = load_model(d / "c_np2.npz")
    f = margin_grid([plant, ctrl], plant.dt)  # the grid is the command's; the margins are not
    assert m["n_frequencies"] == f.size
    ref = reference_disk_margins(plant, ctrl, f)
    assert m["mimo"]["alpha"] == pytest.approx(ref["mimo_alpha"], rel=1e-7)
    assert [lp["alpha"] for lp in m["loops"]] == pytest.approx(ref["loop_alpha"], rel=1e-9)


def test_closed_loop_given_a_model_says_it_may_not_be_a_controller(files, capsys):
    """Newcomer audit 3: `closed-loop MODEL.npz` ended in "controller input 'ch1' is not a
    plant output", which names the wrong cause."""
    d = files
    res = run_here(capsys, "closed-loop", d / "model.npz", d / "model.npz", "--out", d / "x")
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1
    assert "is it a model rather than a controller?" in res.stderr
    assert not (d / "x").exists()
