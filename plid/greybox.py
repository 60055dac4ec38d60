"""Grey-box identification: fit named physical parameters of a model to data, honestly.

Two layers, so the same machinery serves time-domain fitting and FE model updating:

* :func:`fit_parameters` fits any residual function ``residual(p) -> 1-D array`` of a
  parameter dict (optionally with its analytic Jacobian), with bounds, fixed parameters,
  equality/inequality constraints and seeded multi-start, and returns a
  :class:`GreyboxReport` with estimates, Jacobian confidence intervals, an identifiability
  analysis naming the parameter combinations the data cannot determine, and the
  multi-start spread.
* :func:`fit_greybox` builds that residual from a continuous-time model
  ``model(p) -> control.StateSpace | control.TransferFunction`` simulated (ZOH or FOH, to
  match how the data were sampled) with any input, against measured outputs.

Positive parameters (lower bound >= 0 and positive initial value) are estimated in
``ln p`` by default: their scale then drops out of the optimiser and of the
identifiability analysis, and a direction ``v`` in log space that the data cannot see is
the power product ``prod p_i ** v_i`` -- which is how undetermined combinations are named
(e.g. ``R*k``). Other parameters are estimated as ``p / scale`` with ``scale`` the initial
magnitude.

Constraints are callables of the parameter dict: ``Constraint(fun, "eq")`` means
``fun(p) == 0``, ``Constraint(fun, "ineq")`` means ``fun(p) >= 0`` (scipy's convention).
Write them in a scaled form (e.g. ``T(p) / T_hat - 1``): feasibility is judged with the
absolute tolerance ``ctol``.

Modules: the result and constraint types are :mod:`trussid.plid.greybox_report`, the generic
fit :mod:`trussid.plid.parameter_fit` (its parameter space the private
:mod:`trussid.plid._parameter_space`); this module simulates continuous-time models against
data and holds the time-domain fit, and re-exports the others' public names.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence

import control
import numpy as np
import scipy.signal

from trussid.plid._parameter_space import build_space
from trussid.plid._validate import as_2d, check_time
from trussid.plid.errors import DataError
from trussid.plid.greybox_report import Combination, Constraint, GreyboxReport, StartResult
from trussid.plid.parameter_fit import fit_parameters

__all__ = [
    "Combination",
    "Constraint",
    "GreyboxReport",
    "StartResult",
    "fit_greybox",
    "fit_parameters",
    "simulate_continuous",
]


# --------------------------------------------------------------------------- time domain


def simulate_continuous(system, t, u, hold: str = "zoh", x0=None) -> np.ndarray:
    """Response of a continuous-time system to sampled input.

    (Named apart from :func:`trussid.plid.experiment.simulate`, which runs a discrete model
    through python-control: this one samples a continuous model with the input's hold, and
    for the low orders of grey-box models runs the recursion in C through
    ``scipy.signal.lfilter``, which the fit's hundreds of calls need.)

    Parameters
    ----------
    system : control.StateSpace or control.TransferFunction
        Continuous-time model (anything ``control.ss`` accepts).
    t : (N,) array
        Uniformly spaced sample times [s].
    u : (N,) or (N, m) array
        Input samples.
    hold : {"zoh", "foh"}
        How the input behaves between samples: held constant (a DAC, a square wave
        generator) or linearly interpolated (a sampled smooth signal).
    x0 : (n,) array, optional
        State at ``t[0]`` in the coordinates of ``control.ss(system)`` (default zero).
        With ``hold="foh"`` it is the state of the sampled system, which differs from the
        continuous state by a multiple of ``u[0]``.

    Returns
    -------
    (N, p) array
        Output samples.
    """
    if hold not in ("zoh", "foh"):
        raise DataError(f"hold must be 'zoh' or 'foh', got {hold!r}")
    dt = check_time(t)
    u = as_2d(u, "u", len(t), finite=True)
    try:
        sysc = control.ss(system)
    except Exception as exc:  # noqa: BLE001 - any failure here is the user's model
        raise DataError(f"model did not return a state-space or transfer function: {exc}") from None
    if sysc.isdtime(strict=True):
        raise DataError("model must be continuous-time (dt = 0)")
    if sysc.ninputs != u.shape[1]:
        raise DataError(f"model has {sysc.ninputs} input(s) but u has {u.shape[1]} column(s)")
    sysd = control.sample_system(sysc, dt, method=hold)
    a, b, c, d = (np.asarray(m, dtype=float) for m in (sysd.A, sysd.B, sysd.C, sysd.D))
    n = a.shape[0]
    if x0 is not None:
        x0 = np.asarray(x0, dtype=float).ravel()
        if x0.size != n:
            raise DataError(f"initial state has {x0.size} entries for {n} model state(s)")
    y = u @ d.T
    if n == 0:
        return y
    if n <= 8:
        # lfilter runs the recursion in C; a transfer function per input is well
        # conditioned for the low orders grey-box models have.
        y = np.zeros((u.shape[0], c.shape[0]))
        for j in range(u.shape[1]):
            num, den = scipy.signal.ss2tf(a, b, c, d, input=j)
            for i in range(c.shape[0]):
                y[:, i] += scipy.signal.lfilter(num[i], den, u[:, j])
        if x0 is not None and np.any(x0):
            # free response C A^k x0: the impulse response of (A, x0, C, 0), one step on
            num, den = scipy.signal.ss2tf(a, x0[:, None], c, np.zeros((c.shape[0], 1)))
            imp = np.zeros(u.shape[0] + 1)
            imp[0] = 1.0
            for i in range(c.shape[0]):
                y[:, i] += scipy.signal.lfilter(num[i], den, imp)[1:]
        return y
    _, yd, _ = scipy.signal.dlsim((a, b, c, d, dt), u, x0=x0)
    return np.asarray(yd).reshape(u.shape[0], -1)


def fit_greybox(
    model: Callable[[Mapping[str, float]], object],
    t,
    u,
    y,
    initial: Mapping[str, float],
    *,
    hold: str = "zoh",
    initial_state: str = "zero",
    weights=None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    fixed: Iterable[str] | Mapping[str, float] = (),
    constraints: Sequence[Constraint] = (),
    log: Mapping[str, bool] | None = None,
    n_starts: int = 1,
    seed: int = 0,
    confidence: float = 0.95,
    ctol: float = 1e-6,
) -> GreyboxReport:
    """Fit a parametric continuous-time model to sampled input/output data.

    Parameters
    ----------
    model : callable
        ``model(p) -> control.StateSpace | control.TransferFunction``, continuous time,
        from the dict of named parameters (SI).
    t : (N,) array
        Uniform sample times [s]; the simulation starts from zero state at ``t[0]``.
    u : (N,) or (N, m) array
        Input.
    y : (N,) or (N, p) array
        Measured output.
    initial, bounds, fixed, constraints, log, n_starts, seed, confidence, ctol
        As in :func:`fit_parameters`.
    hold : {"zoh", "foh"}
        Inter-sample behaviour of the input (see :func:`simulate_continuous`).
    initial_state : {"zero", "fit"}
        Start the simulation from rest, or estimate the state at ``t[0]`` as extra
        (nuisance) parameters named ``x0[0]``, ``x0[1]``, ... in the state coordinates of
        ``control.ss(model(p))`` (give a state-space model with physical states, so that
        they mean something and do not move with the other parameters). Their starting
        values come from linear least squares at the initial parameters.
    weights : (p,) array, optional
        Residual weight per output; default 1 for one output, ``1 / std(y_i)`` for several
        (so that channels in different units count alike).

    Returns
    -------
    GreyboxReport
    """
    n = len(np.atleast_1d(t))
    check_time(t)
    u2 = as_2d(u, "u", n, finite=True)
    y2 = as_2d(y, "y", n, finite=True)
    space = build_space(initial, bounds, fixed, log)
    need = len(space.free) + 2
    if n < need:
        raise DataError(f"data too short: {n} samples for {len(space.free)} free parameters "
                        f"(need at least {need})")
    if weights is None:
        sd = y2.std(axis=0)
        w = np.ones(y2.shape[1]) if y2.shape[1] == 1 else 1.0 / np.where(sd > 0, sd, 1.0)
    else:
        w = np.asarray(weights, dtype=float).ravel()
        if w.size != y2.shape[1]:
            raise DataError(f"weights has {w.size} entries for {y2.shape[1]} output(s)")

    if initial_state not in ("zero", "fit"):
        raise DataError(f"initial_state must be 'zero' or 'fit', got {initial_state!r}")
    x0_names: list[str] = []
    scales = None
    if initial_state == "fit":
        initial, log, scales = _initial_state_guess(model, space, t, u2, y2, w, hold,
                                                    initial, log)
        x0_names = [n for n in initial if n.startswith("x0[")]

    def residual(p):
        x0 = [p[n] for n in x0_names] if x0_names else None
        ys = simulate_continuous(model(p), t, u2, hold, x0)
        if ys.shape[1] != y2.shape[1]:
            raise DataError(f"model has {ys.shape[1]} output(s) but y has {y2.shape[1]} "
                            "column(s)")
        return ((ys - y2) * w).ravel()

    return fit_parameters(residual, initial, bounds=bounds, fixed=fixed,
                          constraints=constraints, log=log, n_starts=n_starts, seed=seed,
                          confidence=confidence, ctol=ctol, scales=scales)


def _initial_state_guess(model, space, t, u2, y2, w, hold, initial, log):
    """Add ``x0[i]`` parameters, started at the least-squares initial state: the output is
    linear in it, ``y = y_u + O x0`` with O the free responses to unit initial states."""
    sys0 = control.ss(model(space.params(space.theta(space.values), "model")))
    n = sys0.nstates
    names = [f"x0[{i}]" for i in range(n)]
    clash = [nm for nm in names if nm in initial]
    if clash:
        raise DataError(f"parameter name {clash[0]!r} is reserved for the fitted initial state")
    y_u = simulate_continuous(sys0, t, u2, hold)
    zero = np.zeros_like(u2)
    obs = np.column_stack([(simulate_continuous(sys0, t, zero, hold, np.eye(n)[i]) * w).ravel()
                           for i in range(n)])
    x0, *_ = np.linalg.lstsq(obs, ((y2 - y_u) * w).ravel(), rcond=None)
    initial = {**initial, **{nm: float(v) for nm, v in zip(names, x0)}}
    log = {**(log or {}), **{nm: False for nm in names}}
    # a state's natural unit: the state that alone explains the largest output seen
    gain = np.max(np.abs(obs), axis=0)
    ymax = float(np.max(np.abs(y2 * w)))
    scales = {nm: (ymax / g if g > 0 and ymax > 0 else 1.0) for nm, g in zip(names, gain)}
    return initial, log, scales
