"""The PLID recursions compiled: many samples per call, with the problem's structure used.

:func:`run_direct` and :func:`run_sqrt` process a block of samples with the arithmetic of
:func:`trussid.plid.recursion_direct.direct_step` and
:func:`trussid.plid.recursion_sqrt.sqrt_step` (the references; same model, same moments,
equal to rounding: the tests check 1e-9 relative), in one numba-compiled loop that

- applies ``C`` (a selector or a sum of block components) as a sparse sum and ``F``
  (block-diagonal rotations, a shift) in CSR form, so that ``A_hat X = F X + Abar (C X)``
  costs O((nnz F + n p) cols) instead of O(n^2 cols);
- reads ``P C^T`` as rows of the symmetric ``P`` (contiguous);
- square-root form: applies the product of the p Carlson factors
  ``T = diag(D) + tril(U V^T, -1)`` by a right-to-left running sum, O(d J p), where the
  reference calls a dense triangular product (BLAS trmm, O(d J^2 / 2)), two columns per
  sweep (four with three outputs) with the state correction in the same sweep; applies
  ``F`` in the new x rows by its 2 x 2 blocks (the rotation basis) or else its diagonals;
  takes upper-triangular factors of the p x p (and m x m) weights of the second-order
  moments, so that their Gram stacks n p (p + 1) / 2 rows, not n p^2; and
  triangularises ``[A_hat L_xx, Wf]`` with ``Wf`` triangular by Householder reflections
  that touch n + 1 columns per row (n^3 instead of 5 n^3 / 3);
- allocates nothing per sample.

Why compiled: the numpy steps are bound by about 40 small numpy calls per sample, not by
arithmetic (the project's PLID research notes, section 1: 175 us per sample of which two
BLAS calls carry 69 % of the flops in 22 % of the time). Compiling the same dense
arithmetic gained nothing (the first attempt, recorded in ``recursion_direct``); using the
structure is what gains. ``benchmarks/bench_plid.py`` times both beside each other.

The module is this dispatch and the pure-numpy fallback; the compiled loops live in
:mod:`trussid.plid.kernel_direct` (direct form), :mod:`trussid.plid.kernel_sqrt`
(square-root form) and :mod:`trussid.plid.kernel_common` (what they share).

Without numba (``HAVE_NUMBA`` False) the same functions run the reference steps sample by
sample: same results, at the reference speed. The kernels are compiled on first use and
cached on disk (``cache=True``): the first call in a fresh environment costs the compile
(a few CPU seconds, see the benchmark), later processes load it.
"""

from __future__ import annotations

import numpy as np

from trussid.plid.kernel_common import HAVE_NUMBA, csr, diagonals, pair_blocks
from trussid.plid.kernel_direct import direct_kernel
from trussid.plid.kernel_sqrt import sqrt_kernel
from trussid.plid.recursion_common import Problem, psd_factor
from trussid.plid.recursion_direct import DirectState, direct_step
from trussid.plid.recursion_sqrt import SqrtState, sqrt_step

__all__ = ["HAVE_NUMBA", "KernelRun", "run_direct", "run_sqrt", "compiled"]


class KernelRun:
    """What one block of samples left besides the state: the innovations go to ``E``.

    Attributes
    ----------
    first_bad : int
        Direct form: index (within the block) of the first sample after which a variance
        was not positive, -1 if none.
    failed : int
        Index of the first sample whose step could not be completed (a singular
        innovation covariance or a non-finite moment, where the reference step raises):
        as :class:`~trussid.plid.estimator.PLID` does, the estimate was set to NaN there.
        -1 if none.
    """

    __slots__ = ("first_bad", "failed")

    def __init__(self, first_bad: int = -1, failed: int = -1):
        self.first_bad = first_bad
        self.failed = failed


def _hist_rows(k_done: int, count: int, every: int) -> int:
    if every <= 0:
        return 0
    return (k_done + count) // every - k_done // every


def _ref_loop(step, pb, st, us, ys, E, hist, every, k_done, track, start, run):
    """The reference steps for samples ``start..`` (the fallback and the after-failure path)."""
    hrow = _hist_rows(k_done, start, every)
    for k in range(start, us.shape[0]):
        try:
            step(pb, st, us[k], ys[k], E[k])
        except (np.linalg.LinAlgError, ValueError):
            # as PLID._one: a broken covariance carries on in NaN, reported by the result
            st.z[:] = np.nan
        if track and run.first_bad < 0 and not np.diagonal(st.P).min() > 0:
            run.first_bad = k
        if every and (k_done + k + 1) % every == 0:
            hist[hrow] = st.z[:pb.q]
            hrow += 1
    return run


def _null(pb: Problem):
    N = pb.N if pb.N is not None else np.zeros((pb.m, pb.m))
    qth = pb.Q_theta if pb.Q_theta is not None else np.zeros(pb.q)
    return np.ascontiguousarray(N, dtype=float), np.ascontiguousarray(qth, dtype=float)


def run_direct(pb: Problem, st: DirectState, us: np.ndarray, ys: np.ndarray, E: np.ndarray,
               hist: np.ndarray, hist_every: int, k_done: int, track: bool = True,
               use_kernel: bool | None = None) -> KernelRun:
    """Direct form over ``us[k], ys[k]`` (scaled units), in place on ``st``.

    Parameters
    ----------
    pb, st : Problem, DirectState
        The problem and the state (updated in place).
    us, ys : ndarray (N, m), (N, p)
        Inputs and outputs, scaled.
    E : ndarray (N, p)
        Receives the innovations ``y_k - C x_k^-``.
    hist : ndarray (rows, q)
        Receives theta after every sample whose running count (``k_done`` + index + 1) is a
        multiple of ``hist_every``; ``rows`` from :func:`history_rows`.
    hist_every : int
        Samples between two rows of ``hist`` (0: no history).
    k_done : int
        Samples processed before this block.
    track : bool
        Record the first sample after which a variance was not positive.
    use_kernel : bool or None
        None: the compiled kernel when numba is there; False: the reference steps.

    Returns
    -------
    KernelRun
    """
    run = KernelRun()
    use = HAVE_NUMBA if use_kernel is None else (use_kernel and HAVE_NUMBA)
    if not use:
        return _ref_loop(direct_step, pb, st, us, ys, E, hist, hist_every, k_done, track, 0, run)
    Fp, Fi, Fx = csr(pb.F)
    Cp, Ci, Cx = csr(pb.C)
    N, qth = _null(pb)
    out = np.full(2, -1, dtype=np.int64)
    direct_kernel(st.z, st.P, Fp, Fi, Fx, Cp, Ci, Cx, np.ascontiguousarray(pb.R),
                   np.ascontiguousarray(pb.Q), N, pb.N is not None, qth,
                   pb.Q_theta is not None, np.ascontiguousarray(us), np.ascontiguousarray(ys),
                   E, hist, int(hist_every), int(k_done), pb.n, pb.p, pb.m, bool(track), out)
    run.first_bad, run.failed = int(out[0]), int(out[1])
    return run


def run_sqrt(pb: Problem, st: SqrtState, us: np.ndarray, ys: np.ndarray, E: np.ndarray,
             hist: np.ndarray, hist_every: int, k_done: int,
             use_kernel: bool | None = None) -> KernelRun:
    """Square-root form over a block of samples; as :func:`run_direct` (no variance
    tracking: this form keeps the covariance positive semi-definite by construction).

    A parameter drift (``Q_theta``) re-triangularises the theta rows every sample (an
    O(q^3) QR); that option runs the reference steps.
    """
    run = KernelRun()
    use = HAVE_NUMBA if use_kernel is None else (use_kernel and HAVE_NUMBA)
    if not use or pb.Q_theta is not None:
        return _ref_loop(sqrt_step, pb, st, us, ys, E, hist, hist_every, k_done, False, 0, run)
    Fp, Fi, Fx = csr(pb.F)
    Cp, Ci, Cx = csr(pb.C)
    N, _ = _null(pb)
    # an upper-triangular factor of N (the factor of the reversed N, reversed): the
    # kernel's k-th combination of the b-blocks then reaches only blocks 0..k
    Wn = np.ascontiguousarray(psd_factor(N[::-1, ::-1])[::-1, ::-1])
    out = np.full(2, -1, dtype=np.int64)
    if not st.L.flags.f_contiguous:
        st.L = np.asfortranarray(st.L)
    Fo, Fd = diagonals(pb.F)
    Fb = pair_blocks(pb.F)
    if Fb.shape[0]:
        Fo, Fd = Fo[:0], Fd[:0]       # the kernel applies F by its 2 x 2 blocks instead
    Cd = np.ascontiguousarray(pb.C, dtype=float)
    sqrt_kernel(st.z, st.L, Fp, Fi, Fx, Fo, Fd, Fb, Cp, Ci, Cx, Cd, np.ascontiguousarray(st.Rw),
                 np.ascontiguousarray(st.Hw), int(st.J), np.ascontiguousarray(pb.Q), Wn,
                 pb.N is not None, np.ascontiguousarray(us), np.ascontiguousarray(ys), E, hist,
                 int(hist_every), int(k_done), pb.n, pb.p, pb.m, out)
    run.failed = int(out[1])
    return run


def history_rows(k_done: int, count: int, every: int) -> int:
    """Rows of ``hist`` a block of ``count`` samples after ``k_done`` fills."""
    return _hist_rows(k_done, count, every)


def compiled() -> bool:
    """Whether the compiled kernels are in use (numba importable)."""
    return HAVE_NUMBA
