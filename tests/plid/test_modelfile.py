"""Model files: round trip of discrete/continuous models with K and names; clear refusals."""

import control
import numpy as np
import pytest

from trussid.plid.errors import DataError
from trussid.plid.modelfile import FORMAT_VERSION, is_model_file, load_model, save_model


@pytest.fixture
def models():
    sc = control.ss([[0, 1], [-400, -0.4]], [[0], [1]], [[1, 0], [0, 1]], [[0], [0]])
    return sc, control.c2d(sc, 1e-3)


def test_round_trip_discrete_with_gain_names_and_continuous(tmp_path, models):
    sc, sd = models
    K = np.arange(4.0).reshape(2, 2)
    path = save_model(tmp_path / "m.npz", sd, K=K, input_names=["pzt"],
                      output_names=["x", "v"], continuous=sc, extra={"note": np.arange(3)})
    assert is_model_file(path)
    sys, meta = load_model(path)
    for name in "ABCD":
        np.testing.assert_array_equal(getattr(sys, name), getattr(sd, name))
    assert sys.dt == 1e-3 and meta.dt == 1e-3
    np.testing.assert_array_equal(meta.K, K)
    assert meta.input_names == ["pzt"] and meta.output_names == ["x", "v"]
    assert meta.format_version == FORMAT_VERSION and meta.has_continuous
    np.testing.assert_array_equal(meta.extra["note"], np.arange(3))
    csys, cmeta = load_model(path, which="continuous")
    assert csys.dt == 0 and cmeta.K is None
    np.testing.assert_array_equal(csys.A, sc.A)


def test_names_come_from_the_system_labels(tmp_path, models):
    sc, sd = models
    named = control.ss(sd.A, sd.B, sd.C, sd.D, sd.dt, inputs=["pzt1"], outputs=["a", "b"])
    sys, meta = load_model(save_model(tmp_path / "n.npz", named))
    assert meta.input_names == ["pzt1"] and meta.output_names == ["a", "b"]
    assert list(sys.input_labels) == ["pzt1"] and list(sys.output_labels) == ["a", "b"]
    _, meta = load_model(save_model(tmp_path / "d.npz", sd))  # python-control's u[0], y[0]
    assert meta.input_names == ["u1"] and meta.output_names == ["y1", "y2"]


def test_repeated_channel_names_are_refused(tmp_path, models):
    _, sd = models
    with pytest.raises(DataError, match="output name 'a' is used more than once"):
        save_model(tmp_path / "m.npz", sd, output_names=["a", "a"])
    path = tmp_path / "x.npz"
    np.savez(path, A=sd.A, B=sd.B, C=sd.C, D=sd.D, dt=1e-3, output_names=["a", "a"])
    with pytest.raises(DataError, match="output name 'a' is used more than once"):
        load_model(path)


def test_continuous_only_file(tmp_path, models):
    sc, _ = models
    path = save_model(tmp_path / "c.npz", sc)
    sys, meta = load_model(path, which="continuous")
    assert meta.dt == 0 and sys.dt == 0
    with pytest.raises(DataError, match="continuous \\(dt = 0\\); a discrete one is needed"):
        load_model(path, which="discrete")


def test_missing_array_is_named(tmp_path):
    path = tmp_path / "x.npz"
    np.savez(path, A=np.eye(2), B=np.ones((2, 1)), D=np.zeros((1, 1)), dt=0.1)
    with pytest.raises(DataError, match="not a model file: missing array 'C'"):
        load_model(path)
    assert not is_model_file(tmp_path / "absent.npz")


def test_inconsistent_shapes_are_named(tmp_path):
    path = tmp_path / "x.npz"
    np.savez(path, A=np.eye(2), B=np.ones((3, 1)), C=np.ones((1, 2)), D=np.zeros((1, 1)), dt=0.1)
    with pytest.raises(DataError, match="array 'B' has shape \\(3, 1\\), needs 2 rows"):
        load_model(path)


def test_data_file_is_not_a_model(tmp_path):
    path = tmp_path / "d.npz"
    np.savez(path, u=np.ones(3), y=np.ones(3), fs=1.0)
    assert not is_model_file(path)
    with pytest.raises(DataError, match="missing array 'A'"):
        load_model(path)


def test_save_refuses_wrong_gain_and_leaves_no_file(tmp_path, models):
    _, sd = models
    with pytest.raises(DataError, match="K has shape \\(3, 1\\), needs \\(2, 2\\)"):
        save_model(tmp_path / "m.npz", sd, K=np.ones((3, 1)))
    with pytest.raises(DataError, match="extra array name 'dt' is reserved"):
        save_model(tmp_path / "m.npz", sd, extra={"dt": 1})
    assert list(tmp_path.iterdir()) == []
