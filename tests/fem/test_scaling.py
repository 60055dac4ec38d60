"""Scaling guards for the FE path (assembly, constraints, modes): memory and work grow
linearly with the model on a truss boom, and nothing of size n_dof x n_dof is formed.

Why: a thin SVD that became a full one (an n_dof x n_dof dense U in
``rigid_null_dimension``) made the 1.5e4-DOF boom take 14 s and 3.5 GB, and the 1.5e5-DOF
one impossible on a 24 GB machine, and nothing caught it (issue 18). No wall-clock time is
asserted here; memory and operation counts are.

Each size is solved in a fresh child process, so its peak resident set size (``VmHWM``)
is its own: the model's share is the peak minus the RSS once the model is built (imports,
interpreter and model excluded). ``tracemalloc`` sees every numpy array besides; the
operation count is the number of factor solves times the factor's stored entries (the
work of the shift-invert iterations), plus the factor entries themselves.

A dense n x n float array is 1.8 GB at 1.5e4 DOF; the bounds below are a fraction of that,
and several times what a linear-memory solution uses (measured: ~40 MB).
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: Child process: build a boom of ``n_bays`` bays (benchmarks/fem_models.py, 72 n + 18 DOF),
#: assemble it and solve 20 modes, then print the measurements as JSON.
CHILD = r"""
import json, sys, tracemalloc
sys.path.insert(0, sys.argv[2])
from fem_models import to_trussid, truss_boom
from trussid.fem.assembly import assemble
from trussid.fem.factor import SPDFactor
from trussid.fem.modal import solve_modes

def status(field):
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024.0

factors, solves = [], [0]
init, solve = SPDFactor.__init__, SPDFactor.solve
def counting_init(self, *a, **k):
    init(self, *a, **k)
    factors.append(self)
def counting_solve(self, b):
    solves[0] += 1
    return solve(self, b)
SPDFactor.__init__, SPDFactor.solve = counting_init, counting_solve

model = to_trussid(truss_boom(int(sys.argv[1])))
base = status("VmRSS")
tracemalloc.start()
system = assemble(model)
modes = solve_modes(system, 20)
traced = tracemalloc.get_traced_memory()[1] / 2**20
tracemalloc.stop()
peak = status("VmHWM")
nnz = [f.factor_nnz() for f in factors]
print("RESULT " + json.dumps({
    "n_dof": int(system.n_dof), "rss_share_mb": peak - base, "traced_peak_mb": traced,
    "solves": solves[0], "factor_nnz": int(sum(nnz)),
    "ops": int(sum(nnz) + solves[0] * max(nnz)), "f1_hz": float(modes.frequencies_hz[0])}))
"""


def measure(n_bays: int) -> dict:
    """Measurements of one boom size in a fresh process (see :data:`CHILD`)."""
    out = subprocess.run([sys.executable, "-c", CHILD, str(n_bays), str(ROOT / "benchmarks")],
                         capture_output=True, text=True, timeout=600,
                         env={"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                              "PATH": "/usr/bin:/bin"})
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("RESULT ")]
    assert out.returncode == 0 and lines, out.stderr[-2000:]
    return json.loads(lines[-1][len("RESULT "):])


@pytest.fixture(scope="module")
def boom_sizes():
    """52 and 208 bays: 3 762 and 14 994 DOF (a factor 3.99)."""
    return measure(52), measure(208)


def test_a_15000_dof_boom_solves_in_linear_memory(boom_sizes):
    """The 1.5e4-DOF boom's own peak memory stays far below one dense n x n array (1.8 GB):
    both as the process sees it (RSS, C libraries included) and as numpy allocates it."""
    big = boom_sizes[1]
    assert big["n_dof"] == 14994
    dense_mb = big["n_dof"] ** 2 * 8 / 2**20
    assert big["rss_share_mb"] < 300.0, big           # 1/6 of a dense n x n
    assert big["traced_peak_mb"] < 150.0, big
    assert big["rss_share_mb"] < dense_mb / 6


def test_memory_and_work_grow_linearly_with_the_boom(boom_sizes):
    """Four times the DOFs: memory and operation counts grow about four times (a bound of
    6.5x; a quadratic term would give ~16x). The boom is a 1-D structure, so the fill of
    a good ordering is linear in its length."""
    small, big = boom_sizes
    ratio = big["n_dof"] / small["n_dof"]
    assert 3.9 < ratio < 4.1
    limit = 1.6 * ratio
    assert big["traced_peak_mb"] / small["traced_peak_mb"] < limit, (small, big)
    # RSS shares of a few tens of MB carry allocator noise of a few MB: compare above a floor.
    assert max(big["rss_share_mb"], 20.0) / max(small["rss_share_mb"], 20.0) < limit, (small, big)
    assert big["factor_nnz"] / small["factor_nnz"] < limit, (small, big)
    assert big["ops"] / small["ops"] < limit, (small, big)
