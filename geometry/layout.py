"""Points and members of the testbed: where everything is, as small numpy arrays.

:func:`testbed_layout` is cheap (no meshes; about 0.1 ms), since design sweeps call
it for every design.

Frame and numbering
-------------------
Global frame: origin at the centre of the base plate's top face, z up. Units m.

- Base point ``B_j`` (j = 0, 1, 2) is on the circle of radius ``R_b`` at azimuth
  ``120 j`` degrees.
- Top vertex ``V_k`` (k = 0, 1, 2) is above the midpoint of the chord ``B_k B_(k+1)``,
  at azimuth ``60 + 120 k`` degrees, radius ``R_b / 2`` and height ``sqrt(L^2 - run^2)``.
- Strut ``2k`` runs from ``B_k`` to ``V_k``; strut ``2k + 1`` from ``B_(k+1 mod 3)`` to
  ``V_k``. The two struts meeting at ``V_k`` lie in one vertical plane and are actuator
  channel ``k``. The bipod on base point ``B_j`` is struts ``(2j, 2j - 1 mod 6)``.
- Each strut's local frame: ``x`` along the strut from base to top; ``y`` horizontal,
  normal to its vertical plane (radially outward, the same for both struts of a channel);
  ``z = x cross y``, in the vertical plane. The wafers sit on the adapter's ``+y`` and ``-y``
  faces (and ``+z``, ``-z`` when there are four).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trussid.geometry.spec import Testbed

#: Strut ``i`` starts at base point ``STRUT_BASE[i]``.
STRUT_BASE = np.array([0, 1, 1, 2, 2, 0])
#: Strut ``i`` ends at top vertex (and is driven by channel) ``STRUT_VERTEX[i]``.
STRUT_VERTEX = np.array([0, 0, 1, 1, 2, 2])


@dataclass(frozen=True)
class Layout:
    """Positions [m] and memberships of the testbed's parts (arrays are read-only).

    Attributes
    ----------
    base_points : (3, 3) ndarray
        ``B_j``, the lower strut ends, on the plate's top face (z = 0).
    top_vertices : (3, 3) ndarray
        ``V_k``, the upper strut ends (the UDF's lower corners).
    strut_start, strut_end : (6, 3) ndarray
        Base and top end of each strut.
    strut_base, strut_vertex : (6,) int ndarray
        Index of each strut's base point and top vertex; ``strut_vertex`` is its channel.
    strut_axis, strut_y, strut_z : (6, 3) ndarray
        Unit vectors of each strut's local frame (module docstring).
    bipods : (3, 2) int ndarray
        The two struts anchored at each base point.
    channel_struts : (3, 2) int ndarray
        The two struts meeting at each top vertex, driven together by channel k.
    adapter_centre, adapter_start, adapter_end : (6, 3) ndarray
        Mid-span of each strut and the two ends of its adapter block (grid points in FE).
    accelerometer_points : (3, 3) ndarray
        The accelerometers, on top of the UDF's upper bars above each strut junction.
    accelerometer_axes : (3, 3) ndarray
        Their sensing directions (vertical, +z).
    udf_lower_corners, udf_upper_corners : (3, 3) ndarray
        Corners of the UDF prism (bar centrelines); lower corners are the top vertices.
    base_centre : (3,) ndarray
        Centre of the base plate (its mid-plane).
    bungee_points : (n_bungees, 3) ndarray
        Bungee attachments on the plate's top face, at azimuths ``60 + 360 j / n`` degrees.
    """

    base_points: np.ndarray
    top_vertices: np.ndarray
    strut_start: np.ndarray
    strut_end: np.ndarray
    strut_base: np.ndarray
    strut_vertex: np.ndarray
    strut_axis: np.ndarray
    strut_y: np.ndarray
    strut_z: np.ndarray
    bipods: np.ndarray
    channel_struts: np.ndarray
    adapter_centre: np.ndarray
    adapter_start: np.ndarray
    adapter_end: np.ndarray
    accelerometer_points: np.ndarray
    accelerometer_axes: np.ndarray
    udf_lower_corners: np.ndarray
    udf_upper_corners: np.ndarray
    base_centre: np.ndarray
    bungee_points: np.ndarray

    def __post_init__(self) -> None:
        for value in vars(self).values():
            value.flags.writeable = False  # shared by callers: guard against in-place edits

    def strut_frames(self) -> np.ndarray:
        """Rotation matrices (6, 3, 3) whose rows are each strut's local x, y, z axes."""
        return np.stack([self.strut_axis, self.strut_y, self.strut_z], axis=1)


def _on_circle(radius: float, azimuth_deg: np.ndarray, z: float) -> np.ndarray:
    a = np.radians(azimuth_deg)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.full(a.shape, z)])


def testbed_layout(tb: Testbed) -> Layout:
    """Points and members of testbed ``tb`` (see the module docstring for the numbering).

    Parameters
    ----------
    tb : Testbed

    Returns
    -------
    Layout
    """
    r_b = tb.base_radius
    h = tb.strut_height
    k = np.arange(3)
    base_points = _on_circle(r_b, 120.0 * k, 0.0)
    # Above the chord midpoints: radius R_b cos 60 deg = R_b / 2.
    top_vertices = _on_circle(0.5 * r_b, 60.0 + 120.0 * k, h)

    start = base_points[STRUT_BASE]
    end = top_vertices[STRUT_VERTEX]
    axis = (end - start) / tb.struts.length
    radial = _on_circle(1.0, 60.0 + 120.0 * k, 0.0)  # horizontal normal of channel k's plane
    y = radial[STRUT_VERTEX]
    z = np.cross(axis, y)

    centre = 0.5 * (start + end)
    half = 0.5 * tb.adapter.length * axis

    up = np.array([0.0, 0.0, 1.0])
    upper = top_vertices + tb.udf.height * up
    accel = upper + 0.5 * tb.udf.member_size * up

    n_b = tb.base.bungee_count
    bungees = _on_circle(tb.base.bungee_radius, 60.0 + 360.0 * np.arange(n_b) / n_b, 0.0)

    return Layout(
        base_points=base_points,
        top_vertices=top_vertices,
        strut_start=start,
        strut_end=end,
        strut_base=STRUT_BASE.copy(),
        strut_vertex=STRUT_VERTEX.copy(),
        strut_axis=axis,
        strut_y=y,
        strut_z=z,
        bipods=np.array([[0, 5], [1, 2], [3, 4]]),
        channel_struts=np.array([[0, 1], [2, 3], [4, 5]]),
        adapter_centre=centre,
        adapter_start=centre - half,
        adapter_end=centre + half,
        accelerometer_points=accel,
        accelerometer_axes=np.tile(up, (3, 1)),
        udf_lower_corners=top_vertices.copy(),
        udf_upper_corners=upper,
        base_centre=np.array([0.0, 0.0, -0.5 * tb.base.thickness]),
        bungee_points=bungees,
    )


__all__ = ["Layout", "testbed_layout", "STRUT_BASE", "STRUT_VERTEX"]
