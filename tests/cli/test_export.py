"""``trussid export``: a model file out to MATLAB (.mat) and python-control (.py code).

Checked independently of the writer: the .mat file is read back with scipy.io.loadmat (the
MATLAB v5 format Octave and MATLAB read), and the .py file is executed in a fresh namespace;
the frequency responses of what comes back equal the model's."""

import subprocess
import sys

import control
import numpy as np
import pytest
import scipy.io

from trussid.cli import main
from trussid.plid.modelfile import load_model, save_model

DT = 1e-3


def plant():
    """A continuous two-mode plant (1 input, 2 outputs) and its ZOH equivalent."""
    A = np.zeros((4, 4))
    for i, (f, z) in enumerate([(60.0, 0.02), (210.0, 0.01)]):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-w**2, -2 * z * w]]
    sc = control.ss(A, [[0], [1.0], [0], [0.7]], [[4e4, 0, 6e4, 0], [1e5, 0, -3e4, 0]],
                    np.zeros((2, 1)))
    return sc, control.c2d(sc, DT)


@pytest.fixture
def files(tmp_path):
    sc, sd = plant()
    K = np.arange(8.0).reshape(4, 2) / 7
    save_model(tmp_path / "m.npz", sd, K=K, input_names=["pzt 1"], output_names=["acc1", "acc2"],
               continuous=sc)
    return tmp_path, sd, sc, K


def test_mat_file_holds_abcd_ts_k_names_and_the_continuous_model(files, capsys):
    d, sd, sc, K = files
    assert main(["export", str(d / "m.npz"), "--to", str(d / "m.mat")]) == 0
    out = capsys.readouterr().out
    assert "s = load('m.mat'); G = ss(s.A, s.B, s.C, s.D, s.Ts, 'InputName'" in out
    mat = scipy.io.loadmat(d / "m.mat")
    for k in "ABCD":
        np.testing.assert_array_equal(mat[k], getattr(sd, k))
        np.testing.assert_array_equal(mat[k + "c"], getattr(sc, k))
    assert mat["Ts"].item() == DT
    np.testing.assert_array_equal(mat["K"], K)
    assert [str(c[0]) for c in mat["InputName"].ravel()] == ["pzt 1"]
    assert [str(c[0]) for c in mat["OutputName"].ravel()] == ["acc1", "acc2"]


def test_continuous_export_has_ts_zero(files, capsys):
    d, _, sc, _ = files
    assert main(["export", str(d / "m.npz"), "--continuous", "--to", str(d / "c.mat")]) == 0
    mat = scipy.io.loadmat(d / "c.mat")
    assert mat["Ts"].item() == 0.0 and "K" not in mat
    np.testing.assert_array_equal(mat["A"], sc.A)


def test_python_file_rebuilds_the_same_system_with_names(files, capsys):
    d, sd, _, K = files
    assert main(["export", str(d / "m.npz"), "--to", str(d / "exported.py")]) == 0
    ns = {}
    exec(compile((d / "exported.py").read_text(), "exported.py", "exec"), ns)
    model = ns["model"]
    assert isinstance(model, control.StateSpace) and model.dt == DT
    assert list(model.input_labels) == ["pzt 1"] and list(model.output_labels) == ["acc1", "acc2"]
    np.testing.assert_array_equal(ns["K"], K)
    z = np.exp(2j * np.pi * np.linspace(1, 499, 50) * DT)
    np.testing.assert_array_equal(model(z), sd(z))  # repr round-trips every double


@pytest.mark.slow  # a fresh interpreter importing python-control: seconds on a loaded machine
def test_python_code_needs_nothing_of_trussid(files, capsys):
    d, _, _, _ = files
    assert main(["export", str(d / "m.npz"), "--python"]) == 0
    stdout = capsys.readouterr().out
    assert "trussid" not in "".join(l for l in stdout.splitlines() if "import" in l)
    code = stdout + "\nprint(model.nstates, model.ninputs, model.noutputs)\n"
    run = subprocess.run([sys.executable, "-I", "-c", code], capture_output=True, text=True,
                         check=True)
    assert run.stdout.split() == ["4", "1", "2"]


@pytest.mark.parametrize("args, match", [
    (["--to", "m.txt"], "give a .mat (MATLAB) or .py (python-control) file"),
    (["--to", "x.mat", "--continuous"], "no continuous model in the file"),
])
def test_bad_export_requests_are_one_line(tmp_path, capsys, args, match):
    save_model(tmp_path / "d.npz", plant()[1])
    code = main(["export", str(tmp_path / "d.npz"), *[str(tmp_path / a) if a.endswith(
        (".txt", ".mat")) else a for a in args]])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and match in err[0], err
    assert not (tmp_path / "x.mat").exists()
