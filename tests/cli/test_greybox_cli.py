"""`trussid greybox dc-motor`: JSON schema, honest nulls, flywheel inertia, clear errors."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from trussid.cli import main

# Adewusi (2016) values
J, R, B, K = 9.85e-3, 6.29, 2.52e-3, 1.57e-2


def run(*args):
    return subprocess.run([sys.executable, "-m", "trussid", "greybox", *args],
                          capture_output=True, text=True, timeout=300)


def write_motor_csv(path, J_true=J, seed=3, noise=0.01):
    """Square-wave speed data from the exact sampled first-order solution."""
    den = B * R + K**2
    T, G = J_true * R / den, K / den
    fs, n = 10.0, 1200
    t = np.arange(n) / fs
    u = np.where((t // (5 * T)) % 2 == 0, 3.25, -3.25)
    a = np.exp(-1 / (fs * T))
    y = np.zeros(n)
    for i in range(n - 1):
        y[i + 1] = a * y[i] + G * (1 - a) * u[i]
    y += noise * np.sqrt(np.mean(y**2)) * np.random.default_rng(seed).standard_normal(n)
    np.savetxt(path, np.column_stack([t, u, y]), delimiter=",", header="t,u,y", comments="")
    return T, G


@pytest.fixture(scope="module")
def motor_csv(tmp_path_factory):
    path = tmp_path_factory.mktemp("gb") / "motor.csv"
    T, G = write_motor_csv(path)
    return path, T, G


def test_json_with_inertia_only_reports_T_G_and_nulls_the_undetermined(motor_csv):
    path, T, G = motor_csv
    res = run("dc-motor", str(path), "--inertia", str(J), "--json", "--starts", "3")
    assert res.returncode == 0, res.stderr
    d = json.loads(res.stdout)
    assert abs(d["T"] / T - 1) < 0.01 and abs(d["G"] / G - 1) < 0.01
    assert set(d["parameters"]) == {"J", "b", "R", "k"}
    assert d["parameters"]["J"] == J
    assert d["parameters"]["R"] is None and d["parameters"]["k"] is None
    assert d["undetermined"] and any("R" in c and "k" in c for c in d["undetermined"])
    assert set(d["intervals"]) == {"J", "b", "R", "k"}


def test_json_with_resistance_determines_all_four(motor_csv):
    path, T, G = motor_csv
    res = run("dc-motor", str(path), "--inertia", str(J), "--resistance", str(R), "--json",
              "--starts", "1")
    assert res.returncode == 0, res.stderr
    d = json.loads(res.stdout)
    assert d["undetermined"] == []
    for name, value in {"J": J, "b": B, "R": R, "k": K}.items():
        assert abs(d["parameters"][name] / value - 1) < 0.02, name
    lo, hi = d["intervals"]["k"]
    assert lo < d["parameters"]["k"] < hi


def test_flywheel_dimensions_give_J_from_the_solid(tmp_path):
    dims = (0.1, 0.02, 0.01, 0.2, 7850.0)
    rd, td, rs, ls, rho = dims
    J_fly = 0.5 * rho * math.pi * (rd**4 * td + rs**4 * (ls - td))  # closed form
    path = tmp_path / "fly.csv"
    write_motor_csv(path, J_true=J_fly)
    res = run("dc-motor", str(path), "--flywheel", "0.1,0.02,0.01,0.2", "--resistance",
              str(R), "--json", "--starts", "1")
    assert res.returncode == 0, res.stderr
    d = json.loads(res.stdout)
    assert d["parameters"]["J"] == pytest.approx(J_fly, rel=5e-3)
    assert d["parameters"]["k"] == pytest.approx(K, rel=0.02)


def test_human_readable_output_names_what_is_not_determined(motor_csv, capsys):
    path, _, _ = motor_csv
    assert main(["greybox", "dc-motor", str(path), "--inertia", str(J), "--starts", "2"]) == 0
    out = capsys.readouterr().out
    assert "T =" in out and "NOT determined" in out and "R*k" in out


def test_bad_input_from_a_subprocess_is_one_line_exit_2_no_traceback(tmp_path):
    path = tmp_path / "one.csv"
    path.write_text("t,u,y\n0,1,0\n")
    res = run("dc-motor", str(path), "--inertia", "0.01")
    assert res.returncode == 2
    assert "Traceback" not in res.stderr
    lines = res.stderr.strip().splitlines()
    assert lines == [f"trussid greybox: error: {path}: data too short: 1 sample row(s), "
                     "need at least 10"]


@pytest.mark.parametrize(
    ("content", "extra", "pattern"),
    [
        ("t,u,y\n0,1,0\n", [], "data too short"),
        ("t,u,speed\n" + "".join(f"{i},1,0\n" for i in range(20)), [], "column 'y' missing"),
        ("t,u,y\n" + "".join(f"{i},1,0\n" for i in range(5)) + "5,one,0\n"
         + "".join(f"{i},1,0\n" for i in range(6, 20)), [], "row 7, column 'u'"),
        ("t,u,y\n" + "".join(f"{i},1,{i}\n" for i in range(20)), ["--flywheel", "0.1,0.02"],
         "flywheel dimensions"),
        ("t,u,y\n" + "".join(f"{i},1,{i}\n" for i in range(20)), ["--flywheel",
         "0.1,0.02,0.2,0.3"], "flywheel.shaft_radius"),
    ],
)
def test_bad_input_is_one_line_exit_2_no_traceback(tmp_path, content, extra, pattern, capsys):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    args = extra or ["--inertia", "0.01"]
    assert main(["greybox", "dc-motor", str(path), *args]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("trussid greybox: error:")
    assert pattern in lines[0]


def test_missing_data_file_is_a_clean_error(tmp_path, capsys):
    assert main(["greybox", "dc-motor", str(tmp_path / "nope.csv"), "--inertia", "0.01"]) == 2
    assert "nope.csv" in capsys.readouterr().err


def test_inertia_and_flywheel_are_exclusive_and_one_is_required(motor_csv, capsys):
    path, _, _ = motor_csv
    for args in ([], ["--inertia", "0.01", "--flywheel", "0.1,0.02,0.01,0.2"]):
        with pytest.raises(SystemExit) as exc:
            main(["greybox", "dc-motor", str(path), *args])
        assert exc.value.code == 2
    assert "not allowed" in capsys.readouterr().err


def test_help_documents_the_flywheel_format(capsys):
    with pytest.raises(SystemExit):
        main(["greybox", "dc-motor", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "disc radius, disc thickness, shaft radius, shaft length [m]" in text
    assert "7850" in text
