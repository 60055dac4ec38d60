"""UFF lab files: round trips to the format's precision, files made by pyuff's own writer
the way modal-test software writes them, and bad files refused naming file, record, channel."""

import numpy as np
import pytest

pyuff = pytest.importorskip("pyuff")

from trussid.cli import main  # noqa: E402
from trussid.plid.datafile import IOData, read_data, write_data  # noqa: E402
from trussid.plid.errors import DataError  # noqa: E402
from trussid.plid.frf import FRF  # noqa: E402
from trussid.plid.modal import ModeShapes  # noqa: E402
from trussid.plid.uff import Geometry, read_uff, write_uff  # noqa: E402

#: Relative precision of a double-precision 58 value (%20.11e: 12 significant digits).
DOUBLE_58 = 5e-12
#: ... of every %13.5e field (6 significant digits): 58 single precision, 55, 15, headers.
E13_5 = 5e-6


@pytest.fixture
def lab(rng):
    """1000 samples at 1024 Hz (an increment 1/1024 s that %13.5e cannot hold exactly)."""
    return IOData(u=rng.standard_normal((1000, 2)), y=1e-3 * rng.standard_normal((1000, 3)),
                  fs=1024.0, input_names=["shaker 1", "shaker 2"],
                  output_names=["acc1", "acc2", "acc3"], units={"acc1": "m/s^2"})


def test_uff58_round_trip_equals_the_original_to_the_formats_precision(tmp_path, lab):
    back = read_data(write_data(lab, tmp_path / "lab.uff"))
    np.testing.assert_allclose(back.u, lab.u, rtol=DOUBLE_58, atol=0)
    np.testing.assert_allclose(back.y, lab.y, rtol=DOUBLE_58, atol=0)
    assert back.fs == 1024.0  # 9.76563e-04 s in the header, snapped back to whole Hz
    assert back.input_names == lab.input_names and back.output_names == lab.output_names
    assert back.units == {"acc1": "m/s^2"}


def test_a_rate_that_is_no_whole_number_keeps_the_headers_six_digits(tmp_path, lab):
    lab.fs = 1000.0 / 3.0
    back = read_data(write_data(lab, tmp_path / "lab.unv"))
    assert back.fs == pytest.approx(1000.0 / 3.0, rel=E13_5)


def _lms_like_time_records(tmp_path, n=2048, fs=2048.0):
    """Time histories as LMS Test.Lab exports them (cf. pyuff's Sample_UFF58_ascii.uff):
    single precision, 'Point:+Z' ids, force marked as excitation (13), acceleration (12)."""
    rng = np.random.default_rng(7)
    force = rng.standard_normal(n)
    accs = rng.standard_normal((n, 2))
    sets = []
    for k, (name, values, kind, unit) in enumerate([
            ("Force:1:+Z", force, 13, "N"), ("Point3:+Z", accs[:, 0], 12, "g"),
            ("Point7:-Y", accs[:, 1], 12, "g")]):
        sets.append(pyuff.prepare_58(
            binary=0, id1=name, id3="18-Apr-16 13:49:58", func_type=1, rsp_ent_name=name[:10],
            rsp_node=k + 1, rsp_dir=3, ref_ent_name="NONE", ref_node=0, ref_dir=0,
            ord_data_type=2, num_pts=n, abscissa_spacing=1, abscissa_min=0.0,
            abscissa_inc=1 / fs, abscissa_spec_data_type=17, abscissa_axis_units_lab="s",
            ordinate_spec_data_type=kind, ordinate_axis_units_lab=unit,
            orddenom_spec_data_type=0, z_axis_spec_data_type=0, data=values,
            x=np.arange(n) / fs))
    path = tmp_path / "testlab.uff"
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite", force_double=False)
    return path, force, accs


def test_time_histories_written_by_pyuff_like_test_lab_are_read(tmp_path):
    path, force, accs = _lms_like_time_records(tmp_path)
    d = read_data(path)
    assert d.input_names == ["Force:1:+Z"] and d.output_names == ["Point3:+Z", "Point7:-Y"]
    assert d.fs == 2048.0 and d.units == {"Force:1:+Z": "N", "Point3:+Z": "g",
                                          "Point7:-Y": "g"}
    np.testing.assert_allclose(d.u[:, 0], force, rtol=E13_5, atol=1e-300)
    np.testing.assert_allclose(d.y, accs, rtol=E13_5, atol=1e-300)


def test_frfs_written_as_in_pyuffs_readme_example_are_read(tmp_path, rng):
    """pyuff's README writes accelerance FRFs at three response nodes for one reference."""
    f = np.linspace(0, 1000, 501)
    H = rng.standard_normal((501, 3)) + 1j * rng.standard_normal((501, 3))
    path = tmp_path / "measurement.uff"
    uf = pyuff.UFF(str(path))
    for i in range(3):
        data = pyuff.prepare_58(
            binary=0, id1="Measurement point %d" % (i + 1), rsp_node=i + 1, rsp_dir=3,
            ref_node=1, ref_dir=3, func_type=4, data=H[:, i], x=f, abscissa_spacing=1,
            abscissa_min=0.0, abscissa_inc=f[1] - f[0], abscissa_spec_data_type=18,
            ordinate_spec_data_type=12, orddenom_spec_data_type=13)
        uf.write_sets(data, mode="add")
    frf, ins, outs = read_uff(path).frf
    assert ins == ["node:1+Z"] and outs == ["node:1+Z", "node:2+Z", "node:3+Z"]
    np.testing.assert_allclose(frf.f, f, rtol=E13_5)
    np.testing.assert_allclose(frf.H[:, :, 0], H, rtol=DOUBLE_58)
    with pytest.raises(DataError, match="measurement.uff: no time histories .* it holds "
                       "frequency response functions"):
        read_data(path)


def test_frfs_modes_and_geometry_round_trip_in_one_file(tmp_path, rng):
    f = np.arange(0, 200.5, 0.5)
    H = rng.standard_normal((f.size, 2, 1)) + 1j * rng.standard_normal((f.size, 2, 1))
    modes = ModeShapes(frequencies_hz=np.array([12.5, 47.25]), damping=np.array([0.01, 0.02]),
                       shapes=rng.standard_normal((4, 2)) + 1j * rng.standard_normal((4, 2)),
                       dofs=[(1, 3), (2, 3), (3, 1), (3, 2)])
    geo = Geometry(node_ids=np.array([1, 2, 3]),
                   xyz=np.array([[0.0, 0, 0], [0.5, 0, 0], [0.5, 0.25, 0.125]]),
                   lines=[np.array([1, 2, 3])])
    path = write_uff(tmp_path / "all.uff", frf=(FRF(f=f, H=H), ["force"], ["a1", "a2"]),
                     modes=modes, geometry=geo)
    back = read_uff(path)
    frf, ins, outs = back.frf
    np.testing.assert_allclose(frf.H, H, rtol=DOUBLE_58)
    np.testing.assert_allclose(back.modes.frequencies_hz, modes.frequencies_hz, rtol=E13_5)
    np.testing.assert_allclose(back.modes.damping, modes.damping, rtol=1e-4)
    rows = [back.modes.dofs.index(d) for d in modes.dofs]
    np.testing.assert_allclose(back.modes.shapes[rows], modes.shapes, rtol=0,
                               atol=E13_5 * np.abs(modes.shapes).max() * 2)
    np.testing.assert_array_equal(back.geometry.node_ids, [1, 2, 3])
    np.testing.assert_allclose(back.geometry.xyz, geo.xyz, rtol=E13_5)
    np.testing.assert_array_equal(back.geometry.lines[0], [1, 2, 3])


# ------------------------------------------------------------------------ bad lab files


def _cli_error(capsys, path, tmp_path):
    code = main(["identify", str(path), "--order", "2", "--out", str(tmp_path / "m.npz")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert not (tmp_path / "m.npz").exists()
    return err[0]


def test_a_truncated_file_names_the_unclosed_record(tmp_path, lab, capsys):
    path = write_data(lab, tmp_path / "lab.uff")
    text = path.read_text()
    cut = text.index("    58", text.index("    58", text.index("    58") + 1) + 1)  # record 3
    (tmp_path / "cut.uff").write_text(text[:cut + 2000])
    msg = _cli_error(capsys, tmp_path / "cut.uff", tmp_path)
    assert f"{tmp_path / 'cut.uff'}: record 3 (data set 58) is not closed" in msg
    assert "truncated" in msg


def test_values_missing_inside_a_closed_record_name_record_and_channel(tmp_path, lab, capsys):
    path = write_data(lab, tmp_path / "lab.uff")
    lines = path.read_text().splitlines(keepends=True)
    starts = [k for k, ln in enumerate(lines) if ln.rstrip() == "    58"]
    del lines[starts[3] + 20: starts[3] + 30]  # 40 values of record 4 (acc2)
    (tmp_path / "short.uff").write_text("".join(lines))
    msg = _cli_error(capsys, tmp_path / "short.uff", tmp_path)
    assert "short.uff: record 4 (channel 'acc2') holds 960 values but declares 1000" in msg


def test_a_file_of_the_wrong_record_type_says_what_it_holds(tmp_path, capsys, rng):
    modes = ModeShapes(frequencies_hz=np.array([10.0]), damping=np.array([0.01]),
                       shapes=rng.standard_normal((3, 1)), dofs=[(1, 1), (1, 2), (1, 3)])
    path = write_uff(tmp_path / "modes.uff", modes=modes)
    msg = _cli_error(capsys, path, tmp_path)
    assert "modes.uff: no time histories (data set 58, function type 1)" in msg
    assert "mode shapes (55)" in msg
    # a data set type pyuff cannot parse at all is named by its record
    text = path.read_text().replace("    55", "  9999", 1)
    (tmp_path / "odd.uff").write_text(text)
    msg = _cli_error(capsys, tmp_path / "odd.uff", tmp_path)
    assert "odd.uff: no time histories" in msg and "record 1: data set 9999" in msg


def test_channels_of_different_length_are_named(tmp_path, lab, capsys):
    short = IOData(u=lab.u[:900], y=lab.y[:900], fs=lab.fs, input_names=lab.input_names,
                   output_names=lab.output_names)
    a, b = tmp_path / "a.uff", tmp_path / "b.uff"
    write_data(lab, a)
    write_data(short, b)
    blocks_b = b.read_text().split("    -1\n")
    text = a.read_text().split("    -1\n")
    # record 3 (acc1) of the 900-sample file replaces that of the 1000-sample one
    idx = [k for k, blk in enumerate(text) if blk.startswith("    58")]
    text[idx[2]] = [blk for blk in blocks_b if blk.startswith("    58")][2]
    (tmp_path / "mixed.uff").write_text("    -1\n".join(text))
    msg = _cli_error(capsys, tmp_path / "mixed.uff", tmp_path)
    assert ("mixed.uff: record 3 (channel 'acc1') has 900 samples, record 1 (channel "
            "'shaker 1') has 1000") in msg


def test_nan_in_a_channel_names_record_channel_and_sample(tmp_path, lab, capsys):
    # pyuff's writer turns NaN into 0, so the NaN is put in as a logger with a dropped
    # sample writes it: the text NaN in the value's 20-character field
    lab.y[17, 1] = 12345.0
    text = write_data(lab, tmp_path / "lab.uff").read_text()
    assert text.count("   1.23450000000e+04") == 1
    (tmp_path / "nan.uff").write_text(text.replace("   1.23450000000e+04", f"{'NaN':>20}"))
    msg = _cli_error(capsys, tmp_path / "nan.uff", tmp_path)
    assert "nan.uff: record 4 (channel 'acc2') has a non-finite value (nan) at sample 17" in msg


def test_a_file_that_is_not_uff_is_refused(tmp_path, capsys):
    (tmp_path / "text.uff").write_text("t,u1,y1\n0,1,2\n")
    assert "text.uff: not a UFF file" in _cli_error(capsys, tmp_path / "text.uff", tmp_path)


def test_identify_reads_a_uff_file(tmp_path, capsys):
    """`trussid identify DATA.uff` on a lightly damped 2nd-order system (10 Hz, 2 %)."""
    import control

    fs = 200.0
    wn, zeta = 2 * np.pi * 10.0, 0.02
    plant = control.c2d(control.ss(control.tf([wn ** 2], [1, 2 * zeta * wn, wn ** 2])),
                        1 / fs)
    u = np.random.default_rng(3).standard_normal(3000)
    y = control.forced_response(plant, U=u).outputs
    write_data(IOData(u=u, y=y, fs=fs, input_names=["force"], output_names=["acc"]),
               tmp_path / "sdof.uff")
    code = main(["identify", str(tmp_path / "sdof.uff"), "--order", "2", "--out",
                 str(tmp_path / "m.npz"), "--json"])
    assert code == 0, capsys.readouterr().err
    import json

    summary = json.loads(capsys.readouterr().out)
    assert summary["inputs"] == ["force"] and summary["fs"] == 200.0
    (pole,) = [p for p in summary["poles"] if p["damping"] < 0.5]
    assert pole["frequency_hz"] == pytest.approx(10.0, rel=1e-3)
    assert pole["damping"] == pytest.approx(0.02, rel=2e-2)


def test_real_normal_modes_round_trip_as_uff55_analysis_type_2(tmp_path, rng):
    """FE modes are real: written as normal modes with frequency and viscous damping."""
    modes = ModeShapes(frequencies_hz=np.array([50.43, 79.4]), damping=np.array([0.0, 0.005]),
                       shapes=rng.standard_normal((3, 2)), dofs=[(11, 1), (11, 2), (12, 3)])
    back = read_uff(write_uff(tmp_path / "fe.uff", modes=modes)).modes
    assert not np.iscomplexobj(back.shapes)
    np.testing.assert_allclose(back.frequencies_hz, modes.frequencies_hz, rtol=E13_5)
    np.testing.assert_allclose(back.damping, modes.damping, atol=1e-8)
    rows = [back.dofs.index(d) for d in modes.dofs]
    np.testing.assert_allclose(back.shapes[rows], modes.shapes, rtol=E13_5, atol=1e-300)
    with pytest.raises(DataError, match="needs a \\(node, direction\\) for each of the 3 rows"):
        write_uff(tmp_path / "x.uff", modes=ModeShapes(modes.frequencies_hz, modes.damping,
                                                       modes.shapes))
