"""Three structures that are not the testbed and not like each other (issue 32's acceptance):
decks and IO files written here, each with at least two actuators, three accelerometers
(a feed-through), sampled at 1-4 kHz, with more modes below Nyquist than the campaign's
identified model has states.

- :func:`pzt_tower`: a tapered three-bay truss tower of aluminium tubes, PZT wafer pairs
  bending three leg members near the base, 2 kHz, 0.5 % damping (the tower of issue 32).
- :func:`force_grid`: a cantilevered planar grid of steel rectangular bars (a frame with
  rigid joints, bending out of its plane), two force shakers, 1 kHz, 1 % damping.
- :func:`lattice_beam`: a long, pinned-pinned beam-like lattice of steel rods with a
  PZT in extension and a shaker, one collocated and two non-collocated accelerometers,
  4 kHz, 0.8 % damping.
"""

from __future__ import annotations

import numpy as np

from trussid import fem

WAFER = ('{ width = 0.008, length = 0.06, thickness = 0.0005, youngs_modulus = 6.3e10, '
         'd31 = -1.9e-10 }')


def _members(m, pairs, pos, section, material, n_el, orient, first_node):
    """Each member ``(a, b)`` of ``pairs`` as ``n_el`` beam elements (new nodes numbered
    from ``first_node``); returns the element ids of each member."""
    nid, eid, out = first_node, 0, []
    for a, b in pairs:
        chain = [a]
        for k in range(1, n_el):
            m.add_nodes([nid], [pos[a] + (pos[b] - pos[a]) * k / n_el])
            chain.append(nid)
            nid += 1
        chain.append(b)
        ids = list(range(eid + 1, eid + n_el + 1))
        eid += n_el
        o = orient(pos[a], pos[b])
        m.add_beams(ids, [[chain[k], chain[k + 1]] for k in range(n_el)], section, material,
                    orient=o)
        out.append(ids)
    return out


def _sensors(rows):
    return "".join(f"""
[[sensor]]
name = "{name}"
node = {node}
direction = {list(direction)}
quantity = "acceleration"
""" for name, node, direction in rows)


def pzt_tower():
    """``(fem.Model, IO text)``: three bays of 0.35 m over a triangle that narrows from
    0.30 m to 0.18 m, aluminium tubes, lumped mass, a 0.8 kg tip mass; PZT pairs on the
    three first-bay legs."""
    m = fem.Model(mass="lumped")
    ids, xyz = [], []
    for b in range(4):
        s = 0.30 - 0.04 * b
        for c, ang in enumerate((90.0, 210.0, 330.0)):
            a = np.radians(ang)
            ids.append(10 * b + c + 1)
            xyz.append([s / np.sqrt(3) * np.cos(a), s / np.sqrt(3) * np.sin(a), 0.35 * b])
    xyz = np.array(xyz)
    m.add_nodes(ids, xyz)
    pos = dict(zip(ids, xyz))
    members = []
    for b in range(3):
        for c in range(3):
            members += [(10 * b + c + 1, 10 * (b + 1) + c + 1),
                        (10 * b + c + 1, 10 * (b + 1) + (c + 1) % 3 + 1)]
    for b in range(1, 4):
        members += [(10 * b + c + 1, 10 * b + (c + 1) % 3 + 1) for c in range(3)]
    els = _members(m, members, pos, fem.Section.tube(0.008, 0.0015), fem.ALUMINIUM, 2,
                   lambda a, b: np.cross(b - a, [0.3, 0.4, 1.0]), 1000)
    m.add_point_masses([31, 32, 33], [0.8, 0.5, 0.3])
    m.fix([1, 2, 3])
    # the first-bay legs are members 0, 2, 4 (longerons from nodes 1, 2, 3): their first
    # element, at the foot
    io = """
[plant]
fs = 2000.0
damping = 0.005
""" + "".join(f"""
[[actuator]]
name = "pzt_leg{k}"
type = "strain"
elements = [{e}]
offset = 0.00825
face_axis = "y"
arrangement = "bending"
n_wafers = 2
wafer = {WAFER}
""" for k, e in ((1, els[0][0]), (2, els[2][0]), (3, els[4][0]))) + _sensors(
        [("acc_31x", 31, (1, 0, 0)), ("acc_32y", 32, (0, 1, 0)), ("acc_23x", 23, (1, 0, 0))])
    return m, io


def force_grid():
    """``(fem.Model, IO text)``: a 3 x 4 grid of 0.25 m steel bars (20 x 6 mm, the thin side
    out of plane) in the x-y plane, clamped along its y = 0 edge, bending out of plane
    (z); two shakers at the free corners, accelerometers at the free edge and mid-span."""
    m = fem.Model(mass="lumped")
    nx, ny, h = 4, 5, 0.25
    ids = [100 * j + i + 1 for j in range(ny) for i in range(nx)]
    xyz = np.array([[h * i, h * j, 0.0] for j in range(ny) for i in range(nx)])
    m.add_nodes(ids, xyz)
    pos = dict(zip(ids, xyz))
    pairs = [(100 * j + i + 1, 100 * j + i + 2) for j in range(ny) for i in range(nx - 1)]
    pairs += [(100 * j + i + 1, 100 * (j + 1) + i + 1) for j in range(ny - 1) for i in range(nx)]
    _members(m, pairs, pos, fem.Section.rectangle(0.020, 0.006), fem.STEEL, 3,
             lambda a, b: np.array([0.0, 0.0, 1.0]), 1000)
    m.add_point_masses([401, 404], [0.4, 0.25])
    m.fix([1, 2, 3, 4])
    io = """
[plant]
fs = 1000.0
damping = 0.01

[[actuator]]
name = "shaker_corner_a"
type = "force"
node = 401
direction = [0, 0, 1]

[[actuator]]
name = "shaker_corner_b"
type = "force"
node = 404
direction = [0, 0, 1]
""" + _sensors([("acc_401", 401, (0, 0, 1)), ("acc_403", 403, (0, 0, 1)),
                ("acc_202", 202, (0, 0, 1))])
    return m, io


def lattice_beam():
    """``(fem.Model, IO text)``: a 2.4 m pinned-pinned lattice beam (Warren truss of two
    chords 0.12 m apart, twelve 0.2 m bays) of steel rods, in the x-z plane, braced out of
    plane by its supports; a PZT in extension on a lower chord bay and a shaker at the
    upper chord; one accelerometer collocated with the shaker, two not."""
    m = fem.Model(mass="lumped")
    nb, L, H = 12, 0.2, 0.12
    low = [i + 1 for i in range(nb + 1)]
    up = [101 + i for i in range(nb)]
    m.add_nodes(low, [[L * i, 0.0, 0.0] for i in range(nb + 1)])
    m.add_nodes(up, [[L * (i + 0.5), 0.0, H] for i in range(nb)])
    pos = {**{n: np.array([L * i, 0.0, 0.0]) for i, n in enumerate(low)},
           **{n: np.array([L * (i + 0.5), 0.0, H]) for i, n in enumerate(up)}}
    pairs = [(low[i], low[i + 1]) for i in range(nb)] + \
            [(up[i], up[i + 1]) for i in range(nb - 1)] + \
            [(low[i], up[i]) for i in range(nb)] + [(up[i], low[i + 1]) for i in range(nb)]
    els = _members(m, pairs, pos, fem.Section.circle(0.006), fem.STEEL, 2,
                   lambda a, b: np.array([0.0, 1.0, 0.0]), 1000)
    m.add_point_masses(up[3::4], 0.15)
    m.fix(low + up + list(range(1000, 1000 + len(pairs))), "246")  # planar
    m.fix([1], "135")
    m.fix([nb + 1], "35")
    io = """
[plant]
fs = 4000.0
damping = 0.008

[[actuator]]
name = "pzt_chord"
type = "strain"
elements = [""" + str(els[3][0]) + """]
offset = 0.00625
face_axis = "z"
arrangement = "extension"
n_wafers = 2
wafer = """ + WAFER + """

[[actuator]]
name = "shaker"
type = "force"
node = 108
direction = [0, 0, 1]
""" + _sensors([("acc_shaker", 108, (0, 0, 1)), ("acc_quarter", 103, (0, 0, 1)),
                ("acc_low", 10, (1, 0, 0))])
    return m, io


def write(tmp, name, builder, n_modes=120):
    """The deck ``name.bdf`` and ``name_io.toml`` of ``builder()`` in ``tmp``; their paths."""
    model, io = builder()
    deck, iof = tmp / f"{name}.bdf", tmp / f"{name}_io.toml"
    fem.write_bdf(model, deck, n_modes=n_modes)
    iof.write_text(io)
    return deck, iof
