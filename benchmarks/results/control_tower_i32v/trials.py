# Trials of issue 32 on the PZT tower, frequency-shaped LQG (../control_tower_i32v.md).
# Run from the folder holding the output of `trussid demo pzt_tower.bdf --io pzt_tower_io.toml
# --quick --out rep` (the deck and IO of tests/campaign/structures.py):
#   python trials.py rep > trials.log    (trials.log beside this file: 62 of the 64 designs, the
#   rest cut by the time limit of the run)
import sys, time
import numpy as np
import control
from pathlib import Path; sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
from trussid.plid.modelfile import load_model
from trussid.plid.datafile import read_data
from trussid.lqg.design import mode_rows, _levels, design_lqg, excited_band
from trussid.lqg.procedure import _grade, rank_targets, default_band
from tests.campaign.test_control_by_default import modes_of, mimo_disk_margin_db
out = sys.argv[1] if len(sys.argv) > 1 else "rep"
meta_model, meta = load_model(f"{out}/model_mimo.npz", which="discrete")
data = read_data(f"{out}/data_mimo_ide.npz", inputs=meta.input_names, outputs=meta.output_names)
model = control.ss(meta_model.A, meta_model.B, meta_model.C, meta_model.D, meta_model.dt,
                   inputs=list(data.input_names), outputs=list(data.output_names))
plant, _ = load_model(f"{out}/plant_true.npz")
fs = 1/model.dt
u, y = data.u, data.y
rows = mode_rows(model, _levels(u))
excited = excited_band(u, fs)
def truth_eval(ctrl):
    Ap, Bp, Cp, Dp = (np.asarray(M) for M in (plant.A, plant.B, plant.C, plant.D))
    iy = [list(plant.output_labels).index(n) for n in ctrl.input_labels]
    iu = [list(plant.input_labels).index(n) for n in ctrl.output_labels]
    Bu, Cy, Dyu = Bp[:, iu], Cp[iy], Dp[np.ix_(iy, iu)]
    Ac, Bc, Cc, Dc = (np.asarray(M) for M in (ctrl.A, ctrl.B, ctrl.C, ctrl.D))
    lam_o, s_o, f_o, z_o = modes_of(Ap, fs)
    up = lam_o.imag > 0
    Acl = np.block([[Ap, Bu @ Cc], [Bc @ Cy, Ac + Bc @ Dyu @ Cc]])
    lam, s, f, z = modes_of(Acl, fs)
    rho = np.max(np.abs(lam))
    V = np.linalg.eig(Ap)[1]; W = np.linalg.inv(V)
    residue = np.array([np.linalg.norm(np.outer(Cy @ V[:, i], W[i] @ Bu), 2) for i in range(len(lam_o))])
    below = np.flatnonzero(up & (f_o < 0.25 * fs))
    targets = below[np.argsort(-residue[below])[:3]]
    owner = np.argmin(np.abs(s[:, None] - s_o[None, :]), axis=1)
    tz, worst_other = [], (9, None)
    for i in np.flatnonzero(up & (f_o < 0.4 * fs)):
        mine = (owner == i) & (lam.imag >= 0)
        if not mine.any():
            mine = np.arange(lam.size) == np.argmin(np.abs(s - s_o[i]))
        near = mine & (np.abs(f - f_o[i]) <= 0.01 * f_o[i])
        worst = z[near].min() if near.any() else z[mine].min()
        if i in targets: tz.append((f_o[i], worst))
        else:
            r = worst / z_o[i]
            if r < worst_other[0]: worst_other = (r, f_o[i])
    gm = mimo_disk_margin_db((Ap, Bu, Cy, Dyu), (Ac, Bc, Cc, Dc), fs, f_o[up & (z_o < 0.05)]) if rho < 1 else float('nan')
    tz.sort()
    ok = rho < 1 and all(w >= 0.03 for _, w in tz) and worst_other[0] >= 0.8 and gm >= 6
    return (f"TRUTH rho {rho:.5f} targets " + " / ".join(f"{f:.1f}:{100*w:.2f}%" for f, w in tz)
            + f" others min {worst_other[0]:.2f}@{worst_other[1]:.1f} gm {gm:.1f} dB {'PASS' if ok else 'fail'}")

from trussid.lqg.shaping import InputWeight
def run(tset, zeta, peaks=None, quiet=False, **kw):
    t0 = time.process_time()
    w = None if peaks is None else InputWeight(tuple(peaks), model.dt)
    des = design_lqg(model, u, y, target_damping=zeta, verify=False, blocks=tset, K=meta.K, input_weight=w, **kw)
    failure, detail, gm, ratio, reached = _grade(model, des, tset, rows, 0.07, excited, 6.0, 0.8)
    print(f"[{[round(rows[b].frequency_hz) for b in tset]} z {np.round(zeta,3)} W {peaks}] model: {failure or 'ok'} {detail} gm {gm and round(gm,1)} others {ratio and round(ratio,2)} reached {np.round(100*np.array(reached),2)} sf {[round(100*t.state_feedback_damping,2) for t in des.target_modes]} ({time.process_time()-t0:.1f}s)")
    print("   ", truth_eval(des.controller), flush=True)
    return des


W_SETS = {  # (f0 [Hz], half width [Hz], gain) per section of the input weight
    "none": None,
    "oob": [(514, 10, 5), (760, 20, 5)],
    "cl365": [(365, 6, 10)],
    "cl365+oob": [(365, 6, 10), (514, 10, 5), (760, 20, 5)],
    "cl2+oob": [(355, 3, 5), (367, 4, 5), (514, 10, 5), (760, 20, 5)],
    "n392": [(392, 1.5, 2)],
    "n392+n361": [(392, 1.5, 2), (361, 1.5, 2)],
    "n392+n361+oob": [(392, 1.5, 2), (361, 1.5, 2), (514, 10, 5), (760, 20, 5)],
}

if __name__ == "__main__":
    import itertools
    for (z1, z3), (name, pk), ez in itertools.product(
            ((0.035, 0.03), (0.04, 0.03), (0.04, 0.035), (0.045, 0.03)), W_SETS.items(),
            (None, 0.04)):
        print(f"## z1 {z1} z3 {z3} W {name} est {ez}")
        try:
            run([2, 3, 6], np.array([z1, 0.03, z3]), peaks=pk, estimator_damping=ez)
        except Exception as e:
            print("ERR", e)
