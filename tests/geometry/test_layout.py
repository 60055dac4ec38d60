"""Layout of the reference testbed: acceptance item 1 (geometry to 1e-12) and the numbering."""

import math

import numpy as np
import pytest

from trussid.geometry.layout import testbed_layout
from trussid.geometry.spec import Testbed

IN = 0.0254  # the thesis's unit, written out independently of geometry.testbed.INCH


@pytest.fixture(scope="module")
def tb():
    return Testbed()


@pytest.fixture(scope="module")
def lay(tb):
    return testbed_layout(tb)


def test_every_strut_is_36_inches_long(lay):
    lengths = np.linalg.norm(lay.strut_end - lay.strut_start, axis=1)
    np.testing.assert_allclose(lengths, 36 * IN, rtol=0, atol=1e-12)


def test_udf_sides_are_12_inches(lay):
    v = lay.top_vertices
    sides = [np.linalg.norm(v[i] - v[(i + 1) % 3]) for i in range(3)]
    np.testing.assert_allclose(sides, 12 * IN, rtol=0, atol=1e-12)


def test_base_points_on_documented_circle_120_degrees_apart(lay):
    r_b = 12 / math.sqrt(3) * 2 * IN  # testbed.md: R_b = 12/sqrt(3) * 2 in = 13.856 in
    b = lay.base_points
    np.testing.assert_allclose(np.hypot(b[:, 0], b[:, 1]), r_b, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b[:, 2], 0.0, atol=1e-12)
    az = np.degrees(np.arctan2(b[:, 1], b[:, 0])) % 360
    np.testing.assert_allclose(np.diff(az), 120.0, atol=1e-9)


def test_each_vertex_two_struts_lie_in_one_vertical_plane(lay):
    ez = np.array([0.0, 0.0, 1.0])
    for k, (a, b) in enumerate(lay.channel_struts):
        # Both struts end at V_k, and (strut a, strut b, vertical) are coplanar.
        np.testing.assert_allclose(lay.strut_end[a], lay.top_vertices[k], atol=1e-12)
        np.testing.assert_allclose(lay.strut_end[b], lay.top_vertices[k], atol=1e-12)
        triple = np.dot(np.cross(lay.strut_axis[a], lay.strut_axis[b]), ez)
        assert abs(triple) < 1e-12


def test_top_vertices_at_documented_height_above_chord_midpoints(lay):
    np.testing.assert_allclose(lay.top_vertices[:, 2], math.sqrt(36**2 - 12**2) * IN, atol=1e-12)
    b = lay.base_points
    mid = 0.5 * (b + np.roll(b, -1, axis=0))  # chord B_k B_(k+1)
    np.testing.assert_allclose(lay.top_vertices[:, :2], mid[:, :2], atol=1e-12)


def test_bipods_pair_the_struts_of_each_base_point(lay):
    for j, pair in enumerate(lay.bipods):
        assert sorted(np.flatnonzero(lay.strut_base == j)) == sorted(pair)
        np.testing.assert_allclose(lay.strut_start[pair], lay.base_points[[j, j]], atol=1e-12)


def test_channel_k_is_the_two_struts_sharing_top_vertex_k(lay):
    np.testing.assert_array_equal(lay.channel_struts, [[0, 1], [2, 3], [4, 5]])
    for k, pair in enumerate(lay.channel_struts):
        assert list(lay.strut_vertex[pair]) == [k, k]


def test_strut_frames_are_right_handed_with_y_normal_to_the_vertical_plane(lay):
    R = lay.strut_frames()
    for i in range(6):
        np.testing.assert_allclose(R[i] @ R[i].T, np.eye(3), atol=1e-12)
        assert np.linalg.det(R[i]) == pytest.approx(1.0, abs=1e-12)
    assert np.all(np.abs(lay.strut_y[:, 2]) < 1e-12)  # horizontal
    for a, b in lay.channel_struts:
        np.testing.assert_allclose(lay.strut_y[a], lay.strut_y[b], atol=1e-12)
        assert abs(np.dot(lay.strut_y[a], lay.strut_axis[b])) < 1e-12


def test_adapters_are_centred_at_mid_span_with_ends_along_the_strut(tb, lay):
    np.testing.assert_allclose(lay.adapter_centre, 0.5 * (lay.strut_start + lay.strut_end), atol=1e-12)
    gap = np.linalg.norm(lay.adapter_end - lay.adapter_start, axis=1)
    np.testing.assert_allclose(gap, tb.adapter.length, atol=1e-12)
    # The adapter's ends lie on the strut line: distances from the two strut ends add up.
    d_start = np.linalg.norm(lay.adapter_start - lay.strut_start, axis=1)
    d_end = np.linalg.norm(lay.strut_end - lay.adapter_end, axis=1)
    np.testing.assert_allclose(d_start + d_end + gap, 36 * IN, atol=1e-12)
    np.testing.assert_allclose(d_start, d_end, atol=1e-12)


def test_accelerometers_sit_vertically_above_the_strut_junctions(lay):
    np.testing.assert_allclose(lay.accelerometer_points[:, :2], lay.top_vertices[:, :2], atol=1e-12)
    assert np.all(lay.accelerometer_points[:, 2] > lay.top_vertices[:, 2])
    np.testing.assert_allclose(lay.accelerometer_axes, np.tile([0, 0, 1.0], (3, 1)))


def test_base_plate_centre_is_half_its_thickness_below_the_base_points(tb, lay):
    # 105 lb of aluminium (2700 kg/m^3) as a 30 in disc is 1.5229 in thick.
    t = 105 * 0.45359237 / (2700 * math.pi * (15 * IN) ** 2)
    np.testing.assert_allclose(lay.base_centre, [0, 0, -t / 2], atol=1e-12)


def test_bungees_attach_inside_the_outer_ring_of_the_plate(tb, lay):
    r = np.hypot(lay.bungee_points[:, 0], lay.bungee_points[:, 1])
    assert lay.bungee_points.shape == (3, 3)
    assert np.all((r > 12 * IN) & (r < 15 * IN))  # the thesis's outer 3 in ring


def test_longer_struts_raise_the_top_and_keep_the_plan(tb):
    lay = testbed_layout(tb.replace(struts__length=40 * IN))
    np.testing.assert_allclose(np.linalg.norm(lay.strut_end - lay.strut_start, axis=1), 40 * IN, atol=1e-12)
    np.testing.assert_allclose(lay.top_vertices[:, 2], math.sqrt(40**2 - 12**2) * IN, atol=1e-12)


def test_layout_arrays_are_read_only(lay):
    with pytest.raises(ValueError):
        lay.strut_start[0, 0] = 1.0
