"""Scaling guard for identification over record length: :func:`trussid.plid.identify`
(N4SID prior, then the PLID recursion) must use memory and operations linear in the number
of samples N; nothing N x N may be formed.

Why: nfoursid's own final step takes a full SVD of a (p i) x N matrix, an N x N factor
(47 s at N = 10 000; ``trussid.plid.subspace`` takes the thin one instead). A regression of
that kind, or a per-sample step that grows with N, shows here as super-linear growth.

Memory is numpy's peak as ``tracemalloc`` sees it (every numpy array is traced); the
operation count is the number of Python-level calls (``cProfile``), which a recursion that
does a fixed amount of work per sample makes linear in N. No wall-clock time is asserted.
"""

import cProfile
import pstats
import tracemalloc

import numpy as np
from trussid.plid import identify

FS = 1000.0


def costs(modal_plant, simulate) -> dict:
    """Peak traced memory [MB] and call counts of ``identify`` at N and 4 N samples."""
    rng = np.random.default_rng(7)
    plant = modal_plant([50.0, 120.0], [0.01, 0.02], 1, 1, FS, rng)

    def record(n):
        u = rng.standard_normal((n, 1))
        y, _ = simulate(plant, u, rng, 40.0)
        return u, y

    identify(*record(200), 4, 1 / FS)  # warm-up: first-call imports are not the record's cost
    out = {}
    for n in (500, 2000):
        u, y = record(n)
        prof = cProfile.Profile()
        tracemalloc.start()
        prof.enable()
        idn = identify(u, y, 4, 1 / FS)
        prof.disable()
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        assert idn.model.nstates == 4
        out[n] = {"peak_mb": peak, "calls": pstats.Stats(prof).total_calls}
    return out


def test_identify_memory_and_operations_grow_linearly_with_record_length(modal_plant, simulate):
    """Four times the samples: at most 6.4x the peak memory and the calls (an N x N term
    gives ~16x; the fixed setup makes the call ratio less than 4x)."""
    c = costs(modal_plant, simulate)
    small, big = c[500], c[2000]
    assert big["peak_mb"] / small["peak_mb"] < 6.4, c
    assert big["peak_mb"] < 2000**2 * 8 / 2**20, c      # below one N x N array (31 MB)
    assert big["calls"] / small["calls"] < 6.4, c
