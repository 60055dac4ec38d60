# Per-mode estimator damping on the 399 Hz target (../control_tower_i32v.md, 2b): run as trials.py
import sys; from pathlib import Path
exec((Path(__file__).parent / "trials.py").read_text().split("\nW_SETS")[0])
import itertools
for ez3, z3, z1, wn in itertools.product((0.01, 0.015, 0.02), (0.03, 0.04), (0.035, 0.04), ("none", "oob")):
    pk = None if wn == "none" else [(514, 10, 5), (760, 20, 5)]
    print(f"## z1 {z1} z3 {z3} W {wn} est [0.025 0.025 {ez3}]")
    try: run([2,3,6], np.array([z1, 0.03, z3]), peaks=pk, estimator_damping=np.array([0.025, 0.025, ez3]))
    except Exception as e: print("ERR", e)
