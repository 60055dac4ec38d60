"""Quick subspace (N4SID) estimates: the comparator for PLID and an optional PLID prior.

The subspace step is PO-MOESP as Verhaegen and Verdult give it (*Filtering and System
Identification*, Cambridge 2007, p. 329): block Hankel matrices of past and future inputs
and outputs, one QR factorisation, the SVD of the observability estimate, then least
squares for the system matrices from the estimated state sequence. It is the algorithm of
the ``nfoursid`` package, step for step (tests compare the two to rounding), written out
here because nfoursid (i) always fits a direct term D in its final least squares, where
PLID models have none and dropping an estimated D costs accuracy (0.23 dB on the 24-state
plant of ``docs/plid.md``), so that step must be redone with D = 0 on the same state
sequence; (ii) takes a full SVD of the (p i) x N observability estimate, an N x N factor
(47 s at N = 10000), where a thin SVD gives the same leading triplets; and (iii) takes its
data as a pandas DataFrame. Reaching into its internals for (i) and (ii) was brittle.

:func:`refit_input_matrix` then re-estimates ``B`` (and the initial state) with ``A, C``
fixed and ``D = 0`` by output-error least squares, which is linear: in modal coordinates
every regressor is a one-pole filter of an input (``scipy.signal.lfilter``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import control
import numpy as np
import scipy.linalg
import scipy.linalg.lapack

from trussid.plid._linalg import lstsq, real_modal_regressors
from trussid.plid._validate import as_2d
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.experiment import simulate
from trussid.plid.stability import stabilise

__all__ = ["SubspaceChoice", "SubspaceFit", "n4sid", "po_moesp", "block_hankel", "refit_input_matrix",
           "output_error_fit", "direct_term_test", "subspace_prior", "cached_n4sid",
           "default_block_rows", "DEFAULT_BLOCK_ROWS", "sweep_block_rows", "MIN_GAIN_DB"]


@dataclass
class SubspaceChoice:
    """Which block-row count :func:`subspace_prior` kept, and how each candidate scored.

    Attributes
    ----------
    block_rows : int
    candidates : dict of int to float
        Output-error ratio [dB] of the prior with each block-row count tried (data alone).
    stopped : str or None
        Why the default sweep stopped where it did (None: the block rows were given, all
        tried).
    """

    block_rows: int
    candidates: dict
    stopped: str | None = None


@dataclass
class SubspaceFit:
    """Matrices of one subspace run (discrete, sample time ``dt``) and its two models.

    ``with_d`` (the least squares on ``[x; u]`` with a direct term: nfoursid's model) and
    ``zero_d`` (same ``A, B``, ``C0`` from the least squares on ``x`` alone, ``D = 0``) are
    built on first use: a ``control.StateSpace`` costs about 0.1 ms, and ``identify`` uses
    one of the two per run. ``scored`` holds the priors' scored candidates built from this
    run (:func:`subspace_prior`, :func:`trussid.plid.feedthrough.direct_prior`), so that a
    candidate is refitted and scored once however many sweeps read it.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray                    # with D
    D: np.ndarray
    C0: np.ndarray                   # of the least squares with D = 0
    dt: float
    block_rows: int
    singular_values: np.ndarray      # of the observability estimate (order selection)
    scored: dict = field(default_factory=dict, repr=False)

    @cached_property
    def with_d(self) -> control.StateSpace:
        """The least squares with a direct term (nfoursid's model)."""
        return control.ss(self.A, self.B, self.C, self.D, self.dt)

    @cached_property
    def zero_d(self) -> control.StateSpace:
        """Same state sequence, least squares with ``D = 0``."""
        return control.ss(self.A, self.B, self.C0, np.zeros_like(self.D), self.dt)

    @cached_property
    def stable_zero_d(self) -> control.StateSpace:
        """:attr:`zero_d` with any unstable pole reflected in
        (:func:`trussid.plid.stability.stabilise`): the ``A, C`` of the strictly proper
        prior this run gives (:func:`subspace_prior` refits only ``B``), which the
        direct-term test of :func:`trussid.plid.recipe.identify` reads without that
        refit."""
        return _stabilised(self.zero_d)

    @cached_property
    def stable_with_d(self) -> control.StateSpace:
        """:attr:`with_d` with any unstable pole reflected in."""
        return _stabilised(self.with_d)


def block_hankel(a: np.ndarray, rows: int) -> np.ndarray:
    """Block Hankel matrix of the samples ``a`` (N, c): ``rows`` block rows of c entries,
    N - rows + 1 columns; column k stacks samples k .. k + rows - 1."""
    w = np.lib.stride_tricks.sliding_window_view(a, rows, axis=0)  # (N - rows + 1, c, rows)
    return np.ascontiguousarray(w.transpose(0, 2, 1).reshape(w.shape[0], -1).T)


def po_moesp(u: np.ndarray, y: np.ndarray, block_rows: int):
    """``(R22, R32, singular values of R32, [U; Y] past Hankel)`` of PO-MOESP.

    The instrument is past inputs and outputs; the R factors are blocks of the QR
    factorisation of ``[U_f; U_p; Y_p; Y_f]`` (as its transpose's QR).
    """
    i = block_rows
    uh, yh = block_hankel(u, i), block_hankel(y, i)
    stacked = np.concatenate([uh[:, i:], uh[:, :-i], yh[:, :-i], yh[:, i:]])
    r = np.linalg.qr(stacked.T, mode="r").T
    y_rows, u_rows = y.shape[1] * i, u.shape[1] * i
    R32 = r[-y_rows:, u_rows:-y_rows]
    R22 = r[u_rows:-y_rows, u_rows:-y_rows]
    return R22, R32, np.linalg.svd(R32, compute_uv=False), np.concatenate([uh, yh])


def n4sid(u, y, n: int, block_rows: int, dt: float) -> SubspaceFit:
    """N4SID of order ``n`` with ``block_rows`` block rows (needs ``block_rows * p >= n``).

    Parameters
    ----------
    u : array (N, m)
    y : array (N, p)
    n : int
        Model order.
    block_rows : int
        Block rows of the Hankel matrices.
    dt : float
        Sample time [s] of the returned models.

    Examples
    --------
    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import excitation, modal_table, n4sid, simulate
    >>> s = control.tf("s")
    >>> G = sum(g * (2 * np.pi * f) ** 2 / (s**2 + 0.04 * 2 * np.pi * f * s + (2 * np.pi * f) ** 2)
    ...         for f, g in ((50.0, 1.0), (120.0, 0.5)))
    >>> plant = control.c2d(control.ss(G), 1e-3)
    >>> u = excitation("white", 2000, fs=1000.0, seed=1)
    >>> fit = n4sid(u, simulate(plant, u), n=4, block_rows=10, dt=1e-3)
    >>> print(np.round(modal_table(fit.with_d).frequencies_hz, 2))
    [ 50. 120.]
    """
    u = as_2d(u, "u", finite=True)
    y = as_2d(y, "y", finite=True)
    p = y.shape[1]
    if block_rows * p < n:
        raise IdentificationError(f"N4SID with {block_rows} block rows and {p} outputs "
                                  f"gives at most order {block_rows * p}, not {n}")
    if y.shape[0] < 2 * block_rows + 2:
        raise DataError(f"N4SID with {block_rows} block rows needs at least "
                        f"{2 * block_rows + 2} samples, got {y.shape[0]}")
    R22, R32, sv, uy = po_moesp(u, y, block_rows)
    W = _times_pinv(R32, R22)
    obs = W @ uy
    x = _leading_state(W, uy, obs, n)[:, :-1]
    yl = y[block_rows:].T[:, :-1]
    ul = u[block_rows:].T[:, :-1]
    xk, xk1 = x[:, :-1], x[:, 1:]
    XU = np.vstack([xk, ul])
    AB = np.linalg.lstsq(XU.T, xk1.T, rcond=None)[0].T
    CD = np.linalg.lstsq(XU.T, yl.T, rcond=None)[0].T
    C0 = np.linalg.lstsq(xk.T, yl.T, rcond=None)[0].T
    return SubspaceFit(AB[:, :n], AB[:, n:], CD[:, :n], CD[:, n:], C0, dt, block_rows, sv)


def _times_pinv(M: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``M pinv(R)`` for the lower-triangular block ``R`` of :func:`po_moesp`'s factor.

    By a triangular solve (``R^T W^T = M^T``) when ``R`` is well conditioned (LAPACK's
    estimate of its reciprocal condition number above ``1e-10``): the same product to
    rounding (measured: 4e-10 relative at most on the four measured sets, whose ``R``
    has a reciprocal condition number of 5e-10 to 8e-5), where the pseudo-inverse's SVD
    was a sixth to a third of a run's time on the small sets (40 x 40 to 120 x 120); else
    the pseudo-inverse (a rank-deficient ``R``, e.g. noise-free data, which only it
    truncates: above that estimate its default cut-off, ``1e-15`` of the largest
    singular value, truncates nothing)."""
    if R.size and np.all(np.isfinite(R)):
        rcond, info = scipy.linalg.lapack.dtrcon(R, norm="1", uplo="L", diag="N")
        if info == 0 and rcond > 1e-10:
            return scipy.linalg.solve_triangular(R, M.T, trans="T", lower=True,
                                                 check_finite=False).T
    return M @ np.linalg.pinv(R)


def _leading_state(W, uy, obs, n):
    """``sqrt(s) V^T`` of the ``n`` leading singular triplets of ``obs = W uy`` (a short,
    wide matrix: (p i) x N).

    From the eigenvectors of the small Gram ``obs obs^T = W (uy uy^T) W^T`` instead of a
    thin SVD of ``obs``: the same triplets (up to each state's sign, which no model
    depends on) at a fifth of the cost on the subframe record (40 against 8 ms at 30 block
    rows; ``identify`` runs several). The Gram's eigenvalues carry an absolute error of
    about ``eps s_1^2``, so the thin SVD is kept when the ``n``-th singular value is under
    ``1e-6 s_1``.
    """
    G = W @ (uy @ uy.T) @ W.T
    lam, U = np.linalg.eigh(0.5 * (G + G.T))
    lam, U = lam[::-1][:n], U[:, ::-1][:, :n]
    if lam.size and lam[-1] > 1e-12 * lam[0] > 0:
        return (U.T @ obs) / np.sqrt(np.sqrt(lam))[:, None]
    _, s, vh = np.linalg.svd(obs, full_matrices=False)
    return np.sqrt(s[:n])[:, None] * vh[:n]


def _stabilised(model: control.StateSpace) -> control.StateSpace:
    return model if _stable(model.A) else stabilise(model).model


def _stable(A) -> bool:
    return bool(np.max(np.abs(np.linalg.eigvals(np.asarray(A, float))), initial=0) < 1)


def output_error_fit(sys, u, y, direct: bool = False, d_std: bool = True):
    """``B`` (and ``D``) and x0 by output-error least squares with ``A, C`` of ``sys`` fixed.

    Linear in the unknowns: in modal coordinates every regressor is a one-pole filter of an
    input (:func:`scipy.signal.lfilter`). Rows are scaled per output channel so that every
    channel counts alike.

    Parameters
    ----------
    sys : control.StateSpace
        Discrete, stable model; its ``A`` must be diagonalisable (identified models
        generically are).
    u : array (N, m)
    y : array (N, p)
    direct : bool
        Estimate ``D`` too (else ``D = 0``).
    d_std : bool
        With ``direct``, also the standard errors of ``D`` (else None: a prior's sweep
        does not use them, and they cost one more Gram matrix).

    Returns
    -------
    model : control.StateSpace
        ``(A, B_new, C, D_new)``.
    y_sim : ndarray (N, p)
        Its response to ``u`` from x0 = 0 (without the fitted initial state).
    D_std : ndarray (p, m) or None
        Standard errors of ``D`` from the least-squares residual (white-residual
        assumption), when ``direct`` and ``d_std``.
    """
    u = as_2d(u, "u")
    y = as_2d(y, "y")
    A, C = np.asarray(sys.A, float), np.asarray(sys.C, float)
    n, m, p = A.shape[0], u.shape[1], y.shape[1]
    if not _stable(A):
        # Output error over a long record is meaningless for an unstable A.
        raise IdentificationError("an output-error refit needs a stable model")
    # real modal parameters (B = P b, x0 = P x0_m): the same column space as state
    # coordinates at a fraction of the regressors' cost (plid._linalg.real_modal_regressors);
    # rows weighted per channel as they are built
    w = 1.0 / np.sqrt(np.mean(y ** 2, axis=0))
    R, P = real_modal_regressors(A, C, u, x0=True, direct=direct, weights=w)
    Rm = R.reshape(-1, R.shape[2])
    theta = lstsq(Rm, (y * w).ravel())
    B = P @ theta[: n * m].reshape(m, n).T
    y_sim = R[:, :, :n * m] @ theta[:n * m]
    D = np.zeros((p, m))
    D_std = None
    if direct:
        D = theta[n * m + n:].reshape(p, m)
        y_sim += R[:, :, n * m + n:] @ theta[n * m + n:]
    if direct and d_std:
        res = Rm @ theta - (y * w).ravel()
        dof = max(Rm.shape[0] - Rm.shape[1], 1)
        s2 = float(res @ res) / dof
        # D's block of the covariance does not depend on the (invertible) change of the
        # other parameters' coordinates
        cov = s2 * np.linalg.pinv(Rm.T @ Rm)
        D_std = np.sqrt(np.clip(np.diag(cov)[n * m + n:], 0, None)).reshape(p, m) / w[:, None]
    y_sim /= w
    model = control.ss(A, B, C, D, sys.dt)
    return model, y_sim, D_std


def refit_input_matrix(sys, u, y) -> control.StateSpace:
    """``B`` (and x0) by output-error least squares with ``A, C`` of ``sys`` fixed, D = 0
    (:func:`output_error_fit` without the direct term).

    Parameters
    ----------
    sys : control.StateSpace
        Discrete model; its ``A`` must be diagonalisable (identified models generically are).
    u : array (N, m)
    y : array (N, p)

    Returns
    -------
    control.StateSpace
        ``(A, B_new, C, 0)``.
    """
    return output_error_fit(sys, u, y, direct=False)[0]


def direct_term_test(sys, u, y, folds: int = 2, margin: float = 0.05) -> dict:
    """Does the identification record call for a direct term ``D``? Decided on the data alone.

    With ``A, C`` of ``sys`` fixed, ``B, x0`` (without D) and ``B, D, x0`` (with D) are fitted
    by output error on all but one of ``folds`` contiguous segments and scored on the
    held-out one (its own initial state fitted there: the state at a segment start is not
    known), for every segment in turn. The in-sample fit always improves with more
    parameters; the held-out one improves only where the data carry a feed-through (an
    accelerometer's response to a force input, say). ``D`` is chosen when the held-out
    normalised error power falls by more than ``margin`` (relative).

    Returns
    -------
    dict
        ``{"direct": bool, "held_out_nmse": {"without": float, "with": float},
        "margin": margin, "folds": folds}``.
    """
    u = as_2d(u, "u")
    y = as_2d(y, "y")
    A, C = np.asarray(sys.A, float), np.asarray(sys.C, float)
    n, m, p = A.shape[0], u.shape[1], y.shape[1]
    edges = np.linspace(0, u.shape[0], folds + 1).astype(int)
    w = 1.0 / np.sqrt(np.mean(y ** 2, axis=0))
    # real modal parameters: only the held-out predictions are used, which do not depend on
    # the parameters' coordinates; rows weighted per channel as they are built
    regs = [real_modal_regressors(A, C, u[a:b], x0=True, direct=True, weights=w)[0]
            for a, b in zip(edges[:-1], edges[1:])]
    yw = [(y[a:b] * w).ravel() for a, b in zip(edges[:-1], edges[1:])]
    nb, nd = n * m, p * m
    score = {"without": 0.0, "with": 0.0}
    for k in range(folds):
        train = [j for j in range(folds) if j != k]
        for label, use_d in (("without", False), ("with", True)):
            # B (and D) shared by the training segments, one x0 per segment
            cols = nb + n * len(train) + (nd if use_d else 0)
            if len(train) == 1:     # the segment's own columns are [B, x0, D] already
                M = regs[train[0]][:, :, :cols].reshape(-1, cols)
            else:
                rows = []
                for t_i, j in enumerate(train):
                    Rj = regs[j]
                    x0 = np.zeros((Rj.shape[0], p, n * len(train)))
                    x0[:, :, t_i * n:(t_i + 1) * n] = Rj[:, :, nb:nb + n]
                    parts = [Rj[:, :, :nb], x0] + ([Rj[:, :, nb + n:]] if use_d else [])
                    rows.append(np.concatenate(parts, axis=2).reshape(-1, cols))
                M = np.vstack(rows)
            th = lstsq(M, np.concatenate([yw[j] for j in train]))
            b = th[:nb]
            d = th[nb + n * len(train):] if use_d else np.zeros(nd)
            Rk = regs[k]
            pred = Rk[:, :, :nb] @ b + Rk[:, :, nb + n:] @ d        # weighted units
            # the held-out segment's own initial state
            X0 = Rk[:, :, nb:nb + n].reshape(-1, n)
            r = yw[k] - pred.ravel()
            r = (r - X0 @ lstsq(X0, r)).reshape(-1, p) / w
            yk = y[edges[k]:edges[k + 1]]
            score[label] += float(np.mean(np.mean(r ** 2, 0) / np.mean(yk ** 2, 0))) / folds
    direct = score["with"] < (1.0 - margin) * score["without"]
    return {"direct": bool(direct), "held_out_nmse": score, "margin": margin, "folds": folds}


#: N4SID block rows the priors try by default (:func:`default_block_rows`).
DEFAULT_BLOCK_ROWS = (20, 30, 40, 60, 80)


def default_block_rows(n_samples: int, n: int, m: int, p: int) -> list[int]:
    """Block rows a prior tries for an order-``n`` model of ``m`` inputs and ``p`` outputs
    from ``n_samples`` samples: :data:`DEFAULT_BLOCK_ROWS`, at least ``n / p + 1``, those
    whose Hankel matrices have more columns than rows; increasing.

    N4SID accuracy on lightly damped plants depends strongly on the block rows (case (b) of
    the benchmark: 2.7 dB at 30, 0.12 dB at 40, 0.018 dB at 80), so several are tried.
    Raises IdentificationError when the record is too short for any.
    """
    lo = -(-n // p) + 1
    cand = {max(lo, i) for i in DEFAULT_BLOCK_ROWS}
    rows = sorted(i for i in cand if n_samples - 2 * i >= 2 * i * (m + p))
    if not rows:
        raise IdentificationError(
            f"{n_samples} samples are too few for a subspace estimate of order {n} "
            f"(at least {2 * lo * (m + p + 1)} needed); identify from scratch instead")
    return rows


def cached_n4sid(u, y, n: int, block_rows: int, dt: float,
                 fits: dict | None) -> SubspaceFit:
    """:func:`n4sid`, or its run at ``block_rows`` already in ``fits`` (filled when given).

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
    n : int
        Order.
    block_rows : int
        Block rows.
    dt : float
        Sample time [s].
    fits : dict or None
        Runs of :func:`n4sid` on these ``u, y`` at order ``n``, by block rows.

    Returns
    -------
    SubspaceFit
    """
    if fits is None:
        return n4sid(u, y, n, block_rows, dt)
    if block_rows not in fits:
        fits[block_rows] = n4sid(u, y, n, block_rows, dt)
    return fits[block_rows]


def subspace_prior(u, y, n: int, dt: float, block_rows=None, refit: bool = True,
                   patience: int | None = 1, fits: dict | None = None):
    """A strictly proper order-``n`` prior from the data alone.

    Runs :func:`n4sid` for each candidate block-row count (default 20, 30, 40, 60 and 80,
    at least ``n / p + 1``), takes the D = 0 model, unstable poles reflected
    (:func:`trussid.plid.stability.stabilise`), optionally :func:`refit_input_matrix`, and keeps
    the candidate with the smallest output error on the data themselves (no truth used).
    The default candidates are tried in increasing order and the sweep stops at the first
    one that does not improve on the best so far (``patience``): the cost of a candidate
    grows with the square of its block rows (80 block rows cost 7x what 20 do on the
    8523-sample subframe record), and the score rarely recovers after a drop; it also stops
    after a candidate that gained under :data:`MIN_GAIN_DB` (:func:`sweep_block_rows`).

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
    n : int
        Order.
    dt : float
        Sample time [s].
    block_rows : int or sequence of int, optional
        Block rows to try (default above).
    refit : bool
        Refit ``B`` by output error.
    patience : int or None
        Candidates without improvement before the default sweep stops (None: all).
    fits : dict, optional
        :func:`n4sid` runs by block rows, read and filled here: a caller that also needs
        N4SID's model with D on the same data (:func:`trussid.plid.feedthrough.direct_prior`)
        passes the same dict, so each block-row count is factorised once (the QR is most
        of a run's cost).

    Returns
    -------
    model : control.StateSpace
    choice : SubspaceChoice
        The block rows kept and every candidate's output-error ratio [dB].
    """

    return sweep_block_rows(u, y, n, dt, block_rows, direct=False, refit=refit,
                            patience=patience, fits=fits)


#: A default block-row sweep stops after a candidate that improved the best output-error
#: ratio by less than this [dB] (:func:`sweep_block_rows`).
MIN_GAIN_DB = 0.05


def sweep_block_rows(u, y, n: int, dt: float, block_rows=None, *, direct: bool = False,
                     refit: bool = True, patience: int | None = 1, fits: dict | None = None,
                     min_gain_db: float | None = MIN_GAIN_DB):
    """The block-row sweep of :func:`subspace_prior` (``direct=False``: N4SID's model with
    ``D = 0``, ``B`` refitted) and of :func:`trussid.plid.feedthrough.direct_prior`
    (``direct=True``: N4SID's model with ``D``, ``B, D`` refitted): each candidate's
    unstable poles reflected in, scored by its output-error ratio [dB] on the data, the best
    kept; default block rows swept in increasing order and stopped after ``patience``
    candidates without improvement, or after one that improved by less than
    ``min_gain_db``. A candidate already scored on the same run (in ``fits``) is not
    refitted.

    Why the second stop: a run's QR costs the square of its block rows, and on the
    subframe record at order 36 the sweep went on to 60 and 80 block rows for 0.006 and
    0.001 dB (with D: 14.213, 14.302, 14.314, 14.320, 14.321 dB at 20, 30, 40, 60, 80), two
    thirds of ``identify``'s subspace time; where a larger count mattered (order 24 there:
    8.9 dB at 40, 12.4 at 60) the step before it had gained 0.1 dB.

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
    n : int
        Order.
    dt : float
        Sample time [s].
    block_rows : int or sequence of int, optional
        Block rows to try, all of them (default :func:`default_block_rows`, swept).
    direct : bool
        Candidates with a direct term.
    refit : bool
        Refit ``B`` (and ``D``) by output error (else each candidate is scored as it is).
    patience : int or None
        Candidates without improvement before the default sweep stops (None: all, and no
        stop on a small gain either).
    fits : dict, optional
        :func:`n4sid` runs on these data by block rows, read and filled here.
    min_gain_db : float or None
        The default sweep stops after a candidate that improved on the best by less than
        this [dB] (None: no such stop).

    Returns
    -------
    model : control.StateSpace
    choice : SubspaceChoice
    """
    u = as_2d(u, "u")
    y = as_2d(y, "y")
    p = y.shape[1]
    m = u.shape[1]
    given = block_rows is not None
    if block_rows is None:
        block_rows = default_block_rows(u.shape[0], n, m, p)
    best, scores, worse = None, {}, 0
    sweep = not given and patience is not None
    stopped = "last candidate" if not given else None
    for i in np.atleast_1d(block_rows):
        if sweep and worse >= patience:
            stopped = f"{worse} candidate(s) without improvement"
            break
        fit = cached_n4sid(u, y, n, int(i), dt, fits)
        if (direct, refit) not in fit.scored:
            fit.scored[direct, refit] = _scored_candidate(fit, u, y, direct, refit)
        score, model = fit.scored[direct, refit]
        scores[int(i)] = score
        if best is None or score > best[0]:
            gain = None if best is None else score - best[0]
            best, worse = (score, model, int(i)), 0
            if sweep and min_gain_db is not None and gain is not None and gain < min_gain_db:
                stopped = f"improved by {gain:.3f} dB, under {min_gain_db:g} dB"
                break
        else:
            worse += 1
    return best[1], SubspaceChoice(block_rows=best[2], candidates=scores, stopped=stopped)


def _scored_candidate(fit: SubspaceFit, u, y, direct: bool, refit: bool):
    """``(output-error ratio [dB], model)`` of one run's candidate (see
    :func:`sweep_block_rows`)."""
    model = fit.stable_with_d if direct else fit.stable_zero_d
    if refit:
        model, ysim, _ = output_error_fit(model, u, y, direct=direct, d_std=False)
    else:
        ysim = simulate(model, u)
    e = y - ysim
    return float(-10 * np.log10(np.mean(np.mean(e ** 2, 0) / np.mean(y ** 2, 0)))), model
