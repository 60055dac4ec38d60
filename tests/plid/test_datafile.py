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
