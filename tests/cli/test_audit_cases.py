"""Cases of the newcomer audit (shared docs/newcomer-audit.md, section 4) that gave a wrong
cause, a traceback or a silent wrong result: each now ends in one line naming the real
cause, exit status 2, no traceback and no output file (issue 19, acceptance 1).

Lab-file readers, file permissions and ``render --out`` directories are tested with those
modules (issue 16b)."""

import subprocess
import sys

import control
import numpy as np
import pytest

from trussid.cli import main
from trussid.plid.modelfile import save_model


def run(*args, env=None):
    return subprocess.run([sys.executable, "-m", "trussid", *map(str, args)],
                          capture_output=True, text=True, env=env)


def one_line(code, err, cmd, match):
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith(f"trussid {cmd}: error: "), err
    assert match in lines[0], lines[0]


def mode_pair(radius, f_hz=50.0, dt=1e-3, m=1, p=1, seed=0):
    """One discrete mode of pole radius ``radius`` at ``f_hz``, random B and C."""
    rng = np.random.default_rng(seed)
    th = 2 * np.pi * f_hz * dt
    A = radius * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    return control.ss(A, rng.standard_normal((2, m)), rng.standard_normal((p, 2)),
                      np.zeros((p, m)), dt)


def test_b29_negative_scientific_value_after_an_option_reaches_the_real_check(tmp_path, capsys):
    code = main(["render", "--scale", "-1e9", "--out", str(tmp_path / "r.png")])
    one_line(code, capsys.readouterr().err, "render", "scale must be a finite number >= 0")
    assert not (tmp_path / "r.png").exists()


def test_b96_negative_list_after_an_option_reaches_the_real_check(tmp_path, capsys):
    csv = tmp_path / "m.csv"
    csv.write_text("t,u,y\n0,0,0\n")
    code = main(["greybox", "dc-motor", str(csv), "--flywheel", "-0.1,0.02,0.01,0.2"])
    one_line(code, capsys.readouterr().err, "greybox",
             "flywheel.disc_radius must be a positive number")


def test_b50_simulate_refuses_an_unstable_plant_saying_so(tmp_path, capsys):
    plant = tmp_path / "unstable.npz"
    with pytest.warns(UserWarning, match="unstable"):
        save_model(plant, mode_pair(1.5))
    out = tmp_path / "d.csv"
    code = main(["simulate", str(plant), "--out", str(out)])
    one_line(code, capsys.readouterr().err, "simulate",
             f"the plant {plant} is unstable: 2 pole(s) outside the unit circle")
    assert not out.exists()


def test_b51_too_many_samples_is_refused_with_the_memory_estimate(tmp_path, capsys):
    """Was a 20-line MemoryError traceback; 1e12 samples cannot fit on any machine here."""
    plant = tmp_path / "p.npz"
    save_model(plant, mode_pair(0.9))
    out = tmp_path / "d.npz"
    code = main(["simulate", str(plant), "--samples", "1e12", "--out", str(out)])
    err = capsys.readouterr().err
    one_line(code, err, "simulate", "1000000000000 samples of a 2-state plant need about")
    assert "GiB of memory, but" in err and "use at most" in err
    assert not out.exists()


def test_an_out_of_memory_error_is_one_line(monkeypatch, capsys):
    """Whatever runs out of memory, the user gets one line, not numpy's traceback."""
    import trussid.cli.commands.modes as modes

    def boom(args):
        raise MemoryError("Unable to allocate 105. GiB")

    monkeypatch.setattr(modes, "run", boom)
    code = main(["modes"])
    one_line(code, capsys.readouterr().err, "modes", "out of memory (Unable to allocate 105. GiB)")


def test_memory_estimate_is_checked_against_what_is_available():
    from trussid.plid.errors import DataError
    from trussid.plid.experiment import check_memory, experiment_memory_bytes

    sys_ = mode_pair(0.9)
    need = experiment_memory_bytes(sys_, 10_000)
    assert need == 8 * 10_000 * (2 * 2 + 2 + 10 * 2)  # state trajectory + I/O copies
    check_memory(sys_, 10_000, available=need)
    with pytest.raises(DataError, match="use at most 5000 samples"):
        check_memory(sys_, 10_000, available=need // 2)


def test_b88_too_short_a_record_for_h1_names_the_record_not_the_inputs(tmp_path, capsys):
    model = tmp_path / "m.npz"
    save_model(model, mode_pair(0.9, m=3, p=3), input_names=["u1", "u2", "u3"],
               output_names=["y1", "y2", "y3"])
    rng = np.random.default_rng(1)
    rows = rng.standard_normal((20, 6))
    t = np.arange(20) * 1e-3
    csv = tmp_path / "short.csv"
    np.savetxt(csv, np.column_stack([t, rows]), delimiter=",", comments="",
               header="t,u1,u2,u3,y1,y2,y3")
    code = main(["compare", str(model), str(csv), "--out", str(tmp_path / "cmp")])
    one_line(code, capsys.readouterr().err, "compare", "20 samples give 1 Welch segment(s)")
    assert not (tmp_path / "cmp").exists()


def test_debug_and_threads_are_accepted_after_the_command(tmp_path, capsys):
    from trussid.fem.errors import ModelError

    with pytest.raises(ModelError, match="no such file"):  # --debug: the exception itself
        main(["modes", str(tmp_path / "nonexistent.bdf"), "--debug"])
    with pytest.raises(SystemExit):
        main(["modes", str(tmp_path / "nonexistent.bdf"), "--threads", "x"])
    assert "invalid int value: 'x'" in capsys.readouterr().err
    code = main(["modes", str(tmp_path / "nonexistent.bdf"), "--threads", "-1"])
    one_line(code, capsys.readouterr().err, "modes", "--threads must be a whole number >= 0")


@pytest.fixture
def unstable_vs_plant(tmp_path):
    """A 2-mode plant and the same model with A x 1.05 (every pole outside the unit circle)."""
    rng = np.random.default_rng(2)
    dt = 1e-3
    A = np.zeros((4, 4))
    for i, (f, z) in enumerate([(60.0, 0.02), (210.0, 0.02)]):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-w**2, -2 * z * w]]
    sd = control.c2d(control.ss(A, rng.standard_normal((4, 1)), rng.standard_normal((2, 4)),
                                np.zeros((2, 1))), dt)
    bad = control.ss(1.05 * sd.A, sd.B, sd.C, sd.D, dt)
    save_model(tmp_path / "plant.npz", sd, input_names=["u1"], output_names=["y1", "y2"])
    with pytest.warns(UserWarning, match="unstable"):
        save_model(tmp_path / "bad.npz", bad, input_names=["u1"], output_names=["y1", "y2"])
    return tmp_path


def test_b90_compare_says_an_unstable_model_is_unstable(unstable_vs_plant, capsys):
    d = unstable_vs_plant
    assert main(["compare", str(d / "bad.npz"), str(d / "plant.npz"), "--out",
                 str(d / "cmp")]) == 0
    cap = capsys.readouterr()
    lines = cap.err.strip().splitlines()
    assert lines == [l for l in lines if l.startswith("trussid compare: warning: ")]
    assert any(f"the model {d / 'bad.npz'} is unstable: 4 pole(s) outside the unit circle"
               in l for l in lines), cap.err
    assert "RuntimeWarning" not in cap.err and "overflow" not in cap.err
    assert "simulation fit (against noise-free outputs): none: the model is unstable" in cap.out
    import json

    m = json.loads((d / "cmp" / "metrics.json").read_text())
    assert m["stable"] is False and "is unstable" in m["stability"]


def test_b91_compare_of_an_unstable_model_against_data_leaks_no_numpy_warning(
        unstable_vs_plant, capsys):
    d = unstable_vs_plant
    assert main(["simulate", str(d / "plant.npz"), "--out", str(d / "val.csv"),
                 "--samples", "2000", "--seed", "1"]) == 0
    capsys.readouterr()
    assert main(["compare", str(d / "bad.npz"), str(d / "val.csv"), "--out",
                 str(d / "cmp2")]) == 0
    cap = capsys.readouterr()
    assert "is unstable" in cap.err and "RuntimeWarning" not in cap.err
    assert "overflow" not in cap.err and "none: the model is unstable" in cap.out


def test_help_descriptions_show_a_single_percent_sign(capsys):
    """argparse %-formats help strings but not descriptions: '63.2 %%' showed doubled."""
    with pytest.raises(SystemExit):
        main(["greybox", "dc-motor", "--help"])
    out = capsys.readouterr().out
    assert "63.2 % rule" in out and "%%" not in out
    with pytest.raises(SystemExit):
        main(["identify", "--help"])
    out = capsys.readouterr().out
    assert "70 % of the record" in " ".join(out.split()) and "%%" not in out


def test_b35_a_slow_sample_rate_is_told_which_filters_it_cannot_show(tmp_path, capsys):
    assert main(["plant", "--fs", "100", "--out", str(tmp_path / "p100.npz")]) == 0
    err = capsys.readouterr().err
    assert "corner of the low-pass (120 Hz) lies above the Nyquist frequency (50 Hz)" in err


def test_the_default_plant_does_not_warn_about_its_own_lab(tmp_path, capsys):
    """Issue 30 (newcomer D7): `trussid plant --out P.npz` warned that the thesis lab's
    1300 Hz smoothing filter lies above the 800 Hz Nyquist frequency, where a D/A smoother
    belongs."""
    assert main(["plant", "--out", str(tmp_path / "p.npz")]) == 0
    assert capsys.readouterr().err == ""
