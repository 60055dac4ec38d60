"""``trussid demo DECK --io IO.toml`` on a structure that is not the testbed, then
``trussid control`` on its MIMO model, checked on the campaign's true plant with this
file's own algebra (issue 24, acceptance 1).

The structure: a cantilevered three-bay truss tower of triangular section (steel tubes,
uneven tip masses), two force shakers, three accelerometers (so the plant has a
feed-through), sampled at 2 kHz.
"""

import json

import numpy as np
import pytest

from trussid import fem
from trussid.cli import main
from trussid.fem.render_html import external_references
from trussid.plid.modelfile import load_model

IO = """
[plant]
fs = 2000.0
damping = 0.01

[[actuator]]
name = "shaker_a"
type = "force"
node = 31
direction = [0, 0, 1]

[[actuator]]
name = "shaker_b"
type = "force"
node = 33
direction = [0, 1, 0]

[[sensor]]
name = "acc_a"
node = 31
direction = [0, 0, 1]
quantity = "acceleration"

[[sensor]]
name = "acc_b"
node = 33
direction = [0, 1, 0]
quantity = "acceleration"

[[sensor]]
name = "acc_mid"
node = 22
direction = [0, 0, 1]
quantity = "acceleration"
"""


def tower() -> fem.Model:
    """Three bays of 0.4 m over an uneven triangle, one element per member, lumped mass."""
    m = fem.Model(mass="lumped")
    tri = [(0.0, 0.0), (0.3, 0.0), (0.1, 0.25)]
    ids = [10 * b + c + 1 for b in range(4) for c in range(3)]
    xyz = np.array([[0.4 * b, y, z] for b in range(4) for (y, z) in tri])
    m.add_nodes(ids, xyz)
    pos = dict(zip(ids, xyz))
    members = []
    for b in range(3):
        for c in range(3):
            members += [(10 * b + c + 1, 10 * (b + 1) + c + 1),             # longeron
                        (10 * b + c + 1, 10 * (b + 1) + (c + 1) % 3 + 1)]   # diagonal
    for b in range(1, 4):
        members += [(10 * b + c + 1, 10 * b + (c + 1) % 3 + 1) for c in range(3)]  # battens
    tube = fem.Section.tube(0.008, 0.001)
    for e, (a, b) in enumerate(members, start=1):
        m.add_beams([e], [[a, b]], tube, fem.STEEL,
                    orient=np.cross(pos[b] - pos[a], [0.3, 0.4, 1.0]))
    m.add_point_masses([31, 32, 33], [2.0, 1.5, 1.0])
    m.fix([1, 2, 3])
    return m


def modes_of(A, fs):
    lam = np.linalg.eigvals(A).astype(complex)
    s = np.log(lam) * fs
    return lam, s, np.abs(s) / (2 * np.pi), -s.real / np.abs(s)


@pytest.mark.slow
def test_demo_on_a_deck_then_control_damps_the_dominant_modes_on_the_true_plant(tmp_path):
    fem.write_bdf(tower(), tmp_path / "tower.bdf", n_modes=20)
    (tmp_path / "io.toml").write_text(IO)
    out = tmp_path / "rep"
    assert main(["demo", str(tmp_path / "tower.bdf"), "--io", str(tmp_path / "io.toml"),
                 "--quick", "--out", str(out)]) == 0
    for name in ("plant_true.npz", "model_mimo.npz", "data_mimo_ide.npz", "summary.json",
                 "report.md", "model_simo_ch1.npz"):
        assert (out / name).exists(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["plant"]["sample_rate_hz"] == 2000.0
    mimo = [m for m in summary["models"] if m["name"] == "mimo"][0]
    assert mimo["frf_rms_error_db"] < 1.0  # the identified model is the plant
    # report.html for any structure: the deck's modes in 3-D, its sensors by name, one file
    page = (out / "report.html").read_text()
    assert 'trussidModeViewer("modes3d"' in page and external_references(page) == []
    assert all(f'"{name}"' in page for name in ("acc_a", "acc_b", "acc_mid"))

    ctrl_file = tmp_path / "c.npz"
    assert main(["control", str(out / "model_mimo.npz"), "--data",
                 str(out / "data_mimo_ide.npz"), "--out", str(ctrl_file), "--band", "0",
                 "500", "--modes", "3", "--target-damping", "0.05"]) == 0

    # the loop from the files, feed-through included: y = Cp xp + Dp u, u = Cc xc
    plant, _ = load_model(out / "plant_true.npz")
    ctrl, meta = load_model(ctrl_file)
    fs = 1 / plant.dt
    Ap, Bp, Cp, Dp = (np.asarray(M) for M in (plant.A, plant.B, plant.C, plant.D))
    assert np.any(Dp != 0)
    iy = [list(plant.output_labels).index(n) for n in ctrl.input_labels]
    iu = [list(plant.input_labels).index(n) for n in ctrl.output_labels]
    Bu, Cy, Dyu = Bp[:, iu], Cp[iy], Dp[np.ix_(iy, iu)]
    Ac, Bc, Cc, Dc = (np.asarray(M) for M in (ctrl.A, ctrl.B, ctrl.C, ctrl.D))
    assert not np.any(Dc)
    Acl = np.block([[Ap, Bu @ Cc], [Bc @ Cy, Ac + Bc @ Dyu @ Cc]])
    lam, s, f, z = modes_of(Acl, fs)
    assert np.max(np.abs(lam)) < 1  # stable on the campaign's true plant

    lam_o, s_o, f_o, z_o = modes_of(Ap, fs)
    V = np.linalg.eig(Ap)[1]
    W = np.linalg.inv(V)
    residue = np.array([np.linalg.norm(np.outer(Cy @ V[:, i], W[i] @ Bu), 2)
                        for i in range(len(lam_o))])
    up = lam_o.imag > 0
    below = np.flatnonzero(up & (f_o < 0.25 * fs))
    targets = below[np.argsort(-residue[below])[:3]]
    # each closed-loop pole belongs to the open-loop mode nearest in the s-plane
    owner = np.argmin(np.abs(s[:, None] - s_o[None, :]), axis=1)
    for i in np.flatnonzero(up & (f_o < 0.4 * fs)):
        mine = (owner == i) & (lam.imag >= 0)
        near = mine & (np.abs(f - f_o[i]) <= 0.01 * f_o[i])
        worst = z[near].min() if near.any() else z[mine].min()
        if i in targets:
            assert worst >= 0.03, (f_o[i], worst)
        else:
            assert worst >= 0.8 * z_o[i], (f_o[i], worst, z_o[i])
