"""Data files: CSV/NPZ/MAT round trips and validation errors that name the column or sample."""

import numpy as np
import pytest

from trussid.plid.datafile import IOData, check_enough_samples, read_data, with_channels, write_data
from trussid.plid.errors import DataError


@pytest.fixture
def data(rng):
    n = 50
    return IOData(u=rng.standard_normal((n, 2)), y=rng.standard_normal((n, 3)), fs=1600.0,
                  input_names=["u_pzt1", "u_pzt2"], output_names=["y1", "y2", "y3"])


@pytest.mark.parametrize("suffix", [".csv", ".npz", ".mat"])
def test_round_trip_is_exact_in_every_format(tmp_path, data, suffix):
    path = write_data(data, tmp_path / f"d{suffix}")
    back = read_data(path)
    np.testing.assert_array_equal(back.u, data.u)
    np.testing.assert_array_equal(back.y, data.y)
    assert back.fs == pytest.approx(1600.0, rel=1e-12)
    assert back.input_names == data.input_names
    assert back.output_names == data.output_names


def test_csv_names_not_following_the_convention_get_a_prefix(tmp_path, rng):
    d = IOData(u=rng.standard_normal((10, 1)), y=rng.standard_normal((10, 1)), fs=100.0,
               input_names=["pzt"], output_names=["acc"])
    back = read_data(write_data(d, tmp_path / "d.csv"))
    assert back.input_names == ["u_pzt"] and back.output_names == ["y_acc"]


def test_npz_keeps_noise_free_outputs(tmp_path, data):
    data.y_clean = data.y * 0.5
    back = read_data(write_data(data, tmp_path / "d.npz"))
    np.testing.assert_array_equal(back.y_clean, data.y_clean)


def write_csv(path, text):
    path.write_text(text)
    return path


def test_csv_fs_comes_from_the_time_column(tmp_path):
    p = write_csv(tmp_path / "a.csv", "t,u1,y1\n0,1,2\n0.001,2,3\n0.002,-1,0\n")
    assert read_data(p).fs == pytest.approx(1000.0)


def test_csv_without_time_needs_fs(tmp_path):
    p = write_csv(tmp_path / "a.csv", "u1,y1\n1,2\n2,3\n-1,0\n")
    with pytest.raises(DataError, match="sampling frequency missing"):
        read_data(p)
    assert read_data(p, fs=200).fs == 200


def test_csv_given_fs_must_agree_with_time_column(tmp_path):
    p = write_csv(tmp_path / "a.csv", "t,u1,y1\n0,1,2\n0.001,2,3\n0.002,-1,0\n")
    with pytest.raises(DataError, match="fs=500 Hz was given but the file says 1000 Hz"):
        read_data(p, fs=500)


def test_nonuniform_time_names_the_sample(tmp_path):
    p = write_csv(tmp_path / "a.csv", "t,u1,y1\n0,1,2\n0.001,2,3\n0.0035,-1,0\n0.004,1,1\n")
    with pytest.raises(DataError, match="not uniformly sampled.*sample 2"):
        read_data(p)


def test_nan_names_column_and_sample(tmp_path):
    p = write_csv(tmp_path / "a.csv", "t,u1,y1,y2\n0,1,2,3\n0.001,2,3,nan\n0.002,-1,0,1\n")
    with pytest.raises(DataError, match="column 'y2' has a non-finite value \\(nan\\) at sample 1"):
        read_data(p)


def test_inf_in_npz_names_column_and_sample(tmp_path, data):
    data.u[7, 1] = np.inf
    path = tmp_path / "d.npz"
    np.savez(path, u=data.u, y=data.y, fs=100.0)
    with pytest.raises(DataError, match="column 'u2' has a non-finite value \\(inf\\) at sample 7"):
        read_data(path)


def test_text_cell_names_column_and_line(tmp_path):
    p = write_csv(tmp_path / "a.csv", "u1,y1\n1,2\n2,oops\n")
    with pytest.raises(DataError, match="column 'y1' sample 1 \\(line 3\\) is not a number"):
        read_data(p, fs=10)


def test_length_mismatch_in_npz(tmp_path):
    path = tmp_path / "d.npz"
    np.savez(path, u=np.arange(10.0), y=np.arange(9.0), fs=10.0)
    with pytest.raises(DataError, match="length mismatch: 'u' has 10 samples, 'y' has 9"):
        read_data(path)


def test_constant_input_is_refused(tmp_path):
    p = write_csv(tmp_path / "a.csv", "u1,u2,y1\n1,3,2\n2,3,3\n-1,3,0\n")
    with pytest.raises(DataError, match="input column 'u2' is constant"):
        read_data(p, fs=10)


def test_unknown_column_suggests_the_closest(tmp_path):
    p = write_csv(tmp_path / "a.csv", "t [s],force,acc1,acc2\n0,1,2,3\n1,2,3,4\n2,-1,0,1\n")
    with pytest.raises(DataError, match="unknown column 'forse'; did you mean 'force'"):
        read_data(p, inputs=["forse"], outputs=["acc1"])


def test_explicit_lists_override_the_naming_convention(tmp_path):
    p = write_csv(tmp_path / "a.csv", "t [s],force,acc1,acc2\n0,1,2,3\n1,2,3,4\n2,-1,0,1\n")
    d = read_data(p, inputs=["force"])
    assert d.input_names == ["force"] and d.output_names == ["acc1", "acc2"]
    d = read_data(p, inputs=["force"], outputs=["acc2"])
    np.testing.assert_array_equal(d.y[:, 0], [3, 4, 1])


def test_unclassifiable_column_is_named(tmp_path):
    p = write_csv(tmp_path / "a.csv", "t,u1,y1,temp\n0,1,2,3\n1,2,3,4\n2,-1,0,1\n")
    with pytest.raises(DataError, match="column 'temp' is an input or an output"):
        read_data(p)


def test_npz_selects_channels_by_name(tmp_path, data):
    path = write_data(data, tmp_path / "d.npz")
    d = read_data(path, inputs=["u_pzt2"], outputs=["y3", "y1"])
    np.testing.assert_array_equal(d.u[:, 0], data.u[:, 1])
    np.testing.assert_array_equal(d.y, data.y[:, [2, 0]])
    with pytest.raises(DataError, match="'y1' is an output channel"):
        read_data(path, inputs=["y1"])


def test_missing_arrays_and_foreign_files(tmp_path):
    path = tmp_path / "d.npz"
    np.savez(path, u=np.arange(3.0), fs=1.0)
    with pytest.raises(DataError, match="missing array 'y'"):
        read_data(path)
    bad = tmp_path / "x.npz"
    bad.write_text("hello")
    with pytest.raises(DataError, match="not a readable .npz data file"):
        read_data(bad)
    with pytest.raises(DataError, match="no such data file"):
        read_data(tmp_path / "absent.csv")
    with pytest.raises(DataError, match="unknown data file type '.txt'"):
        read_data(write_csv(tmp_path / "a.txt", "u1,y1\n"))


def test_fewer_samples_than_parameters(data):
    check_enough_samples(data, 50)
    with pytest.raises(DataError, match="only 50 samples for 60 parameters"):
        check_enough_samples(data, 60)


def test_with_channels_restricts(data):
    d = with_channels(data, outputs=["y2"])
    assert d.y.shape == (50, 1) and d.output_names == ["y2"]


def test_write_is_atomic_on_bad_data(tmp_path, data):
    data.y[3, 0] = np.nan
    with pytest.raises(DataError):
        write_data(data, tmp_path / "d.csv")
    assert list(tmp_path.iterdir()) == []


def test_wrong_array_rank_is_named(tmp_path):
    path = tmp_path / "d.npz"
    np.savez(path, u=np.ones((4, 2, 2)), y=np.ones((4, 1)), fs=1.0)
    with pytest.raises(DataError, match="array 'u' must be 2-D .* got shape \\(4, 2, 2\\)"):
        read_data(path)


# ------------------------------------------------------------------ lab files (issue 19)
# Each file below is written the way the named program writes it; each must read correctly
# or be refused with a reason that names the file and the column.


@pytest.fixture
def record(rng):
    """400 samples at 1600 Hz: two inputs, two outputs, times in seconds."""
    n, fs = 400, 1600.0
    return np.arange(n) / fs, rng.standard_normal((n, 2)), rng.standard_normal((n, 2))


def _rows(t, u, y, fmt="{:.9g}", sep=","):
    return "".join(sep.join(fmt.format(v) for v in (tk, *uk, *yk)) + "\n"
                   for tk, uk, yk in zip(t, u, y))


def _check(d, record, rtol=1e-8):
    t, u, y = record
    assert d.fs == pytest.approx(1600.0, rel=1e-6)
    np.testing.assert_allclose(d.u, u, rtol=rtol, atol=1e-8)
    np.testing.assert_allclose(d.y, y, rtol=rtol, atol=1e-8)


def test_units_in_the_header_are_read_as_units_not_names(tmp_path, record):
    """Audit L01: DEWESoft / HBM catman style headers 'name [unit]'."""
    p = write_csv(tmp_path / "units.csv",
                  "t [s],u1 [V],u2 [V],y1 [m/s^2],y2 [m/s^2]\n" + _rows(*record))
    d = read_data(p)
    _check(d, record)
    assert d.input_names == ["u1", "u2"] and d.output_names == ["y1", "y2"]
    assert d.units == {"u1": "V", "u2": "V", "y1": "m/s^2", "y2": "m/s^2"}
    # a name may be given with or without its unit
    assert read_data(p, inputs=["u2 [V]"], outputs=["y1"]).input_names == ["u2"]


def test_german_excel_semicolons_decimal_commas_crlf_and_bom(tmp_path, record):
    """Audit L02: Excel 'CSV UTF-8' in a German locale: BOM, ';', decimal comma, CRLF."""
    body = _rows(*record, sep=";").replace(".", ",").replace("\n", "\r\n")
    p = tmp_path / "semi.csv"
    p.write_bytes(("Zeit [s];u1 [V];u2 [V];y1 [V];y2 [V]\r\n" + body).encode("utf-8-sig"))
    _check(read_data(p), record)


def test_labview_comment_lines_and_tabs(tmp_path, record):
    """Audit L03/L04: LabVIEW 'Write Delimited Spreadsheet' (tab, %.6f) after a header the
    VI wrote as comment lines."""
    t, u, y = record
    head = "# exported by LabVIEW 2021\n# operator: test cell 2\n"
    p = write_csv(tmp_path / "tabs.csv", head + "t\tu1\tu2\ty1\ty2\n"
                  + _rows(t, u, y, fmt="{:.6f}", sep="\t") + "% end of record\n")
    d = read_data(p)
    assert d.n_samples == 400 and d.fs == pytest.approx(1600.0, rel=1e-4)
    np.testing.assert_allclose(d.y, y, atol=5e-7)


def test_pandas_to_csv_index_column_is_dropped(tmp_path, record):
    import pandas as pd

    t, u, y = record
    frame = pd.DataFrame({"t": t, "u1": u[:, 0], "u2": u[:, 1], "y1": y[:, 0], "y2": y[:, 1]})
    frame.to_csv(tmp_path / "pandas.csv")  # pandas' default: the row index, unnamed, first
    d = read_data(tmp_path / "pandas.csv")
    _check(d, record, rtol=1e-15)
    assert d.input_names == ["u1", "u2"]


def test_time_column_in_milliseconds_is_never_silently_seconds(tmp_path, record):
    """Audit L07: 't' in ms used to give a 1.6 Hz model without a word."""
    t, u, y = record
    plain = write_csv(tmp_path / "ms.csv", "t,u1,u2,y1,y2\n" + _rows(1e3 * t, u, y))
    with pytest.raises(DataError, match=r"ms\.csv: time column 't' has no unit and steps by "
                       r"0\.625: in seconds that is 1\.6 Hz.*'t \[ms\]'"):
        read_data(plain)
    d = read_data(plain, fs=1600)  # checked against --fs: the column is in milliseconds
    assert d.fs == 1600 and "read as milliseconds" in d.notes[0]
    np.testing.assert_allclose(d.t, t, rtol=1e-9, atol=1e-12)
    with pytest.raises(DataError, match="fs=500 Hz was given but the file says 1.6 Hz"):
        read_data(plain, fs=500)
    labelled = write_csv(tmp_path / "ms_unit.csv", "t (ms),u1,u2,y1,y2\n" + _rows(1e3 * t, u, y))
    _check(read_data(labelled), record)
    wrong = write_csv(tmp_path / "hours.csv", "t [V],u1,u2,y1,y2\n" + _rows(t, u, y))
    with pytest.raises(DataError, match="hours.csv: column 't \\[V\\]' has unit 'V', not a time"):
        read_data(wrong)


def test_time_offset_and_jitter_are_tolerated(tmp_path, record, rng):
    """Audit L08: a logger's clock (offset 100 s, 1e-7 s jitter) still gives 1600 Hz."""
    t, u, y = record
    p = write_csv(tmp_path / "jitter.csv", "t,u1,u2,y1,y2\n"
                  + _rows(100 + t + 1e-7 * rng.standard_normal(t.size), u, y, fmt="{:.12g}"))
    assert read_data(p).fs == pytest.approx(1600.0, rel=1e-4)


def test_matlab_variables_with_other_names(tmp_path, record):
    """Audit L05: save('othernames.mat', 'input', 'output', 'Ts') as MATLAB writes it (v5),
    and any names picked with --inputs/--outputs, whole or by column."""
    import scipy.io

    t, u, y = record
    scipy.io.savemat(tmp_path / "othernames.mat", {"input": u, "output": y, "Ts": 1 / 1600})
    d = read_data(tmp_path / "othernames.mat")
    _check(d, record, rtol=0)
    scipy.io.savemat(tmp_path / "lab.mat", {"F1": u[:, 0], "F2": u[:, 1], "acc": y,
                                            "fsamp": 1600.0})
    d = read_data(tmp_path / "lab.mat", inputs=["F1", "F2"], outputs=["acc"])
    _check(d, record, rtol=0)
    assert d.input_names == ["F1", "F2"] and d.output_names == ["acc:1", "acc:2"]
    # one matrix of every channel (the DaISy subframe file): columns counted from 1
    scipy.io.savemat(tmp_path / "matrix.mat", {"data": np.column_stack([u, y])})
    d = read_data(tmp_path / "matrix.mat", inputs=["data:1", "2"], outputs=["data:3-4"],
                  fs=1600)
    _check(d, record, rtol=0)
    with pytest.raises(DataError, match="matrix.mat: output 'data:3-7': variable 'data' has "
                       "only 4 channel"):
        read_data(tmp_path / "matrix.mat", inputs=["data:1,2"], outputs=["data:3-7"], fs=1600)
    with pytest.raises(DataError, match="othernames.mat: unknown variable 'outptu'; did you mean 'output'"):
        read_data(tmp_path / "othernames.mat", inputs=["input"], outputs=["outptu"])


def test_matlab_channels_by_samples_are_transposed_from_the_sample_count(tmp_path, record):
    """Audit L06: u, y stored channels x samples used to read as 2 samples of 400 channels
    ("order must be a multiple of 400 outputs")."""
    import scipy.io

    t, u, y = record
    scipy.io.savemat(tmp_path / "transposed.mat", {"u": u.T, "y": y.T, "fs": 1600.0})
    d = read_data(tmp_path / "transposed.mat")
    _check(d, record, rtol=0)
    assert "channels x samples (400 samples)" in d.notes[0]
    # a time vector [s] declares the sample count and gives fs
    scipy.io.savemat(tmp_path / "with_t.mat", {"u": u.T, "y": y.T, "t": t})
    _check(read_data(tmp_path / "with_t.mat"), record, rtol=0)
    # without one, a square record is ambiguous and refused
    scipy.io.savemat(tmp_path / "ambiguous.mat", {"u": u[:2].T, "y": y[:2], "fs": 1600.0})
    with pytest.raises(DataError, match="ambiguous.mat: variable 'u' is 2x2: cannot tell "
                       "samples from channels"):
        read_data(tmp_path / "ambiguous.mat")


def test_matlab_v73_files_are_refused_with_the_way_out(tmp_path):
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Nov 23 2026 HDF5 schema"
    p = tmp_path / "v73.mat"
    p.write_bytes(header.ljust(116) + b"\0" * 8 + b"\x00\x02IM" + b"\0" * 512)
    with pytest.raises(DataError, match="v73.mat: a MATLAB v7.3 \\(HDF5\\) file; save it with"):
        read_data(p)


def test_a_headerless_spreadsheet_is_refused_naming_the_line(tmp_path, record):
    p = write_csv(tmp_path / "noheader.csv", "# LabVIEW, no column names\n" + _rows(*record))
    with pytest.raises(DataError, match="noheader.csv: the first row \\(line 2\\) must be a "
                       "header of column names"):
        read_data(p)


def test_csv_time_column_is_written_without_noise_digits(tmp_path, data):
    """The audit saw '0.00062500000000000001' in simulate's CSV time column."""
    path = write_data(data, tmp_path / "d.csv")
    second = path.read_text().splitlines()[2].split(",")[0]
    assert second == "0.000625"


def test_csv_channel_names_with_commas_and_quotes_round_trip(tmp_path, rng):
    """Audit 2, I22: a sensor named "acc tip,z" made simulate write a CSV header of 7 names
    over 6 values, which identify could not read."""
    d = IOData(rng.normal(size=(200, 1)), rng.normal(size=(200, 2)), 100.0, ["shaker"],
               ["acc tip,z", 'say "x"'])
    back = read_data(write_data(d, tmp_path / "d.csv"))
    assert back.output_names == ["y_acc tip,z", 'y_say "x"']
    np.testing.assert_array_equal(back.y, d.y)
