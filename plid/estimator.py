"""The PLID estimator: batch ``fit`` and streaming ``update`` over one recursion.

Typical use::

    from trussid.plid.estimator import PLID
    res = PLID(order=12, dt=1 / 1600, R=1e-6).fit(u, y)      # u (N, m), y (N, p)
    res.model        # identified discrete control.StateSpace, original units, D = 0
    res.K            # steady-state one-step predictor gain
    res.innovations  # (N, p) one-step prediction errors y - C x^-

Streaming (identical numbers to ``fit`` on the same samples, bit for bit)::

    est = PLID(order=12, dt=1 / 1600, u_scale=su, y_scale=sy)
    for u_k, y_k in samples:
        e_k = est.update(u_k, y_k)
    res = est.result()

Units and scaling. Inputs and outputs are scaled to unit RMS inside (``u / u_scale``,
``y / y_scale``; by default the RMS of the data given to ``fit``), because raw structural
data is badly scaled. **All noise covariances and prior variances (Q, R, N, Q_theta,
prior_theta_var, prior_x_var) are given in these scaled units**: ``R = 1e-6`` means an
output noise 60 dB below the output's RMS. Everything in :class:`PLIDResult` is in the
original units.

Defaults:

- ``Q = 1e-6``: from the prototype runs in ``docs/plid.md``: a small state noise is not
  optional at higher orders (it absorbs model error while the parameters are far off;
  with ``Q = 0`` the direct form diverged at 24 states, 60-80 dB). On noiseless data of a
  model of the right order, ``Q = 0`` converges to round-off (see the tests).
- ``R = 1e-4``: assumes 40 dB output signal-to-noise; it is a guess, set it from your
  sensor noise when known (the tests use the true noise level).
- ``N = 0`` (noise-free inputs), ``Q_theta = 0`` (time-invariant plant).
- ``prior_theta_var = 1e4``, ``prior_x_var = 1e2``: theta_0 = 0, x_0 = 0 with large
  covariances (shift-form coefficients of lightly damped, oversampled modes reach ~100 at
  24 states). A prior variance of the size of the coefficients conditions the direct form
  better (its round-off against the square-root form drops from ~1e-8 to ~1e-11).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import control
import numpy as np
import scipy.linalg
from tqdm.auto import tqdm

from trussid._util.threads import blas_threads as _limit_blas
from trussid.plid.canonical import ObserverBasis, check_order, from_statespace, split_theta
from trussid.plid._validate import as_2d
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.recursion_common import Problem
from trussid.plid.recursion_direct import direct_covariance, direct_init
from trussid.plid.recursion_kernel import history_rows, run_direct, run_sqrt
from trussid.plid.recursion_sqrt import sqrt_covariance, sqrt_init

__all__ = ["PLID", "PLIDResult", "PLIDWarning"]

_FORMS = ("sqrt", "direct")


class PLIDWarning(UserWarning):
    """The recursion lost its footing (non-finite estimate or covariance not positive definite)."""


@dataclass
class PLIDResult:
    """What a PLID run produced; everything in original (unscaled) units.

    Attributes
    ----------
    model : control.StateSpace
        Identified discrete model ``(A, B, C, D = 0, dt)``. For the shift basis it is in
        observer form (``A = S + Abar C``, ``C`` selecting each block's first state).
    K : ndarray (n, p) or None
        Steady-state one-step predictor gain: ``x+ = A x + B u + K (y - C x)``, from the
        discrete Riccati equation with ``Q + B N B^T`` and ``R``; ``K_source`` says
        ``"dare"``, or ``"final"`` (the recursion's last gain) when the DARE had no solution.
    theta : ndarray (q,)
        ``[vec(Abar); vec(B)]`` of ``model`` (column-major).
    theta_cov : ndarray (q, q)
        Posterior covariance of ``theta``.
    Q, R, N : ndarray
        State, output and input noise covariances used (original units).
    Q_theta : ndarray (q,)
        Diagonal of the parameter drift covariance used (original units).
    u_scale, y_scale : ndarray
        Per-channel scales used inside (data / scale has unit RMS by default).
    innovations : ndarray (n_samples, p)
        One-step prediction errors ``y_k - C x_{k|k-1}``.
    theta_history : ndarray (k, q)
        ``theta`` after the samples ``history_index`` (decimated).
    history_index : ndarray (k,)
        Sample counts at which ``theta_history`` was taken.
    x : ndarray (n,)
        Final one-step state prediction ``x_{N|N-1}`` (state of ``model``).
    form : str
        ``"sqrt"`` or ``"direct"``.
    n_samples : int
        Samples processed.
    finite : bool
        Estimate and covariance are finite.
    cov_min_eig : float
        Smallest eigenvalue of the (scaled) joint covariance of ``[theta; x]``: positive
        when it is positive definite.
    first_negative_variance : int or None
        Direct form: first sample after which a variance became non-positive.
    basis : ObserverBasis
    """

    model: control.StateSpace
    K: np.ndarray | None
    K_source: str
    theta: np.ndarray
    theta_cov: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    N: np.ndarray
    Q_theta: np.ndarray
    u_scale: np.ndarray
    y_scale: np.ndarray
    innovations: np.ndarray
    theta_history: np.ndarray
    history_index: np.ndarray
    x: np.ndarray
    form: str
    n_samples: int
    finite: bool
    cov_min_eig: float
    first_negative_variance: int | None
    basis: ObserverBasis = field(repr=False)


def _check_finite(arr: np.ndarray, name: str) -> None:
    bad = ~np.isfinite(arr)
    if bad.any():
        k, j = np.argwhere(bad)[0]
        raise DataError(f"{name} column {j} has a non-finite value ({arr[k, j]}) at sample {k}")


def _scale(value, data: np.ndarray | None, name: str, width: int) -> np.ndarray:
    if value is None:
        if data is None:
            raise IdentificationError(
                f"streaming update needs fixed scales: pass {name} (e.g. the RMS of a "
                "calibration record) to PLID, or call fit first"
            )
        s = np.sqrt(np.mean(data * data, axis=0))
        for j, v in enumerate(s):
            if not v > 0:
                raise DataError(f"{name[0]} column {j} is identically zero: nothing to scale by")
        return s
    s = np.broadcast_to(np.asarray(value, dtype=float), (width,)).copy()
    if not np.all(np.isfinite(s)) or np.any(s <= 0):
        raise IdentificationError(f"{name} must be positive and finite, got {value!r}")
    return s


class PLID:
    """Pseudo-linear identification of a discrete, strictly proper MIMO model.

    Parameters
    ----------
    order : int
        Number of states n. With the default shift basis a multiple of the number of
        outputs (uniform observability index), else :class:`IdentificationError`
        suggesting the nearest valid orders; a given ``basis`` fixes the structure (any
        order from the number of outputs up with :func:`plid.bases.basis_for`).
    form : {"sqrt", "direct"}
        Square-root (default; keeps the covariance positive definite on long, low-noise
        runs) or direct covariance form.
    dt : float
        Sample time of the returned model [s].
    Q : float, (n,) or (n, n)
        State-noise covariance (scaled units). Default 1e-6.
    R : float, (p,) or (p, p)
        Output-noise covariance (scaled units), positive definite. Default 1e-4.
    N : float, (m,) or (m, m)
        Input-noise covariance (scaled units). Default 0.
    Q_theta : float or (q,)
        Parameter random-walk variance per sample (scaled units). Default 0. In the
        square-root form a non-zero drift costs an O(q^3) re-triangularisation per sample.
    prior : control.StateSpace, optional
        A model (original units, ``order`` states, D = 0) whose observer form starts theta.
    prior_theta_var : float, (q,) or (q, q)
        Prior covariance of theta (scaled units). Default 1e4.
    prior_x_var : float or (n,)
        Prior variance of the initial state (scaled units). Default 1e2.
    basis : ObserverBasis, optional
        Fixed ``(F, C)``; default the block shift.
    u_scale, y_scale : float or array, optional
        Fixed channel scales. Default: the RMS of the data given to ``fit``. Streaming
        ``update`` without a preceding ``fit`` needs them.
    history_every : int
        Keep theta every this many samples (0: none). Default 10.
    passes : int
        Batch passes over the data in ``fit``; each later pass restarts (x_0 = 0) from the
        previous pass's theta, with its posterior covariance times ``pass_inflation`` and
        Q, Q_theta multiplied by ``pass_decay``. Default 1.
    pass_decay : float
        See ``passes``. Default 0.1.
    pass_inflation : float
        See ``passes``. Default 100.
    progress : bool or None
        tqdm progress bar in ``fit``: None shows it when a pass is expected to take more
        than a few seconds (samples x parameters^2 above :attr:`PROGRESS_WORK`).
    blas_threads : int or None
        OpenBLAS threads while the recursion runs (restored afterwards). Default 1: the
        per-sample products are small and threads only add synchronisation (20 times
        slower on a loaded 2-core machine). None leaves the setting alone.
    compiled : bool or None
        Run the recursion in the compiled kernels of :mod:`trussid.plid.recursion_kernel`
        (None, the default: when numba is installed) or in the reference numpy steps
        (False). Both give the same numbers to rounding (the tests check 1e-9); ``fit``
        and ``update`` of one estimator always take the same path, so that streaming
        stays bit for bit equal to ``fit``. The kernels compile on their first use in a
        fresh environment (a few CPU seconds, cached on disk afterwards).

    Examples
    --------
    One PLID pass over a noise-free record of a two-mode plant (50 and 120 Hz, 2 % damping):

    >>> import warnings
    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import PLID, excitation, modal_table, simulate
    >>> s = control.tf("s")
    >>> G = sum(g * (2 * np.pi * f) ** 2 / (s**2 + 0.04 * 2 * np.pi * f * s + (2 * np.pi * f) ** 2)
    ...         for f, g in ((50.0, 1.0), (120.0, 0.5)))
    >>> plant = control.c2d(control.ss(G), 1e-3)
    >>> u = excitation("white", 2000, fs=1000.0, seed=1)
    >>> result = PLID(4, dt=1e-3, progress=False).fit(u, simulate(plant, u))
    >>> result.finite, result.n_samples
    (True, 2000)
    >>> print(np.round(modal_table(result.model).frequencies_hz, 2))
    [ 50. 120.]
    """

    def __init__(self, order: int, *, form: str = "sqrt", dt: float = 1.0, Q=1e-6, R=1e-4,
                 N=0.0, Q_theta=0.0, prior=None, prior_theta_var=1e4, prior_x_var=1e2,
                 basis: ObserverBasis | None = None, u_scale=None, y_scale=None,
                 history_every: int = 10, passes: int = 1, pass_decay: float = 0.1,
                 pass_inflation: float = 100.0,
                 progress: bool | None = None, blas_threads: int | None = 1,
                 compiled: bool | None = None):
        if form not in _FORMS:
            raise IdentificationError(f"form must be one of {_FORMS}, got {form!r}")
        if int(order) != order or order < 1:
            raise IdentificationError(f"order must be a positive integer, got {order!r}")
        if not dt > 0:
            raise IdentificationError(f"dt must be positive, got {dt!r}")
        if int(passes) != passes or passes < 1:
            raise IdentificationError(f"passes must be a positive integer, got {passes!r}")
        if int(history_every) != history_every or history_every < 0:
            raise IdentificationError(f"history_every must be >= 0, got {history_every!r}")
        if basis is not None and basis.n != order:
            raise IdentificationError(f"basis has {basis.n} states but order is {order}")
        self.order = int(order)
        self.form = form
        self.dt = float(dt)
        self.Q, self.R, self.N, self.Q_theta = Q, R, N, Q_theta
        self.prior = prior
        self.prior_theta_var = prior_theta_var
        self.prior_x_var = prior_x_var
        self.basis = basis
        self.u_scale, self.y_scale = u_scale, y_scale
        self.history_every = int(history_every)
        self.passes = int(passes)
        self.pass_decay = float(pass_decay)
        self.pass_inflation = float(pass_inflation)
        self.progress = progress
        self.blas_threads = blas_threads
        self.compiled = compiled
        self.reset()

    # ------------------------------------------------------------------ set-up
    def reset(self) -> None:
        """Forget all data: the next ``fit``/``update`` starts from the prior."""
        self._pb = None
        self._st = None
        self._su = self._sy = None
        self._innov = []
        self._hist = []
        self._hist_k = []
        self._k = 0
        self._first_bad = None

    def _check_outputs(self, p: int) -> None:
        """The default shift basis needs an order that is a multiple of ``p``; a given
        basis (any order, e.g. :func:`plid.bases.basis_for`) must have ``p`` outputs."""
        if self.basis is None:
            check_order(self.order, p)
        elif self.basis.p != p:
            raise IdentificationError(f"basis has {self.basis.p} outputs but the data has {p}")

    def _problem(self, m: int, p: int, decay: float = 1.0) -> Problem:
        basis = self.basis if self.basis is not None else ObserverBasis.shift(
            check_order(self.order, p) * p, p)
        if basis.p != p:
            raise IdentificationError(f"basis has {basis.p} outputs but the data has {p}")
        qt = self.Q_theta
        return Problem(basis, m, np.asarray(self.Q, dtype=float) * decay, self.R, self.N,
                       None if qt is None else np.asarray(qt, dtype=float) * decay)

    def _prior(self, pb: Problem, theta0=None, theta_cov0=None):
        n, q = pb.n, pb.q
        if theta0 is None:
            if self.prior is not None:
                theta0 = self._prior_theta(pb)
            else:
                theta0 = np.zeros(q)
        pt = np.asarray(self.prior_theta_var if theta_cov0 is None else theta_cov0, dtype=float)
        Pt = np.eye(q) * pt if pt.ndim == 0 else (np.diag(pt) if pt.ndim == 1 else pt)
        px = np.asarray(self.prior_x_var, dtype=float)
        Px = np.eye(n) * px if px.ndim == 0 else np.diag(px)
        if Pt.shape != (q, q) or Px.shape != (n, n):
            raise IdentificationError(
                f"prior_theta_var must give a {q} x {q} and prior_x_var an {n} x {n} covariance"
            )
        P0 = scipy.linalg.block_diag(Pt, Px)
        z0 = np.concatenate([theta0, np.zeros(n)])
        return z0, P0

    def _prior_theta(self, pb: Problem) -> np.ndarray:
        sys = self.prior
        if not isinstance(sys, control.StateSpace):
            raise IdentificationError("prior must be a control.StateSpace")
        if sys.nstates != pb.n or sys.ninputs != pb.m or sys.noutputs != pb.p:
            raise IdentificationError(
                f"prior has (states, inputs, outputs) = ({sys.nstates}, {sys.ninputs}, "
                f"{sys.noutputs}); expected ({pb.n}, {pb.m}, {pb.p})"
            )
        A = np.asarray(sys.A, float)
        B = np.asarray(sys.B, float) * self._su[None, :]
        C = np.asarray(sys.C, float) / self._sy[:, None]
        theta, _ = from_statespace((A, B, C, np.asarray(sys.D, float)), pb.basis)
        return theta

    def _start(self, m: int, p: int, theta0=None, decay: float = 1.0, theta_cov0=None) -> None:
        pb = self._problem(m, p, decay)
        z0, P0 = self._prior(pb, theta0, theta_cov0)
        self._pb = pb
        self._st = (sqrt_init if self.form == "sqrt" else direct_init)(pb, z0, P0)
        self._innov = []
        self._hist, self._hist_k = [], []
        self._k = 0
        self._first_bad = None

    # ------------------------------------------------------------------ running
    def fit(self, u, y) -> PLIDResult:
        """Identify from a batch of samples, starting afresh from the prior.

        Parameters
        ----------
        u : array (N, m) or (N,)
            Measured inputs.
        y : array (N, p) or (N,)
            Measured outputs.

        Returns
        -------
        PLIDResult
            After the last pass. With ``passes=1`` the same as ``update`` on each sample.
        """
        u = as_2d(u, "u")
        y = as_2d(y, "y")
        if u.shape[0] != y.shape[0]:
            raise DataError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
        _check_finite(u, "u")
        _check_finite(y, "y")
        m, p = u.shape[1], y.shape[1]
        self._check_outputs(p)
        q = self.order * (m + p)
        if u.shape[0] < q:
            raise DataError(f"{u.shape[0]} samples are fewer than the {q} parameters of an "
                            f"order-{self.order} model with {m} inputs and {p} outputs")
        self.reset()
        self._su = _scale(self.u_scale, u, "u_scale", m)
        self._sy = _scale(self.y_scale, y, "y_scale", p)
        us = u / self._su
        ys = y / self._sy
        theta0 = cov0 = None
        for k in range(self.passes):
            self._start(m, p, theta0, self.pass_decay ** k, cov0)
            self._run(us, ys)
            q = self._pb.q
            theta0 = self._st.z[:q].copy()
            cov0 = self.covariance()[:q, :q] * self.pass_inflation
        return self.result()

    def _run(self, us: np.ndarray, ys: np.ndarray) -> None:
        n_s = us.shape[0]
        show = self.progress if self.progress is not None else self._slow(n_s)
        E = np.empty((n_s, ys.shape[1]))
        chunk = 2000
        bar = tqdm(total=n_s, disable=not show, unit="sample", desc=f"PLID {self.form}")
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"), \
                _limit_blas(self.blas_threads), bar:
            for k0 in range(0, n_s, chunk):
                k1 = min(n_s, k0 + chunk)
                self._block(us[k0:k1], ys[k0:k1], E[k0:k1])
                bar.update(k1 - k0)
        self._innov.append(E)
    #: Samples x parameters^2 above which a pass takes more than about two seconds: the
    #: recursion updates a q x q covariance per sample; measured 2400 samples/s at q = 120
    #: (30-state SIMO, direct form) on the 2-core development machine, i.e. ~3.5e7 per s.
    PROGRESS_WORK = 7e7

    def _slow(self, n_s: int) -> bool:
        """True when a pass over ``n_s`` samples is expected to take more than a few seconds
        (then ``progress=None`` shows the bar)."""
        q = self._pb.q if self._pb is not None else self.order
        return n_s * float(q) ** 2 > self.PROGRESS_WORK

    def _block(self, us, ys, E) -> None:
        """Samples ``us[k], ys[k]`` (scaled) through the recursion; innovations into ``E``.

        A step whose covariance is already broken (NaN/inf, which only the direct form
        can reach) carries on in NaN, so that the result reports it (finite=False)
        instead of raising mid-run (:class:`~trussid.plid.recursion_kernel.KernelRun`).
        """
        pb, st = self._pb, self._st
        every = self.history_every
        hist = np.empty((history_rows(self._k, us.shape[0], every), pb.q))
        if self.form == "direct":
            run = run_direct(pb, st, us, ys, E, hist, every, self._k,
                             track=self._first_bad is None, use_kernel=self.compiled)
            if self._first_bad is None and run.first_bad >= 0:
                self._first_bad = self._k + run.first_bad + 1
        else:
            run_sqrt(pb, st, us, ys, E, hist, every, self._k, use_kernel=self.compiled)
        if every:
            first = (self._k // every + 1) * every
            self._hist.extend(hist)
            self._hist_k.extend(range(first, first + every * hist.shape[0], every))
        self._k += us.shape[0]

    def update(self, u_k, y_k) -> np.ndarray:
        """Process one sample (streaming) and return its innovation ``y_k - C x^-``.

        Continues from the current state (after ``fit``, or from the prior on the first
        call). Needs fixed ``u_scale`` and ``y_scale`` unless a ``fit`` set them.
        """
        u_k = np.atleast_1d(np.asarray(u_k, dtype=float))
        y_k = np.atleast_1d(np.asarray(y_k, dtype=float))
        if u_k.ndim != 1 or y_k.ndim != 1:
            raise DataError("update takes one sample: u_k (m,) and y_k (p,)")
        if not (np.all(np.isfinite(u_k)) and np.all(np.isfinite(y_k))):
            raise DataError(f"non-finite value in sample {self._k}")
        if self._st is None:
            self._check_outputs(y_k.size)
            self._su = _scale(self.u_scale, None, "u_scale", u_k.size)
            self._sy = _scale(self.y_scale, None, "y_scale", y_k.size)
            self._start(u_k.size, y_k.size)
        if u_k.size != self._pb.m or y_k.size != self._pb.p:
            raise DataError(f"sample {self._k} has {u_k.size} inputs and {y_k.size} outputs; "
                            f"expected {self._pb.m} and {self._pb.p}")
        e = np.empty((1, self._pb.p))
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"), \
                _limit_blas(self.blas_threads):
            self._block((u_k / self._su)[None, :], (y_k / self._sy)[None, :], e)
        self._innov.append(e)
        return e[0] * self._sy

    # ------------------------------------------------------------------ results
    def covariance(self) -> np.ndarray:
        """Current joint covariance of ``[theta; x]`` in scaled units (formed on request)."""
        if self._st is None:
            raise IdentificationError("no data processed yet")
        return (sqrt_covariance if self.form == "sqrt" else direct_covariance)(self._st)

    def result(self) -> PLIDResult:
        """The identified model and diagnostics so far (original units)."""
        if self._st is None:
            raise IdentificationError("no data processed yet")
        with _limit_blas(self.blas_threads):
            return self._result()

    def _result(self) -> PLIDResult:
        pb, st = self._pb, self._st
        n, p, m, q = pb.n, pb.p, pb.m, pb.q
        su, sy = self._su, self._sy
        basis = pb.basis
        # State scaling that keeps the basis: for the shift basis, scaling block i by
        # y_scale[i] commutes with S and restores the selector C in original units.
        if basis.name == "shift":
            t = np.repeat(sy, n // p)
        else:
            t = np.ones(n)
        z = st.z
        finite = bool(np.all(np.isfinite(z)))
        Pfull = self.covariance()
        finite = finite and bool(np.all(np.isfinite(Pfull)))
        if self.form == "sqrt" and finite:
            min_eig = float(scipy.linalg.svdvals(st.L).min() ** 2)
        elif finite:
            min_eig = float(np.linalg.eigvalsh(0.5 * (Pfull + Pfull.T)).min())
        else:
            min_eig = float("nan")
        Abar_s, B_s = split_theta(z[:q], n, p, m)
        A_s = basis.F + Abar_s @ basis.C
        dvec = np.concatenate([(t[:, None] / sy[None, :]).ravel(order="F"),
                               (t[:, None] / su[None, :]).ravel(order="F")])
        theta = z[:q] * dvec
        theta_cov = Pfull[:q, :q] * np.outer(dvec, dvec)
        A = (t[:, None] * A_s) / t[None, :]
        B = (t[:, None] * B_s) / su[None, :]
        C = (sy[:, None] * basis.C) / t[None, :]
        model = control.ss(A, B, C, np.zeros((p, m)), self.dt)
        Nm = pb.N if pb.N is not None else np.zeros((m, m))
        qt = pb.Q_theta if pb.Q_theta is not None else np.zeros(q)
        K, K_source = None, "none"
        if finite:
            K, K_source = self._predictor_gain(A_s, B_s, Pfull, z)
        if K is not None:
            K = (t[:, None] * K) / sy[None, :]
        innov = (np.concatenate(self._innov) if self._innov else np.empty((0, p))) * sy
        hist = (np.array(self._hist) * dvec) if self._hist else np.empty((0, q))
        if not finite or not min_eig > 0:
            warnings.warn(
                f"PLID ({self.form} form) after {self._k} samples: "
                + ("estimate or covariance is not finite" if not finite else
                   f"covariance is not positive definite (smallest eigenvalue {min_eig:.3g})")
                + ("; the square-root form avoids this" if self.form == "direct" else ""),
                PLIDWarning, stacklevel=4)
        return PLIDResult(
            model=model, K=K, K_source=K_source, theta=theta, theta_cov=theta_cov,
            Q=pb.Q * np.outer(t, t), R=pb.R * np.outer(sy, sy), N=Nm * np.outer(su, su),
            Q_theta=qt * dvec ** 2, u_scale=su.copy(), y_scale=sy.copy(),
            innovations=innov, theta_history=hist,
            history_index=np.array(self._hist_k, dtype=int), x=z[q:] * t,
            form=self.form, n_samples=self._k, finite=finite, cov_min_eig=min_eig,
            first_negative_variance=self._first_bad, basis=basis)

    def _predictor_gain(self, A_s, B_s, Pfull, z):
        pb = self._pb
        C, R = pb.basis.C, pb.R
        Qd = pb.Q + (B_s @ pb.N @ B_s.T if pb.N is not None else 0.0)
        try:
            with warnings.catch_warnings():
                # An ill-conditioned DARE warns and may fail; the fallback below handles it.
                warnings.simplefilter("ignore", RuntimeWarning)
                X = scipy.linalg.solve_discrete_are(A_s.T, C.T, Qd, R)
            K = A_s @ X @ C.T @ np.linalg.inv(C @ X @ C.T + R)
            if np.all(np.isfinite(K)):
                return K, "dare"
        except (np.linalg.LinAlgError, ValueError):
            pass
        # No stabilising DARE solution (e.g. Q = 0 with unobservable unstable modes): use
        # the recursion's own last gain on the state block.
        Pxx = Pfull[pb.q:, pb.q:]
        K = A_s @ Pxx @ C.T @ np.linalg.inv(C @ Pxx @ C.T + R)
        return K, "final"
