"""The command line with lab files and outputs (issues 16 and 19): audit cases L01-L07, B23,
B25 and the 0600 outputs, plus ``identify --stabilisation`` and ``--modal-table``."""

import json
import os
import stat

import control
import numpy as np
import pytest

from trussid.cli import main
from trussid.plid.datafile import IOData, write_data


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err.strip().splitlines()


@pytest.fixture(scope="module")
def two_modes():
    """A lightly damped 2-mode SISO structure at 400 Hz (31 and 87 Hz), 2000 samples."""
    fs = 400.0
    rng = np.random.default_rng(11)
    sysc = control.ss(control.tf([1e4, 0, 4e6], [1, 2 * 0.01 * 195, 195 ** 2])
                      * control.tf([1], [1, 2 * 0.02 * 547, 547 ** 2]))
    plant = control.c2d(sysc, 1 / fs)
    u = rng.standard_normal(2000)
    y = control.forced_response(plant, U=u).outputs
    y = y / np.std(y) + 1e-3 * rng.standard_normal(y.size)
    return fs, u, y


def _csv(path, header, t, u, y):
    rows = "".join(f"{a:.10g},{b:.10g},{c:.10g}\n" for a, b, c in zip(t, u, y))
    path.write_text(header + "\n" + rows)
    return path


def test_a_time_column_in_ms_is_refused_then_read_with_its_unit(tmp_path, capsys, two_modes):
    fs, u, y = two_modes
    t = np.arange(u.size) / fs
    plain = _csv(tmp_path / "ms.csv", "t,u1,y1", 1e3 * t, u, y)
    code, _, err = run(capsys, "identify", plain, "--order", 4, "--out", tmp_path / "m.npz")
    assert code == 2 and len(err) == 1 and "ms.csv: time column 't' has no unit" in err[0]
    assert not (tmp_path / "m.npz").exists()
    code, out, err = run(capsys, "identify", plain, "--order", 4, "--out", tmp_path / "m.npz",
                         "--fs", 400)
    assert code == 0 and "at 400 Hz" in out
    assert any("read as milliseconds" in line for line in err)
    unit = _csv(tmp_path / "ms_unit.csv", "t [ms],u1 [V],y1 [m/s^2]", 1e3 * t, u, y)
    code, out, _ = run(capsys, "identify", unit, "--order", 4, "--out", tmp_path / "m2.npz")
    assert code == 0 and "from 2000 samples at 400 Hz" in out


def test_channels_by_samples_mat_is_read_and_said_so(tmp_path, capsys, two_modes):
    import scipy.io

    fs, u, y = two_modes
    scipy.io.savemat(tmp_path / "transposed.mat", {"input": u[None, :], "output": y[None, :],
                                                   "Ts": 1 / fs})
    code, out, err = run(capsys, "identify", tmp_path / "transposed.mat", "--order", 4,
                         "--out", tmp_path / "m.npz")
    assert code == 0, err
    assert "from 2000 samples at 400 Hz" in out
    assert any("as channels x samples (2000 samples)" in line for line in err)


def test_outputs_get_the_permissions_the_umask_gives(tmp_path, capsys, two_modes):
    """Audit section 2 item 12: every output was 0600 (mkstemp's mode)."""
    fs, u, y = two_modes
    data = tmp_path / "d.csv"
    old = os.umask(0o022)
    try:
        write_data(IOData(u=u, y=y, fs=fs), data)
        code, _, err = run(capsys, "identify", data, "--order", 4, "--out", tmp_path / "m.npz")
    finally:
        os.umask(old)
    assert code == 0, err
    for path in (data, tmp_path / "m.npz"):
        assert stat.S_IMODE(os.stat(path).st_mode) == 0o644, path


def test_render_refuses_a_missing_directory_at_once_and_creates_none(tmp_path, capsys):
    """Audit B23: `render --out newdir/sub/r7.png` silently created newdir/sub/."""
    out = tmp_path / "newdir" / "sub" / "r7.png"
    code, _, err = run(capsys, "render", "--mode", 7, "--out", out)
    assert code == 2 and len(err) == 1
    assert f"directory {tmp_path / 'newdir' / 'sub'} does not exist" in err[0]
    assert not (tmp_path / "newdir").exists()


@pytest.mark.parametrize("command", [
    ["identify", "DATA", "--order", "4", "--out", "OUT"],
    ["simulate", "PLANT", "--out", "OUT"],
    ["plant", "--out", "OUT"],
])
def test_every_command_checks_its_output_directory_before_working(tmp_path, capsys, command,
                                                                   two_modes):
    fs, u, y = two_modes
    write_data(IOData(u=u, y=y, fs=fs), tmp_path / "d.npz")
    plant = tmp_path / "p.npz"
    from trussid.plid.modelfile import save_model

    save_model(plant, control.ss(np.array([[0.5]]), np.ones((1, 1)), np.ones((1, 1)),
                                 np.zeros((1, 1)), 1 / fs))
    suffix = ".csv" if command[0] == "simulate" else ".npz"
    argv = [{"DATA": str(tmp_path / "d.npz"), "PLANT": str(plant),
             "OUT": str(tmp_path / "nope" / f"x{suffix}")}.get(a, a) for a in command]
    code, _, err = run(capsys, *argv)
    assert code == 2 and len(err) == 1 and f"directory {tmp_path / 'nope'} does not exist" \
        in err[0], err


def test_an_unwritable_output_names_the_users_path(tmp_path, capsys, monkeypatch):
    """Audit B25: the error named the hidden temporary '/sys/.r7.notsux6_.png'."""
    import errno

    from trussid.plid.modelfile import save_model

    save_model(tmp_path / "p.npz", control.ss(np.array([[0.5]]), np.ones((1, 1)),
                                              np.ones((1, 1)), np.zeros((1, 1)), 1e-3))
    real_open = os.open

    def denied(path, flags, mode=0o777, **kw):
        if os.path.basename(path).startswith(".d."):
            raise PermissionError(errno.EACCES, "Permission denied", path)
        return real_open(path, flags, mode, **kw)

    monkeypatch.setattr(os, "open", denied)
    code, _, err = run(capsys, "simulate", tmp_path / "p.npz", "--samples", 200, "--out",
                       tmp_path / "d.csv")
    assert code == 2 and err == [f"trussid simulate: error: Permission denied: "
                                 f"{tmp_path / 'd.csv'}"]


@pytest.mark.slow
def test_identify_draws_the_stabilisation_diagram_and_the_modal_table(tmp_path, capsys,
                                                                      two_modes):
    fs, u, y = two_modes
    write_data(IOData(u=u, y=y, fs=fs, input_names=["force"], output_names=["acc"]),
               tmp_path / "d.uff")
    code, out, err = run(capsys, "identify", tmp_path / "d.uff", "--order", 4, "--out",
                         tmp_path / "m.npz", "--stabilisation", tmp_path / "stab.png",
                         "--stabilisation-orders", "2:6:1", "--modal-table", "--json")
    assert code == 0, err
    summary = json.loads(out)
    stab = summary["stabilisation"]
    assert stab["orders"] == [2, 3, 4, 5, 6] and stab["failed"] == []
    found = sorted(round(m["frequency_hz"]) for m in stab["stable_at_highest_order"])
    assert found == [31, 87]  # 195 and 547 rad/s
    assert (tmp_path / "stab.png").read_bytes()[:4] == b"\x89PNG"
    (m1, m2) = summary["modal_table"]
    assert m1["frequency_hz"] == pytest.approx(195 / (2 * np.pi), rel=1e-3)
    assert m2["damping"] == pytest.approx(0.02, rel=0.05)
    assert m1["shape"]["acc"][0] == pytest.approx(1.0)
    code, _, err = run(capsys, "identify", tmp_path / "d.uff", "--order", 4, "--out",
                       tmp_path / "m.npz", "--stabilisation", tmp_path / "stab.pdf")
    assert code == 2 and "the diagram is a .png" in err[0]


def test_identify_prints_the_modal_table_beside_the_intervals_without_json(tmp_path, capsys,
                                                                           two_modes):
    """The README's modal-analysis command, printed (the newcomer's D4: the table was written
    over the 95 % intervals, and the printed summary ended in KeyError 'frequency_ci95_hz')."""
    fs, u, y = two_modes
    write_data(IOData(u=u, y=y, fs=fs, input_names=["force"], output_names=["acc"]),
               tmp_path / "d.npz")
    code, out, err = run(capsys, "identify", tmp_path / "d.npz", "--order", 4, "--out",
                         tmp_path / "m.npz", "--modal-table")
    assert code == 0, err
    lines = out.splitlines()
    k = lines.index(next(ln for ln in lines if ln.startswith("modes with 95 % intervals")))
    f_ci = sorted(float(ln.split()[0]) for ln in lines[k + 2:k + 4])
    # the structure's two modes: 195 and 547 rad/s
    assert f_ci == pytest.approx([195 / (2 * np.pi), 547 / (2 * np.pi)], rel=2e-3)
    t = lines.index(next(ln for ln in lines if ln.startswith("modal parameters")))
    rows = [ln.split() for ln in lines[t + 2:t + 4]]  # mode, f [Hz], damping [%], ...
    assert [float(r[1]) for r in rows] == pytest.approx(f_ci, abs=1e-3)
    assert [float(r[2]) for r in rows] == pytest.approx([1.0, 2.0], rel=0.05)


def test_demo_refuses_a_missing_parent_before_any_work(tmp_path, capsys):
    """Audit B104: the demo failed only at its first write, after the plant was built."""
    code, _, err = run(capsys, "demo", "--quick", "--out", tmp_path / "nope" / "report")
    assert code == 2 and len(err) == 1
    assert f"the directory {tmp_path / 'nope'} does not exist" in err[0]
    assert not (tmp_path / "nope").exists()
