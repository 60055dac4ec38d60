"""Discrete LQG active damping designed from an identified model and its record.

The controller is ``u = controller(y)``: inputs are the sensor names, outputs the actuator
names, no hidden sign. Two forms (``form``):

``predictor`` (default, as the thesis's PC ran it)
    ``u[k] = -F xhat[k|k-1]``: the command of sample k uses measurements up to k-1, which
    leaves one sample for the computation. ``xhat[k+1|k] = A xhat + B u[k] + K (y[k] - C
    xhat)``, so ``Ac = A - B F - K C``, ``Bc = K``, ``Cc = -F``, ``Dc = 0``.
``filter``
    ``u[k] = -F xhat[k|k]`` with ``xhat[k|k] = xhat[k|k-1] + L (y[k] - C xhat[k|k-1])`` and
    ``L = A^-1 K``: the command uses y[k] itself (a direct term), i.e. assumes the
    computation takes no time.

Recipe (measured in ``benchmarks/results/control.md``):

1. Target modes: the identified model's lightly damped complex modes whose residue from
   the actuators to the sensors is at least ``dominant_fraction`` of the largest one, or
   every mode in ``band`` [Hz].
2. Design model: the modal truncation of the identified model to the target modes (exact
   poles and residues). A design on the full identified model keeps its poorly identified
   out-of-band modes (e.g. the 0.25 % strut second-bending family) in the estimator, and a
   5 % stiffness shift then destabilises the loop.
3. Estimator gain: chosen on the identification record for the *design* model
   (:func:`plid.metrics.choose_predictor`: steady-state Kalman gains for a ladder of
   state-to-output noise ratios, the best one-step predictor on the record wins; the
   out-of-band response of the structure then acts as output noise), or the identified
   model's own ``K`` projected on the target modes (``estimator="model"``). If the
   record's choice leaves a target mode's estimator pole below half the target damping,
   it would ring in the closed loop, so the dual of step 4 replaces it.
4. State feedback: :func:`control.dlqr` with ``R = I`` and a weight per target mode on its
   real 2x2 modal block, iterated until the state-feedback damping of each target mode is
   ``target_damping``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import control
import numpy as np

from trussid.plid.metrics import choose_predictor
from trussid.plid.modal import assign_pairs

from .errors import ControlError
from .evaluate import damping_table
from .modal import freq_damping, modal_data, modal_truncation, real_modal_basis
from .shaping import InputWeight, augment, weighted_controller

__all__ = ["FORMS", "ESTIMATORS", "TargetMode", "DesignCheck", "LQGDesign", "check_model",
           "excited_band", "ModelMode", "mode_rows", "LQRTuning", "select_modes",
           "lqr_for_damping", "design_lqg", "verify_design",
           "controller_matrices"]

FORMS = ("predictor", "filter")
ESTIMATORS = ("record", "model")


@dataclass(frozen=True)
class TargetMode:
    """A target mode of a design: the identified model's mode and what the state feedback
    reached on it.

    Attributes
    ----------
    block : int
        Its block in :func:`trussid.lqg.modal.real_modal_basis` of the model.
    frequency_hz, damping, residue : float
        The identified mode [Hz], [-] and its residue (in the record's input levels).
    complex : bool
        A complex pair (always, for a target).
    state_feedback_damping : float
        Damping the state feedback gives it on the design model [-].
    weight : float
        Its LQR weight.
    """

    block: int
    frequency_hz: float
    damping: float
    residue: float
    complex: bool
    state_feedback_damping: float
    weight: float


@dataclass(frozen=True)
class DesignCheck:
    """A design closed around the whole model it was designed from (:func:`verify_design`):
    the loop's spectral radius and, per target mode, its worst visible damping [-]."""

    spectral_radius: float
    target_damping_reached: list


@dataclass
class LQGDesign:
    """A designed controller and what it was made from.

    Attributes
    ----------
    controller : control.StateSpace
        Discrete, ``u = controller(y)``; inputs the sensor names, outputs the actuator names.
    design_model : control.StateSpace
        The model the gains were computed on (real modal coordinates).
    F : (m, n) float
        State-feedback gain (``u = -F xhat``).
    K : (n, p) float
        One-step predictor gain of the design model.
    form : str
    target_modes : tuple of TargetMode
        Frequency [Hz], identified damping, residue and the state-feedback damping reached.
    info : dict
        Everything else (weights, estimator choice, iterations).
    """

    controller: control.StateSpace
    design_model: control.StateSpace
    F: np.ndarray
    K: np.ndarray
    form: str
    target_modes: tuple
    info: dict = field(default_factory=dict)
    procedure: object = None  # trussid.lqg.procedure.Procedure that chose it, if any


def check_model(model, source: str = "model") -> None:
    """Refuse a model a controller cannot be designed from (one line naming the problem)."""
    if not control.isdtime(model, strict=True):
        raise ControlError(f"{source}: the model is continuous (dt = 0); a discrete model is needed")
    rho = np.max(np.abs(np.linalg.eigvals(np.asarray(model.A))), initial=0.0)
    if not rho < 1:
        raise ControlError(f"{source}: the model is unstable (largest pole magnitude {rho:.6f} >= 1)")


def excited_band(u, fs: float, floor_db: float = -20.0) -> tuple[float, float]:
    """Band [Hz] over which the record's inputs have power: where the summed Welch PSD
    of the inputs is within ``floor_db`` of its peak (the demo's 0-400 Hz excitation)."""
    from scipy.signal import welch

    f, S = welch(np.asarray(u, dtype=float), fs=fs, nperseg=min(1024, len(u)), axis=0)
    S = S.sum(axis=1) if S.ndim > 1 else S
    on = f[S >= S.max() * 10 ** (floor_db / 10)]
    return float(on.min()), float(on.max())


@dataclass(frozen=True)
class ModelMode:
    """One block of :func:`modal.real_modal_basis` of an identified model (:func:`mode_rows`).

    Attributes
    ----------
    block : int
        Its block index.
    frequency_hz, damping : float
        The mode [Hz], [-].
    residue : float
        Its input-output residue (inputs scaled, outputs divided as :func:`mode_rows` was
        told).
    complex : bool
        A complex pair (False: a real pole).
    """

    block: int
    frequency_hz: float
    damping: float
    residue: float
    complex: bool


def mode_rows(model, u_scale=None, y_scale=None) -> list:
    """One :class:`ModelMode` per block of :func:`modal.real_modal_basis`, the residues with
    the inputs scaled by ``u_scale`` and the outputs divided by ``y_scale``."""
    _, blocks = real_modal_basis(model.A)
    su = np.ones(model.ninputs) if u_scale is None else np.asarray(u_scale, dtype=float)
    sy = np.ones(model.noutputs) if y_scale is None else np.asarray(y_scale, dtype=float)
    md = modal_data(model.A, np.asarray(model.B) * su[None, :],
                    np.asarray(model.C) / sy[:, None], model.dt)
    rows = []
    for k, (idx, lam) in enumerate(blocks):
        i = int(np.argmin(np.abs(md.poles - lam)))
        rows.append(ModelMode(k, float(md.frequency_hz[i]), float(md.damping[i]),
                              float(md.residue[i]), idx.size == 2))
    return rows


def select_modes(model, band=None, dominant_fraction: float = 0.25, max_damping: float = 0.05,
                 excited=None, u_scale=None, y_scale=None, n_modes=None):
    """Indices of the target blocks of :func:`modal.real_modal_basis` and a table of all modes.

    Parameters
    ----------
    model : control.StateSpace
        Discrete identified model.
    band : (float, float), optional
        Every complex mode with a frequency in ``[lo, hi]`` Hz.
    max_damping : float
        Only complex modes damped below this are candidates [-].
    dominant_fraction : float
        Without ``band``: the complex modes with damping below ``max_damping`` inside the
        ``excited`` band whose residue is at least this fraction of the largest such residue
        (modes outside the excited band are poorly identified: the demo's 36-state model
        has spurious ones at 441-667 Hz, above its 400 Hz excitation).
    excited : (float, float), optional
        Band the identification record excited [Hz] (:func:`excited_band`).
    n_modes : int, optional
        Target the ``n_modes`` lightly damped modes with the largest residue (in ``band``
        when given, else in the ``excited`` band) instead of all the dominant ones (or all
        those in ``band``).
    u_scale, y_scale : (m,), (p,) float, optional
        Typical level of each input and output (the record's RMS) in their own units: the
        residues are compared in these units, so that a shaker in N beside a PZT in V, or
        an accelerometer beside a strain gauge, weigh as the experiment drove and saw them.
    """
    rows = mode_rows(model, u_scale, y_scale)
    cand = [r for r in rows if r.complex and r.damping < max_damping]
    if band is not None:
        lo, hi = map(float, band)
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi):
            raise ControlError(f"band: need 0 <= LO < HI [Hz], got {lo:g} {hi:g}")
        sel = [r.block for r in cand if lo <= r.frequency_hz <= hi]
        if sel and n_modes is not None:
            sel = sorted(sel, key=lambda b: -rows[b].residue)[:int(n_modes)]
        if not sel:
            near = ", ".join(f"{r.frequency_hz:.1f}" for r in cand)
            nyq = 0.5 / model.dt
            above = f" (above the Nyquist frequency {nyq:g} Hz)" if lo >= nyq else ""
            raise ControlError(f"band {lo:g}-{hi:g} Hz{above} holds no lightly damped mode of "
                               f"the model (its modes: {near} Hz)")
    else:
        if excited is not None:
            cand = [r for r in cand if excited[0] <= r.frequency_hz <= excited[1]]
        if not cand:
            raise ControlError("the model has no lightly damped complex mode to damp"
                               + ("" if excited is None else
                                  f" in the excited band {excited[0]:.0f}-{excited[1]:.0f} Hz"))
        rmax = max(r.residue for r in cand)
        if n_modes is not None:
            sel = [r.block for r in sorted(cand, key=lambda r: -r.residue)[:int(n_modes)]]
        else:
            sel = [r.block for r in cand if r.residue >= dominant_fraction * rmax]
    return sorted(sel, key=lambda b: rows[b].frequency_hz), rows


def _mode_damping(Acl, T_blocks, n_modes, dt, open_hz=None):
    """Damping of each design-model mode in a closed loop on the design model: each
    closed-loop pole (upper half plane) goes to the block holding most of its eigenvector.

    With ``open_hz`` (each block's open-loop frequency [Hz]), a block only gets a pole
    within 30 % of that frequency: the loop of a frequency-shaped design has the weight's
    poles too, and one far above the band can hold a large share of a target block's
    coordinates (the plant responds there) without being that mode."""
    lam, V = np.linalg.eig(Acl)
    # real poles count too: a block whose pair the feedback split into two real (overdamped)
    # poles gets one of them, damping 1 (leaving it out left the block's damping NaN)
    up = lam.imag >= 0
    lam, V = lam[up], V[:, up]
    share = np.array([[np.linalg.norm(V[idx, j]) for j in range(lam.size)] for idx in T_blocks])
    if open_hz is not None:
        f_cl = np.abs(np.angle(lam)) / (2 * np.pi * dt)
        f0 = np.asarray(open_hz, dtype=float)[:, None]
        share = np.where(np.abs(f_cl[None, :] - f0) <= 0.3 * f0, share, 0.0)
    pole = assign_pairs(-share)
    r = np.flatnonzero(pole >= 0)
    c = pole[r]
    zeta = np.full(n_modes, np.nan)
    _, z = freq_damping(lam[c], dt)
    zeta[r] = z
    return zeta


@dataclass(frozen=True)
class LQRTuning:
    """The state feedback of :func:`lqr_for_damping` and how its iteration ended.

    Attributes
    ----------
    F : (m, n) float
        State-feedback gain (``u = -F x``).
    weights : (k,) float
        Final weight on each modal block.
    damping : (k,) float
        State-feedback damping of each block's mode [-] (0 where no pole was assigned).
    iterations : int
    reason : str
        ``"converged"``; ``"weight limit"`` (a mode below the target whose weight reached
        :data:`WEIGHT_RANGE` times the starting one: the actuators barely reach it);
        ``"no progress"`` (the modes below the target gained nothing over
        :data:`STALL_ITERATIONS` iterations: raising one mode's weight damps a close
        neighbour instead, or the mode is not controllable from the actuators);
        ``"iteration limit"``.
    short : (k,) bool
        Blocks left below the target (relative ``tol``) when the iteration stopped.
    """

    F: np.ndarray
    weights: np.ndarray
    damping: np.ndarray
    iterations: int
    reason: str
    short: np.ndarray


#: Largest ratio of a block's weight to the starting weight: beyond 1e12 a mode that is
#: still short of the target is one the actuators do not reach (and the weights, growing
#: x10 a step, would overflow to inf and turn ``Q`` into NaN: "Q must be a symmetric
#: matrix" from the Riccati solver).
WEIGHT_RANGE = 1e12
#: Iterations without gain on the modes below the target after which the iteration stops.
STALL_ITERATIONS = 12


def lqr_for_damping(A, B, blocks, target, dt: float, max_iter: int = 200,
                    tol: float = 0.02, R=None, weight=None) -> LQRTuning:
    """State feedback ``u = -F x`` from :func:`control.dlqr` with a weight on each modal
    block, iterated so that every block's mode reaches damping ``target`` (relative ``tol``).

    A mode's state-feedback damping grows monotonically with its weight; each weight is
    scaled by ``(target / zeta)^2`` (at most x10 per step) until all agree. ``R`` is the
    input weight (default identity). The iteration stops, with its reason
    (:class:`LQRTuning`), when every mode is at the target, when a short mode's weight
    reaches :data:`WEIGHT_RANGE` times the starting one, when the short modes gain nothing
    for :data:`STALL_ITERATIONS` iterations, or after ``max_iter``.

    ``target`` may be one damping per block. ``weight``, a frequency-shaped input weight
    (:class:`InputWeight`), replaces ``u' R u`` by the energy of ``W(z) u`` (Gupta 1980):
    the filter's states are appended to ``A`` (so ``F`` has ``n + nw`` columns) and the
    feedback spends little control where ``|W|`` is large.
    """
    n_plant, m = B.shape
    R = np.eye(m) if R is None else np.asarray(R, dtype=float)
    target = np.broadcast_to(np.asarray(target, dtype=float), (len(blocks),))
    # a starting weight of the size of the input matrix's effect
    q0 = 1e-3 * np.min(np.diag(R)) / max(np.linalg.norm(B, 2) ** 2, 1e-300)
    N = None
    if weight is not None:
        # each block's open-loop frequency, to tell its closed-loop pole from the weight's
        open_hz = [float(np.abs(np.angle(np.linalg.eigvals(A[np.ix_(idx, idx)]))).max())
                   / (2 * np.pi * dt) for idx in blocks]
        A, B, Qw, N, R = augment(A, B, R, weight)
    else:
        open_hz = None
    n = A.shape[0]
    q = np.full(len(blocks), q0)
    F = np.zeros((m, n))
    zeta = np.zeros(len(blocks))
    best, since, reason = -np.inf, 0, "iteration limit"
    for it in range(max_iter):
        Q = np.zeros((n, n)) if N is None else Qw.copy()
        for w, idx in zip(q, blocks):
            Q[np.ix_(idx, idx)] = w * np.eye(idx.size)
        # scipy's solver: slycot's sg02ad (python-control's default once slycot is installed)
        # fails on the weakly weighted, 0.25 %-damped design models ("roundoff changed ...").
        try:
            F_new, _, _ = (control.dlqr(A, B, Q, R, method="scipy") if N is None else
                           control.dlqr(A, B, Q, R, N, method="scipy"))
        except (ValueError, np.linalg.LinAlgError, control.ControlArgument):
            reason = "solver failed"
            break
        F = np.asarray(F_new)
        zeta = _mode_damping(A - B @ F, blocks, len(blocks), dt, open_hz)
        zeta = np.where(np.isfinite(zeta), zeta, 0.0)  # unassigned: treat as undamped
        # a mode already above the target with a vanishing weight needs no feedback
        done = (np.abs(zeta / target - 1) < tol) | ((zeta > target) & (q < 1e-12 * q.max()))
        if np.all(done):
            reason = "converged"
            break
        low = zeta < target * (1 - tol)
        if np.any(low & (q >= WEIGHT_RANGE * q0)):
            reason = "weight limit"
            break
        worst = float(np.min((zeta / target)[low])) if low.any() else 1.0
        if worst > best * (1 + 1e-3):
            best, since = worst, 0
        else:
            since += 1
            if since >= STALL_ITERATIONS:
                reason = "no progress"
                break
        q = np.minimum(q * np.clip((target / np.maximum(zeta, 1e-6)) ** 2, 0.1, 10.0),
                       WEIGHT_RANGE * q0)
    short = zeta < target * (1 - tol)
    return LQRTuning(F, q, zeta, it + 1, reason, short)


def design_lqg(model, u, y, *, target_damping: float = 0.07, band=None,
               form: str = "predictor", estimator: str = "record",
               dominant_fraction: float = 0.25, K=None, verify: bool = True,
               min_fraction: float = 0.5, n_modes: int | None = None,
               blocks=None, input_weight: InputWeight | None = None,
               estimator_damping=None) -> LQGDesign:
    """Design a discrete LQG damping controller from an identified model and its record.

    Parameters
    ----------
    model : control.StateSpace
        Discrete identified model (actuator volts in, sensor volts out), stable.
    u, y : (N, m), (N, p) float
        The identification record the model was identified from [V].
    target_damping : float
        Damping ratio the state feedback gives each target mode [-], in (0, 1).
    band : (float, float), optional
        Target every mode in this band [Hz] instead of the dominant ones.
    form : {"predictor", "filter"}
    estimator : {"record", "model"}
        Kalman gain chosen on the record for the design model, or the model's own ``K``
        (projected on the target modes).
    dominant_fraction : float
        Residue fraction that makes a mode dominant (without ``band``).
    K : (n, p) float, optional
        The identified model's predictor gain (needed for ``estimator="model"``).
    verify : bool
        Close the loop on the whole ``model`` and refuse a design that is unstable there or
        leaves a target mode below ``min_fraction`` of ``target_damping``
        (:func:`verify_design`).
    min_fraction : float
    n_modes : int, optional
        Target this many modes, those with the largest residue (:func:`select_modes`).
    blocks : sequence of int, optional
        Target exactly these blocks of :func:`modal.real_modal_basis` (complex ones; the
        rows of :func:`mode_rows`), instead of selecting by ``band``, ``n_modes`` and
        ``dominant_fraction``.
    input_weight : InputWeight, optional
        Frequency-shaped weight on the control signal (predictor form only): the state
        feedback is tuned on the design model with the weight's states appended, and the
        controller carries them (``u = -F_x xhat - F_w w``, still strictly proper).
    estimator_damping : float or (k,) float, optional
        Tune the estimator as the dual of the damping tuning to this predictor-pole damping
        on each target mode [-] (``estimator="record"`` only) instead of the record's best
        one-step predictor: a broader estimator tolerates the frequency error of modes the
        model smears.

    Returns
    -------
    LQGDesign

    Examples
    --------
    Active damping of a two-mode plant (50 and 120 Hz at 0.5 %) to 5 %, designed from the
    plant and a noisy record of it; the closed loop around the plant:

    >>> import control
    >>> import numpy as np
    >>> from trussid.lqg import closed_loop, design_lqg
    >>> from trussid.plid import excitation, modal_table, simulate
    >>> s = control.tf("s")
    >>> G = sum(g * (2 * np.pi * f) ** 2 / (s**2 + 0.01 * 2 * np.pi * f * s + (2 * np.pi * f) ** 2)
    ...         for f, g in ((50.0, 1.0), (120.0, 0.5)))
    >>> d = control.c2d(control.ss(G), 1e-3)
    >>> plant = control.ss(d.A, d.B, d.C, d.D, 1e-3, inputs=["u"], outputs=["y"])
    >>> u = excitation("white", 2000, fs=1000.0, seed=1)
    >>> y = simulate(plant, u) + 1e-3 * np.random.default_rng(0).standard_normal((2000, 1))
    >>> design = design_lqg(plant, u, y, target_damping=0.05)
    >>> [round(m.frequency_hz, 1) for m in design.target_modes]
    [50.0, 120.0]
    >>> loop = modal_table(closed_loop(plant, design.controller))
    >>> print(np.round(loop.frequencies_hz, 1), np.round(100 * loop.damping, 1))
    [ 50.1  50.1 120.1 120.1] [4.9 5.  4.9 5. ]
    """
    # Long: the four steps of the recipe (module docstring) in order, with the input checks
    # before them and the check on the whole model after; each step calls a helper.
    zt = np.asarray(target_damping, dtype=float) if np.ndim(target_damping) else None
    if zt is None and not (isinstance(target_damping, (int, float)) and 0 < target_damping < 1) \
            or zt is not None and not np.all((zt > 0) & (zt < 1)):
        raise ControlError(f"target damping must lie in (0, 1), got {target_damping!r}")
    if form not in FORMS:
        raise ControlError(f"form must be one of {', '.join(FORMS)}, got {form!r}")
    if estimator not in ESTIMATORS:
        raise ControlError(f"estimator must be one of {', '.join(ESTIMATORS)}, got {estimator!r}")
    check_model(model)
    u = np.asarray(u, dtype=float).reshape(len(u), -1)
    y = np.asarray(y, dtype=float).reshape(len(y), -1)
    if u.shape[1] != model.ninputs or y.shape[1] != model.noutputs:
        raise ControlError(f"record has {u.shape[1]} inputs and {y.shape[1]} outputs; the model "
                          f"{model.ninputs} and {model.noutputs}")
    D = np.asarray(model.D, dtype=float)
    if form == "filter" and np.any(D != 0):
        raise ControlError("the filter form needs a strictly proper model (its D is not zero: "
                           "an algebraic loop with the plant's feed-through); use the "
                           "predictor form")
    excited = excited_band(u, 1.0 / model.dt)
    # Levels of the record's channels in their own units: residues and the LQR input weight
    # (Bryson's rule, R = diag(1 / rms^2)) treat a shaker in N beside a PZT in V as the
    # experiment drove them, instead of comparing a newton with a volt.
    # The outputs are not rescaled: an accelerometer's RMS is that of its highest modes, and
    # dividing by it would hide the low ones.
    u_rms = _levels(u)
    y_rms = _levels(y)
    if blocks is None:
        sel, rows = select_modes(model, band, dominant_fraction, excited=excited,
                                 u_scale=u_rms, n_modes=n_modes)
    else:
        rows = mode_rows(model, u_rms)
        bad = [b for b in blocks if not (0 <= int(b) < len(rows) and rows[int(b)].complex)]
        if bad or not len(blocks):
            raise ControlError(f"target blocks {bad or list(blocks)}: need the indices of "
                               f"complex modes of the model (0..{len(rows) - 1})")
        sel = sorted({int(b) for b in blocks}, key=lambda b: rows[b].frequency_hz)
    dm, kept = modal_truncation(model, sel)
    A, B, C = (np.asarray(M, dtype=float) for M in (dm.A, dm.B, dm.C))
    blocks = [np.array([2 * k, 2 * k + 1]) for k in range(len(kept))]
    if input_weight is not None and form != "predictor":
        raise ControlError("an input weight needs the predictor form")
    R = np.diag(1.0 / u_rms**2)
    tuning = lqr_for_damping(A, B, blocks, target_damping, model.dt, R=R, weight=input_weight)
    F, q, zeta_sf, iters = tuning.F, tuning.weights, tuning.damping, tuning.iterations
    if estimator == "model":
        if K is None:
            raise ControlError("estimator 'model': the model file has no predictor gain K")
        T, all_blocks = real_modal_basis(model.A)
        KT = np.linalg.solve(T, np.asarray(K, dtype=float))
        Kd = np.vstack([KT[all_blocks[b][0]] for b in sel])
        kinfo = {"chosen": "identified model's K, projected on the target modes"}
    else:
        Kd, _, kinfo = choose_predictor(dm, u, y)
        zeta_k = _mode_damping(A - Kd @ C, blocks, len(blocks), model.dt)
        # a NaN (a target mode with no estimator pole assigned) counts as a failure
        if estimator_damping is not None or not np.all(zeta_k >= 0.5 * np.min(target_damping)):
            # An estimator pole left lightly damped on a target mode rings in the closed loop
            # as the mode did (the best one-step predictor of a clean record can be slow).
            # Use the dual of the state-feedback tuning instead: a steady-state Kalman gain
            # whose predictor poles reach the target damping on every target mode.
            ez = target_damping if estimator_damping is None else estimator_damping
            Fd = lqr_for_damping(A.T, C.T, blocks, ez, model.dt,
                                 R=np.diag(y_rms**2)).F
            finite = zeta_k[np.isfinite(zeta_k)]
            kinfo = dict(kinfo, rejected=kinfo.get("chosen"),
                         rejected_min_damping=float(finite.min()) if finite.size else None,
                         chosen="dual of the damping tuning (the record's best predictor "
                                "left a target mode below half the target damping)")
            Kd = Fd.T
    rho = np.max(np.abs(np.linalg.eigvals(A - Kd @ C)))
    if not rho < 1:
        raise ControlError(f"the estimator is unstable on the design model (pole magnitude {rho:.4f})")
    if input_weight is None:
        ctrl = controller_matrices(A, B, C, F, Kd, form, D=D)
    else:
        ctrl = weighted_controller(A, B, C, D, F, Kd, augment(A, B, R, input_weight)[:2])
    names_in, names_out = list(model.output_labels), list(model.input_labels)
    controller = control.ss(*ctrl, model.dt, inputs=names_in, outputs=names_out,
                            name=f"lqg_{form}")
    _, zeta_est = freq_damping(np.linalg.eigvals(A - Kd @ C), model.dt)
    targets = tuple(TargetMode(**asdict(rows[b]), state_feedback_damping=float(z), weight=float(w))
                    for b, z, w in zip(sel, zeta_sf, q))
    info = {"form": form, "estimator": estimator, "estimator_choice": kinfo,
            "target_damping": target_damping if zt is None else zt.tolist(), "band": None if band is None else list(band),
            "dominant_fraction": dominant_fraction, "n_modes": n_modes,
            "lqr_iterations": iters, "lqr_stop": tuning.reason,
            "lqr_short_hz": [rows[b].frequency_hz for b, s in zip(sel, tuning.short) if s],
            "excited_band_hz": list(excited),
            "design_states": int(A.shape[0]), "model_states": int(model.nstates),
            "estimator_min_damping": float(np.min(zeta_est)) if zeta_est.size else None,
            "input_rms": u_rms.tolist(), "output_rms": y_rms.tolist(),
            "input_weight": None if input_weight is None else list(input_weight.peaks),
            "model_modes": rows}
    des = LQGDesign(controller, dm, F, Kd, form, targets, info)
    if verify:
        info["on_model"] = verify_design(model, des, min_fraction=min_fraction)
    return des


def _levels(x) -> np.ndarray:
    """RMS of each column about its mean; a constant column gets 1 (no level to scale by)."""
    r = np.std(x, axis=0)
    return np.where(r > 0, r, 1.0)


def verify_design(model, design: LQGDesign, min_fraction: float = 0.5) -> DesignCheck:
    """The designed controller on the whole model it was designed from: refuse a design that
    is unstable there, or that leaves a target mode below ``min_fraction`` of the target
    damping (:class:`ControlError` naming the pole or the mode).

    The design model holds the target modes only; the modes it leaves out, the estimator
    and the feed-through are all in this loop, so a design can fail here although its state
    feedback reached every target.

    Parameters
    ----------
    model : control.StateSpace
        The identified model the design was made from.
    design : LQGDesign
    min_fraction : float
        Least fraction of the target damping every target mode must reach [-].

    Returns
    -------
    DesignCheck
        The spectral radius and, per target mode, the worst visible closed-loop damping
        (:func:`trussid.lqg.evaluate.damping_table`) on the model.
    """
    nyq = 0.5 / model.dt
    tab = damping_table(model, design.controller, band=(0.0, nyq))
    lam = tab.closed_loop_poles
    if not tab.stable:
        k = int(np.argmax(np.abs(lam)))
        f, z = freq_damping(lam[k:k + 1], model.dt)
        raise ControlError(
            f"the design is unstable on the model it was designed from: closed-loop pole at "
            f"{f[0]:.1f} Hz, damping {100 * z[0]:.2f} % (|z| = {abs(lam[k]):.4f}); try a lower "
            f"--target-damping or a --band holding fewer modes")
    target = design.info["target_damping"]
    reached = []
    for t in design.target_modes:
        r = min(tab.rows, key=lambda r: abs(r.frequency_hz - t.frequency_hz))
        reached.append(float(r.damping_worst_visible))
    asked = np.broadcast_to(np.asarray(target, dtype=float), (len(reached),))
    worst = int(np.argmin(np.asarray(reached) / asked)) if reached else None
    if worst is not None and reached[worst] < min_fraction * asked[worst]:
        t = design.target_modes[worst]
        target = asked[worst]
        raise ControlError(
            f"the design falls short on the model it was designed from: the "
            f"{t.frequency_hz:.1f} Hz target mode reaches {100 * reached[worst]:.2f} % "
            f"damping, less than {100 * min_fraction:g} % of the {100 * target:.1f} % asked "
            f"(the other targets: "
            + ", ".join(f"{x.frequency_hz:.1f} Hz {100 * z:.2f} %"
                        for x, z in zip(design.target_modes, reached) if x is not t)
            + "); try another --band or --target-damping")
    return DesignCheck(tab.spectral_radius, reached)


def controller_matrices(A, B, C, F, K, form: str = "predictor", D=None):
    """``(Ac, Bc, Cc, Dc)`` of ``u = controller(y)`` for the LQG with state feedback ``F`` and
    one-step predictor gain ``K`` (module docstring) of a model with feed-through ``D``
    (default none): the innovation is ``y - C xhat - D u``."""
    m, p = F.shape[0], C.shape[0]
    D = np.zeros((p, m)) if D is None else np.asarray(D, dtype=float)
    if form == "predictor":
        # xhat+ = A xhat + B u + K (y - C xhat - D u), u = -F xhat
        return A - B @ F - K @ (C - D @ F), K, -F, np.zeros((m, p))
    L = np.linalg.solve(A, K)  # filter gain from the predictor gain (K = A L)
    # xf = xhat + L (y - C xhat - D u), u = -F xf  =>  (I - F L D) u = -F (I - L C) xhat - F L y
    G = np.linalg.inv(np.eye(m) - F @ L @ D)
    IminusLC = np.eye(A.shape[0]) - L @ C
    Cc, Dc = -G @ F @ IminusLC, -G @ F @ L
    # xhat+ = A xf + B u = (A - K C) xhat + K y + (B - K D) u
    BKD = B - K @ D
    return A - K @ C + BKD @ Cc, K + BKD @ Dc, Cc, Dc
