"""Offscreen mode-shape rendering (fem.render, ``trussid render``).

Most pictures use a small tripod (three tube struts from a clamped base to a top triangle
held by a rigid body, with point masses) and hand-made modes: the closed-form
clamped-clamped bending shapes of one strut at a time, so the expected picture is known
independently of the FE solver. The mesh-data checks on real FE modes use struts whose
bending frequencies are known in closed form.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

from trussid.fem import render  # noqa: E402
from trussid.fem.materials import ALUMINIUM  # noqa: E402
from trussid.fem.model import Model  # noqa: E402
from trussid.fem.sections import Section  # noqa: E402
from trussid.cli import main as cli_main  # noqa: E402

DATA = Path(__file__).parent / "data"
REFERENCE = DATA / "render_reference.png"
REFERENCE_SIZE = (400, 300)

#: beta*L of the first two clamped-clamped bending modes (Blevins, Table 8-1).
BETA_L = (4.730040744862704, 7.853204624095838)


# ----------------------------------------------------------------------------- fixtures
def cc_shape(xi, n):
    """Clamped-clamped bending shape ``n`` and its slope d/dxi, scaled to max |phi| = 1."""
    bl = BETA_L[n - 1]
    sig = (np.cosh(bl) - np.cos(bl)) / (np.sinh(bl) - np.sin(bl))

    def phi(x):
        b = bl * x
        return np.cosh(b) - np.cos(b) - sig * (np.sinh(b) - np.sin(b))

    b = bl * np.asarray(xi)
    dphi = bl * (np.sinh(b) + np.sin(b) - sig * (np.cosh(b) - np.cos(b)))
    peak = np.abs(phi(np.linspace(0, 1, 4001))).max()
    return phi(np.asarray(xi)) / peak, dphi / peak


def tripod(n_el=6):
    """Three aluminium tube struts from a clamped base circle to a top triangle held by a
    15 kg rigid body; 50 g point masses at the strut mid-spans."""
    m = Model(name="tripod")
    ang = np.deg2rad([90, 210, 330])
    base = np.column_stack([0.45 * np.cos(ang), 0.45 * np.sin(ang), np.zeros(3)])
    top = np.column_stack([0.2 * np.cos(ang + np.pi / 3), 0.2 * np.sin(ang + np.pi / 3), np.full(3, 0.9)])
    sec = Section.tube(0.0127, 0.0016, name="strut")
    struts = []
    for s in range(3):
        ids = np.arange(1 + s * (n_el + 1), 1 + (s + 1) * (n_el + 1))
        m.add_nodes(ids, base[s] + np.linspace(0, 1, n_el + 1)[:, None] * (top[s] - base[s]))
        m.add_beams(100 * (s + 1) + np.arange(n_el), np.column_stack([ids[:-1], ids[1:]]), sec,
                    ALUMINIUM, orient=[0, 0, 1], label=f"strut {s + 1}")
        struts.append(ids)
    m.add_node(1000, top.mean(axis=0))
    m.add_rigid_body(1, 1000, [ids[-1] for ids in struts], mass=15.0)
    m.fix([ids[0] for ids in struts])
    m.add_point_masses([ids[n_el // 2] for ids in struts], 0.05)
    return m, struts


def strut_modes(model, struts):
    """Modes-like object: bending 1 then 2 of each strut alone (clamped-clamped shapes with
    their slopes as nodal rotations), in the horizontal plane across the strut."""
    xyz = model.xyz
    cols, freqs, labels = [], [], []
    for order in (1, 2):
        for s, ids in enumerate(struts):
            idx = model.index_of(ids)
            a, b = xyz[idx[0]], xyz[idx[-1]]
            length = np.linalg.norm(b - a)
            e = (b - a) / length
            d = np.cross(e, [0, 0, 1.0])
            d /= np.linalg.norm(d)
            phi, dphi = cc_shape(np.linspace(0, 1, len(ids)), order)
            u = np.zeros((model.n_nodes, 6))
            u[idx, :3] = phi[:, None] * d
            u[idx, 3:] = (dphi / length)[:, None] * np.cross(e, d)  # slope = theta x e = d dphi/dx
            cols.append(u.ravel())
            freqs.append(60.0 * order**2 * (1 + 0.01 * s))
            labels.append(f"strut {s + 1} bending {order}")
    return SimpleNamespace(shapes_full=np.column_stack(cols), frequencies_hz=np.array(freqs),
                           node_ids=model.node_ids, labels=labels)


@pytest.fixture(scope="module")
def tri():
    model, struts = tripod()
    return model, struts, strut_modes(model, struts)


def reference_image(model, modes, **kw):
    return render.render_mode(model, modes, 2, window_size=REFERENCE_SIZE, **kw)


def mean_abs_diff(a, b):
    """Mean absolute pixel difference, 0-255 scale."""
    return float(np.mean(np.abs(a.astype(float) - b.astype(float))))


# ----------------------------------------------------------------------------- numerics
def test_hermite_interpolation_reproduces_an_end_loaded_cantilever_exactly():
    # Tip-loaded cantilever along a skew axis: w(x) = P x^2 (3L - x) / (6 EI) is cubic, so
    # the Hermite shape functions fed with the closed-form end values give it exactly.
    P, EI, L = 120.0, 3.4e3, 0.8
    e = np.array([1.0, 2.0, 2.0]) / 3.0
    d = np.array([2.0, -1.0, 0.0]) / np.sqrt(5.0)  # transverse, along the load
    x_a = np.array([[0.1, -0.2, 0.3]])
    x_b = x_a + L * e
    tip_w, tip_slope = P * L**3 / (3 * EI), P * L**2 / (2 * EI)
    axial = 1e-3  # a uniform axial stretch on top, linear along the beam
    u_a = np.zeros((1, 6))
    u_b = np.concatenate([tip_w * d + axial * e, tip_slope * np.cross(e, d)])[None]
    xi = np.linspace(0, 1, 17)
    x, u = render.hermite_beam_displacements(x_a, x_b, u_a, u_b, xi)
    s = xi * L
    expected = (P * s**2 * (3 * L - s) / (6 * EI))[:, None] * d + (xi * axial)[:, None] * e
    np.testing.assert_allclose(x[0], x_a + xi[:, None] * L * e, rtol=0, atol=1e-15)
    np.testing.assert_allclose(u[0], expected, rtol=0, atol=1e-12 * tip_w)


def test_hermite_interpolation_keeps_a_rigid_rotation_straight():
    theta = np.array([0.0, 0.0, 0.01])
    x_a, x_b = np.zeros((1, 3)), np.array([[0.5, 0.0, 0.0]])
    u_b = np.concatenate([np.cross(theta, x_b[0]), theta])[None]
    xi = np.linspace(0, 1, 9)
    x, u = render.hermite_beam_displacements(x_a, x_b, np.concatenate([np.zeros(3), theta])[None], u_b, xi)
    np.testing.assert_allclose(u[0], np.cross(theta, x[0]), rtol=0, atol=1e-15)


def test_equivalent_radius_is_the_outer_radius_of_tubes_circles_and_tube_rods():
    tube, circle = Section.tube(0.0127, 0.0016), Section.circle(0.004)
    r = render.equivalent_radius([tube.A, circle.A], [tube.Iy, circle.Iy], [tube.Iz, circle.Iz])
    np.testing.assert_allclose(r, [0.0127, 0.004], rtol=1e-12)
    # A rod's I is a placeholder; its polar moment still gives the tube.
    r_rod = render.equivalent_radius([tube.A], [1.0], [1.0], J=[tube.J], rod=[True])
    np.testing.assert_allclose(r_rod, [0.0127], rtol=1e-12)


def test_a_decoration_follows_its_node_rigid_motion(tri):
    model, struts, _ = tri
    # A mode that only rotates the top (node 1000) about z by 0.02 rad and lifts it 1 mm.
    u = np.zeros((model.n_nodes, 6))
    top = int(model.index_of([1000])[0])
    u[top] = [0, 0, 1e-3, 0, 0, 0.02]
    modes = SimpleNamespace(shapes_full=u.reshape(-1, 1), frequencies_hz=np.array([150.0]),
                            node_ids=model.node_ids)
    box = pv.Cube(center=model.xyz[top] + [0.05, 0.0, 0.03], x_length=0.04, y_length=0.04, z_length=0.02)
    scene = render.mode_scene(model, modes, 1, scale=1.0,
                              decorations=[render.Decoration(box, "gold", node=1000, name="block")])
    mesh = scene.meshes(1.0)["decoration 0: block"]
    rest = np.asarray(scene.ghost_meshes()["decoration 0: block"].points)
    # the drawn solid is the box (its corners repeated per face for flat shading; VTK's
    # normals filter stores points in single precision)
    corners = np.asarray(box.points)
    gap = np.linalg.norm(rest[:, None, :] - corners[None, :, :], axis=2)
    assert gap.min(axis=1).max() < 1e-7 and gap.min(axis=0).max() < 1e-7
    expected = rest + [0, 0, 1e-3] + np.cross([0, 0, 0.02], rest - model.xyz[top])
    np.testing.assert_allclose(mesh.points, expected, rtol=0, atol=1e-12)


def test_mode_shapes_are_matched_to_nodes_by_id_not_position(tri, rng):
    model, _, modes = tri
    perm = rng.permutation(model.n_nodes)
    shuffled = SimpleNamespace(
        shapes_full=modes.shapes_full.reshape(model.n_nodes, 6, -1)[perm].reshape(6 * model.n_nodes, -1),
        frequencies_hz=modes.frequencies_hz, node_ids=model.node_ids[perm])
    a = render.mode_scene(model, modes, 2).meshes()["beams"]
    b = render.mode_scene(model, shuffled, 2).meshes()["beams"]
    np.testing.assert_array_equal(a.points, b.points)
    missing = SimpleNamespace(shapes_full=modes.shapes_full[6:], frequencies_hz=modes.frequencies_hz,
                              node_ids=model.node_ids[1:])
    with pytest.raises(render.RenderError, match=f"node {model.node_ids[0]} of the model has no entry"):
        render.mode_scene(model, missing, 2)


# ----------------------------------------------------------------------------- acceptance 1
def test_png_has_the_requested_size_and_is_not_uniform(tri, tmp_path):
    model, _, modes = tri
    out = tmp_path / "mode.png"
    img = render.render_mode(model, modes, 1, out, window_size=(320, 240))
    from PIL import Image

    with Image.open(out) as im:
        assert im.size == (320, 240)
        pixels = np.asarray(im.convert("RGB"))
    np.testing.assert_array_equal(pixels, img)
    assert img.shape == (240, 320, 3)
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 50
    assert img.std() > 10
    assert not list(tmp_path.glob(".*")), "temporary file left behind"


def test_deformed_image_differs_from_undeformed(tri):
    model, _, modes = tri
    deformed = render.render_mode(model, modes, 1, window_size=(320, 240))
    still = render.render_mode(model, modes, 1, window_size=(320, 240), scale=0.0)
    # Rendering is deterministic (the same scene gives identical pixels, see the reference
    # test), so any difference is the deformation. Ask for more than a rasterisation
    # speck: the bent strut sweeps hundreds of pixels (a 1-pixel line along half the
    # picture height would be ~120).
    changed = np.any(deformed != still, axis=2).sum()
    assert changed > 400, f"only {changed} pixels changed"
    # and only the deformed picture shows the colour of the largest displacement
    top = np.array(render.default_cmap()(1.0)[:3]) * 255
    left = slice(0, int(0.85 * deformed.shape[1]))  # the colour bar sits right of 0.87
    near_top = [(np.abs(img[:, left].astype(float) - top).sum(axis=2) < 90).sum() for img in (deformed, still)]
    assert near_top[0] > 30 and near_top[1] == 0, near_top


def test_gif_has_the_requested_number_of_frames_over_one_period(tri, tmp_path):
    model, _, modes = tri
    out = tmp_path / "mode.gif"
    frames = render.render_mode_gif(model, modes, 2, out, frames=6, window_size=(200, 150))
    from PIL import Image

    with Image.open(out) as im:
        assert im.n_frames == 6
        assert im.size == (200, 150)
        assert im.info.get("loop") == 0
    assert frames.shape == (6, 150, 200, 3)
    # every frame differs from the next (none merged), and half a period later the
    # deflection is mirrored, not repeated
    assert all(mean_abs_diff(frames[j], frames[(j + 1) % 6]) > 0.1 for j in range(6))
    assert mean_abs_diff(frames[1], frames[4]) > 1.0


def test_gif_moves_the_decorations_too():
    # A model that is one node carrying a block: only the block can move in the pictures.
    model = Model()
    model.add_node(1, [0.0, 0.0, 0.0])
    modes = SimpleNamespace(shapes_full=np.array([[0.0], [0.0], [1.0], [0.0], [0.0], [0.0]]),
                            frequencies_hz=np.array([10.0]), node_ids=np.array([1]))
    block = pv.Cube(x_length=0.3, y_length=0.2, z_length=0.1)
    frames = render.render_mode_gif(model, modes, 1, frames=4, window_size=(160, 120),
                                    decorations=[(block, "steelblue", 1)], show_ghost=False)
    # lifts sin(2 pi (j + 1/8) / 4) = 0.38, 0.92, -0.38, -0.92: the block's picture (its
    # blue pixels) ranks from highest to lowest as frames 1, 0, 2, 3 (image rows grow down)
    rows = [np.nonzero((f[:, :, 2].astype(int) - f[:, :, 0]) > 60)[0].mean() for f in frames]
    assert rows[1] < rows[0] < rows[2] < rows[3]


def test_grid_shows_the_first_modes_side_by_side(tri, tmp_path):
    model, _, modes = tri
    img = render.render_mode_grid(model, modes, 4, tmp_path / "grid.png", window_size=(400, 300))
    assert img.shape == (300, 400, 3)
    cells = [img[:150, :200], img[:150, 200:], img[150:, :200], img[150:, 200:]]
    assert all(c.std() > 10 for c in cells)
    assert mean_abs_diff(cells[0], cells[1]) > 1.0  # different modes, different pictures


def test_rendering_needs_no_x_server_and_uses_osmesa(tmp_path):
    script = textwrap.dedent("""
        import numpy as np, pyvista as pv
        from trussid.fem import render
        with render.offscreen_backend():
            p = pv.Plotter(off_screen=True, window_size=(64, 48))
            p.add_mesh(pv.Sphere())
            img = p.screenshot(return_img=True)
            print(type(p.ren_win).__name__, img.shape, float(img.std()) > 0)
            p.close()
    """)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW")}
    res = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.split() == ["vtkOSOpenGLRenderWindow", "(48,", "64,", "3)", "True"]
    assert "X server" not in res.stderr and "WARN" not in res.stderr, res.stderr


# ----------------------------------------------------------------------------- acceptance 2
def test_render_matches_the_stored_reference_image(tri):
    model, _, modes = tri
    img = reference_image(model, modes)
    if os.environ.get("TRUSSID_UPDATE_REFERENCE") == "1":
        from PIL import Image

        DATA.mkdir(exist_ok=True)
        Image.fromarray(img).save(REFERENCE)
        pytest.skip("reference image rewritten")
    ref = np.asarray(__import__("PIL.Image").Image.open(REFERENCE).convert("RGB"))
    assert img.shape == ref.shape
    assert mean_abs_diff(img, ref) < REFERENCE_TOLERANCE


#: Mean absolute pixel difference (0-255) allowed against the reference: antialiasing and
#: rasteriser changes stay well below it; the changes in the test below exceed it.
REFERENCE_TOLERANCE = 0.25


@pytest.mark.parametrize("change", [
    dict(mode=3),                 # another strut bending
    dict(mode=2, amplitude=0.06),  # same mode, 25 % smaller deflection
    dict(mode=2, show_ghost=False),
    dict(mode=2, view=(1.0, -1.45, 0.9)),  # camera turned by about 3 degrees
])
def test_a_visible_change_fails_the_reference_comparison(tri, change):
    model, _, modes = tri
    change = dict(change)
    mode = change.pop("mode")
    ref = np.asarray(__import__("PIL.Image").Image.open(REFERENCE).convert("RGB"))
    img = render.render_mode(model, modes, mode, window_size=REFERENCE_SIZE, **change)
    assert mean_abs_diff(img, ref) > REFERENCE_TOLERANCE


# ----------------------------------------------------------------------------- acceptance 3
def _scalars_and_deflection_per_beam(scene):
    """Per beam id: the largest colour value and the largest deflection of the tube's axis
    (the centroid of each ring of tube-surface points, from the deformed and ghost meshes)."""
    deformed = scene.meshes(1.0)["beams"]
    ghost = scene.ghost_meshes()["beams"]
    ids = np.asarray(deformed.point_data["beam_id"])
    colour = np.asarray(deformed.point_data[render.SCALAR_NAME])
    sample = np.asarray(deformed.point_data["sample"])
    np.testing.assert_array_equal(sample, ghost.point_data["sample"])
    count = np.bincount(sample)

    def centres(mesh):
        p = np.asarray(mesh.points)
        return np.column_stack([np.bincount(sample, p[:, k]) for k in range(3)]) / count[:, None]

    moved = np.linalg.norm(centres(deformed) - centres(ghost), axis=1)
    beam_of_sample = np.zeros(len(count), ids.dtype)
    beam_of_sample[sample] = ids
    uniq = np.unique(ids)
    return (uniq, np.array([colour[ids == k].max() for k in uniq]),
            np.array([moved[beam_of_sample == k].max() for k in uniq]))


def test_hand_made_strut_mode_colours_and_deflects_only_that_strut(tri):
    model, struts, modes = tri
    for mode, strut in [(1, 0), (2, 1), (6, 2)]:
        scene = render.mode_scene(model, modes, mode)
        ids, colour, moved = _scalars_and_deflection_per_beam(scene)
        mine = (ids // 100) == strut + 1
        assert colour[mine].max() == pytest.approx(1.0, abs=2e-3)
        assert colour[~mine].max() < 1e-12
        # the tube surface moves by the drawn amplitude: 8 % of the model's diagonal
        assert moved[mine].max() == pytest.approx(0.08 * scene.diagonal, rel=2e-3)
        assert moved[~mine].max() < 1e-12


def clamped_struts(lengths, n_el=8):
    """Separate aluminium tube struts, clamped at both ends, in one model."""
    m = Model(name="struts")
    sec = Section.tube(0.0127, 0.0016, name="strut")
    for s, length in enumerate(lengths):
        ids = 100 * (s + 1) + np.arange(n_el + 1)
        x = np.column_stack([np.full(n_el + 1, 0.3 * s), np.zeros(n_el + 1), np.linspace(0, length, n_el + 1)])
        m.add_nodes(ids, x)
        m.add_beams(ids[:-1], np.column_stack([ids[:-1], ids[1:]]), sec, ALUMINIUM, orient=[1, 0, 0],
                    label=f"strut {s + 1}")
        m.fix([ids[0], ids[-1]])
    return m, sec


def test_fe_strut_bending_mode_shows_that_strut_deflected_most():
    from trussid.fem.modal import solve_modes

    lengths = [0.9, 0.6, 0.75]
    model, sec = clamped_struts(lengths)
    modes = solve_modes(model, n_modes=6)
    ea = np.sqrt(ALUMINIUM.E * sec.Iy / (ALUMINIUM.rho * sec.A))
    closed_form = {s: BETA_L[0] ** 2 / (2 * np.pi * L**2) * ea for s, L in enumerate(lengths)}
    for s, f in closed_form.items():
        # the two lowest FE modes within 0.5 % of this strut's closed-form frequency
        # (a round tube bends alike in two planes)
        match = np.flatnonzero(np.abs(modes.frequencies_hz / f - 1) < 5e-3)
        assert len(match) == 2, (s, f, modes.frequencies_hz)
        for k in match:
            scene = render.mode_scene(model, modes, int(k) + 1)
            ids, colour, moved = _scalars_and_deflection_per_beam(scene)
            mine = (ids // 100) == s + 1
            assert colour[mine].max() == pytest.approx(1.0, abs=2e-3)
            assert moved[mine].max() > 1e6 * max(moved[~mine].max(), 1e-300)
            # the largest deflection of a first bending mode is at mid-span
            beam = scene.parts[0]
            z = beam.x0[..., 2]
            mid = lengths[s] / 2
            peak = np.unravel_index(np.argmax(np.linalg.norm(beam.u, axis=-1)), z.shape)
            assert abs(z[peak] - mid) < lengths[s] / 16


# ----------------------------------------------------------------------------- the testbed
@pytest.fixture(scope="module")
def testbed():
    """The default testbed's model, its first 18 modes (6 suspension, 12 strut bending),
    their labels and its solids as decorations."""
    testbed_mod = pytest.importorskip("trussid.testbed.model")
    walls_mod = pytest.importorskip("trussid.testbed.walls")

    tbm = testbed_mod.build_testbed()
    modes = walls_mod.solve_testbed_modes(tbm, 18)
    try:
        from trussid.testbed.labels import label_testbed_modes

        labels = label_testbed_modes(tbm, modes).labels
    except ImportError:
        labels = None
    from trussid.testbed.render import testbed_decorations

    return tbm, modes, labels, testbed_decorations(tbm)


def test_testbed_png_has_the_requested_size_and_differs_from_the_undeformed(testbed, tmp_path):
    tbm, modes, labels, decorations = testbed
    out = tmp_path / "testbed.png"
    img = render.render_mode(tbm.model, modes, 9, out, window_size=(360, 270), labels=labels,
                             decorations=decorations)
    still = render.render_mode(tbm.model, modes, 9, window_size=(360, 270), labels=labels,
                               decorations=decorations, scale=0.0)
    from PIL import Image

    with Image.open(out) as im:
        assert im.size == (360, 270)
    assert img.shape == (270, 360, 3) and img.std() > 10
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 50
    assert np.any(img != still, axis=2).mean() > 0.005
    bare = render.render_mode(tbm.model, modes, 9, window_size=(360, 270), labels=labels)
    assert np.any(img != bare, axis=2).mean() > 0.02  # the solids are drawn


def test_testbed_solids_are_attached_to_their_nodes_and_wafers_have_their_own_colour(testbed):
    from trussid.testbed.render import PART_COLOURS

    tbm, _, _, decorations = testbed
    by_name = {d.name: d for d in decorations}
    mp = tbm.map
    assert not any("tube" in name for name in by_name)  # the beams are the tubes
    assert by_name["udf"].node == mp.udf_master
    assert by_name["base"].node == mp.base_master
    for i in range(6):
        adapter = by_name[f"strut {i} adapter"]
        assert adapter.color is None  # coloured by displacement
        assert adapter.node in mp.strut_nodes[i]
        # the node is inside the adapter block (between its end nodes)
        lo, hi = (int(np.flatnonzero(mp.strut_nodes[i] == n)[0]) for n in mp.adapter_nodes[i])
        assert lo <= int(np.flatnonzero(mp.strut_nodes[i] == adapter.node)[0]) <= hi
        wafers = [d for name, d in by_name.items() if name.startswith(f"strut {i} wafer")]
        assert len(wafers) == tbm.testbed.pzt.wafers_per_strut
        assert all(w.color == PART_COLOURS["wafer"] and w.node == adapter.node for w in wafers)


def test_a_solid_without_a_node_is_named_in_the_error():
    import trimesh

    solids = [("strut 0 wafer 0", trimesh.creation.box((0.01, 0.02, 0.03))), ("udf", trimesh.creation.box((1, 1, 1)))]
    with pytest.raises(render.RenderError, match="solid 'udf': no node given"):
        render.decorations_from_solids(solids, {"strut 0 wafer 0": 5})


def test_testbed_gif_has_the_requested_number_of_frames(testbed, tmp_path):
    tbm, modes, labels, decorations = testbed
    out = tmp_path / "testbed.gif"
    frames = render.render_mode_gif(tbm.model, modes, 11, out, frames=5, window_size=(200, 150),
                                    labels=labels, decorations=decorations)
    from PIL import Image

    with Image.open(out) as im:
        assert im.n_frames == 5
    assert all(mean_abs_diff(frames[j], frames[(j + 1) % 5]) > 0.05 for j in range(5))


def test_testbed_strut_bending_modes_show_that_strut_deflected_most(testbed):
    tbm, modes, labels, _ = testbed
    mp = tbm.map
    X = modes.shapes_full.reshape(-1, 6, modes.shapes_full.shape[1])
    idx = tbm.model.index_of(mp.strut_nodes)
    s = (mp.strut_s / mp.strut_s[-1])[:, None]
    checked = 0
    for k in range(modes.shapes_full.shape[1]):
        if modes.frequencies_hz[k] < 5.0:
            continue  # suspension modes
        # From the mode itself: each strut's largest nodal deflection off its chord.
        off_chord = []
        for i in range(6):
            u = X[idx[i], :3, k]
            off_chord.append(u - (1 - s) * u[0] - s * u[-1])
        size = np.array([np.linalg.norm(d, axis=1).max() for d in off_chord])
        strut = int(np.argmax(size))
        assert np.sort(size)[-2] < 0.1 * size[strut], "not a single-strut bending mode"
        if labels is not None:
            assert labels[k].startswith(f"strut {strut} bending 1"), labels[k]
        # From the rendered meshes: colours and tube-axis deflection per strut.
        scene = render.mode_scene(tbm.model, modes, k + 1)
        ids, colour, moved = _scalars_and_deflection_per_beam(scene)
        of = mp.strut_of_element(ids)
        colour_by_strut = np.array([colour[of == i].max() for i in range(6)])
        moved_by_strut = np.array([moved[of == i].max() for i in range(6)])
        assert np.argmax(colour_by_strut) == strut and colour_by_strut[strut] == pytest.approx(1.0, abs=1e-6)
        assert np.argmax(moved_by_strut) == strut
        assert np.delete(colour_by_strut, strut).max() < 0.1
        assert np.delete(moved_by_strut, strut).max() < 0.1 * moved_by_strut[strut]
        # and the drawn strut bends the way the mode does: the largest deflection of the
        # tube's axis off its chord points along the mode's at that station, within 2
        # degrees (up to the sign, which the renderer normalises)
        beam = scene.parts[0]
        mine = np.isin(tbm.model.beams.ids, mp.strut_elements[strut])
        drawn, x = beam.u[mine].reshape(-1, 3), beam.x0[mine].reshape(-1, 3)
        ends = tbm.model.xyz[idx[strut, [0, -1]]]
        t = ((x - ends[0]) @ (ends[1] - ends[0]) / np.sum((ends[1] - ends[0]) ** 2))[:, None]
        drawn_off = drawn - (1 - t) * drawn[np.argmin(t)] - t * drawn[np.argmax(t)]
        j = np.argmax(np.linalg.norm(drawn_off, axis=1))
        node = np.argmin(np.abs(mp.strut_s / mp.strut_s[-1] - t[j, 0]))
        a, b = drawn_off[j], off_chord[strut][node]
        assert abs(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b)) > np.cos(np.radians(2))
        checked += 1
    assert checked == 12


# ----------------------------------------------------------------------------- errors
@pytest.mark.parametrize("mode", [0, -1, 7, 13])
def test_bad_mode_number_names_the_valid_range(tri, mode, tmp_path):
    model, _, modes = tri
    out = tmp_path / "x.png"
    with pytest.raises(render.RenderError, match=r"valid mode numbers are 1 to 6"):
        render.render_mode(model, modes, mode, out)
    assert not out.exists()


def test_wrong_output_suffix_is_refused_before_rendering(tri, tmp_path):
    model, _, modes = tri
    with pytest.raises(render.RenderError, match=r"expected a \.gif file"):
        render.render_mode_gif(model, modes, 1, tmp_path / "x.png")
    with pytest.raises(render.RenderError, match="window size"):
        render.render_mode(model, modes, 1, window_size=(0, 100))
    assert list(tmp_path.iterdir()) == []


DECK = """\
SOL 103
CEND
BEGIN BULK
PARAM,COUPMASS,1
MAT1,1,70.+9,,0.33,2700.
PBARL,1,1,,TUBE
,0.0125,0.0105
GRID,1,,0.,0.,0.
GRID,2,,0.,0.,0.2
GRID,3,,0.,0.,0.4
GRID,4,,0.,0.,0.6
CBAR,1,1,1,2,1.,0.,0.
CBAR,2,1,2,3,1.,0.,0.
CBAR,3,1,3,4,1.,0.,0.
SPC1,1,123456,1
ENDDATA
"""


@pytest.fixture
def deck(tmp_path):
    path = tmp_path / "cantilever.bdf"
    path.write_text(DECK)
    return path


def test_cli_renders_png_and_gif(deck, tmp_path, capsys):
    png, gif = tmp_path / "m2.png", tmp_path / "m2.gif"
    assert cli_main(["render", str(deck), "--mode", "2", "--out", str(png), "--size", "240x180"]) == 0
    assert cli_main(["render", str(deck), "--mode", "2", "--out", str(gif), "--size", "120x90",
                     "--frames", "4"]) == 0
    from PIL import Image

    with Image.open(png) as im:
        assert im.size == (240, 180)
    with Image.open(gif) as im:
        assert im.n_frames == 4
    assert "mode 2" in capsys.readouterr().out


def test_cli_grid_writes_one_png_of_the_first_modes(deck, tmp_path, capsys):
    out = tmp_path / "grid.png"
    assert cli_main(["render", str(deck), "--grid", "3", "--out", str(out), "--size", "300x100"]) == 0
    from PIL import Image

    with Image.open(out) as im:
        assert im.size == (300, 100)
    assert "modes 1 to 3" in capsys.readouterr().out
    assert cli_main(["render", str(deck), "--grid", "3", "--out", str(tmp_path / "grid.gif")]) == 2
    assert "--grid draws a still image" in capsys.readouterr().err


@pytest.mark.parametrize("args, message", [
    (["--mode", "0"], "--mode 0: mode numbers start at 1"),
    (["--mode", "-3"], "--mode -3: mode numbers start at 1"),
    (["--mode", "16"], "--mode 16 is out of range: the model has 15 modes (18 free DOF); valid mode numbers are 1 to 15"),
    (["--grid", "0"], "--grid 0: must be at least 1"),
    (["--size", "big"], "--size 'big': expected WIDTHxHEIGHT"),
    (["--size", "8x8"], "window size 8x8 is out of range"),
    (["--grid", "16"], "--grid 16: only the model has 15 modes"),
    (["--amplitude", "-0.1"], "amplitude must be a finite number >= 0"),
    (["--scale", "nan"], "scale must be a finite number >= 0"),
])
def test_cli_bad_mode_number_is_a_one_line_error(deck, tmp_path, capsys, args, message):
    out = tmp_path / "x.png"
    assert cli_main(["render", str(deck), "--out", str(out)] + args) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [f"trussid render: error: {err.split('error: ', 1)[1].strip()}"]
    assert message in err
    assert "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("name", ["x.jpg", "x", "x.PNG.txt"])
def test_cli_unknown_extension_is_a_one_line_error(deck, tmp_path, capsys, name):
    out = tmp_path / name
    assert cli_main(["render", str(deck), "--mode", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "unknown image type" in err and "use .png or .gif" in err
    assert not out.exists()
    assert list(tmp_path.iterdir()) == [deck]


def test_cli_draws_a_loaded_testbed_with_its_solids_and_labels(testbed, deck):
    from trussid.cli.commands.render import _decorations_and_labels
    from trussid.cli.loaders import LoadedStructure, load_structure

    tbm, modes, labels, decorations = testbed
    decs, labs = _decorations_and_labels(LoadedStructure(tbm.model, "test", testbed=tbm), modes)
    assert sorted(d.name for d in decs) == sorted(d.name for d in decorations)
    assert list(labs) == list(labels)
    decs, labs = _decorations_and_labels(load_structure(deck), modes)  # a deck: bare beams
    assert decs == () and labs is None


def test_cli_renders_the_default_testbed_without_a_model_argument(tmp_path, capsys):
    out = tmp_path / "testbed.png"
    assert cli_main(["render", "--mode", "9", "--out", str(out), "--size", "320x240"]) == 0
    from PIL import Image

    with Image.open(out) as im:
        assert im.size == (320, 240)
    assert "mode 9" in capsys.readouterr().out
