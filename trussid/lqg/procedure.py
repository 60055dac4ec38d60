"""The default design procedure: the best LQG that is stable and robust on the identified
model, backing off from what was asked when that is out of reach (issue 32).

A user with an identified model and its record gets a controller without tuning: the
procedure picks the target modes, tries :func:`trussid.lqg.design.design_lqg` on a ladder
of (target modes, target damping), grades each design on the *whole* identified model and
keeps the best one that is stable there with the required disk margin and spoils no other
mode. It refuses (:class:`~trussid.lqg.errors.ControlError`) only when no rung of the
ladder is stable with that margin.

Choices (justified in the module's tests and issue 32's report):

Band
    ``0`` to ``min(0.25 fs, top of the excited band)``. The controller computes ``u[k]``
    from ``y`` up to ``k - 1``: with the zero-order hold that is 1.5 samples of delay, 135
    degrees of phase at 0.25 fs. Above it a damping loop is phase-starved, and the model
    is least trustworthy there (the modes near Nyquist are the ones the identified model
    truncates or folds). Above the excited band the model is a guess.
Targets
    The lightly damped (< 5 %) complex modes in the band whose input-output residue (each
    input at its record's RMS) is at least a quarter of the largest, and at least the three
    largest: acceptance grades the three largest, and a fourth that is a quarter of the
    largest is worth damping too.
Keeping the other modes out of the loop gain
    The design model is the identified model reduced to the target modes
    (:func:`trussid.lqg.modal.modal_truncation`): the state feedback and the estimator see
    no mode outside the band, so the controller's gain is concentrated on the targets.
    What it still does to the other modes (spillover) is graded on the whole model: every
    other mode below 0.4 fs in the excited band must keep ``others_ratio`` of its damping.
Strictly proper
    The predictor form (``Dc = 0``) is the default; with a plant feed-through the filter
    form (an algebraic loop) is refused by ``design_lqg``.
Back-off ladder
    For the targets ranked by residue, the first ``k`` of them (k from all down to one
    unless ``--modes`` fixed them), and for each the target damping ``asked`` times
    :data:`LADDER`: the first rung that passes is that set's design. Designs are compared
    by the mean over the *original* targets of ``min(reached, asked) / asked`` on the
    model, so dropping a mode wins only when it buys more on the others.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .baselines import tune_baseline
from .design import LQGDesign, design_lqg, excited_band, mode_rows, _levels
from .errors import ControlError
from .evaluate import MODE_DAMPING_MAX, damping_table, disk_margins
from .grading import BASELINE_KINDS, THRESHOLDS, Baseline

__all__ = ["LADDER", "MAX_TARGET_DAMPING", "CLUSTER", "LIMITS", "TargetOutcome", "Attempt",
           "Procedure", "default_band", "rank_targets", "design_procedure", "design_controller"]

#: Fractions of the asked damping tried for one set of target modes, in order.
LADDER = (1.0, 0.75, 0.55, 0.4, 0.3, 0.2)
#: Modes lighter than this are candidates for targets [-].
MAX_TARGET_DAMPING = 0.05
#: A target within this relative frequency of another model mode is in a cluster the
#: identified model may not separate.
CLUSTER = 0.03
#: Why a target mode fell short (the ``limited_by`` of :class:`TargetOutcome`).
LIMITS = ("reached", "margin", "actuator authority", "spillover", "model uncertainty")


@dataclass(frozen=True)
class TargetOutcome:
    """What the procedure achieved on one target mode, on the identified model.

    Attributes
    ----------
    frequency_hz, identified_damping, residue : float
        The model's mode [Hz], its open-loop damping [-], its residue (inputs at the
        record's RMS).
    asked : float
        The damping asked [-].
    designed : float or None
        Damping the chosen design's state feedback was tuned for (None: dropped).
    state_feedback : float or None
        State-feedback damping reached on the design model [-].
    on_model : float
        Worst visible closed-loop damping on the whole identified model [-].
    limited_by : str
        One of :data:`LIMITS`.
    detail : str
        One sentence: what limited it.
    """

    frequency_hz: float
    identified_damping: float
    residue: float
    asked: float
    designed: float | None
    state_feedback: float | None
    on_model: float
    limited_by: str
    detail: str


@dataclass(frozen=True)
class Attempt:
    """One rung of the ladder graded on the model.

    ``passed``: stable, disk margin and spillover within the requirements. ``failure``: ""
    or one of ``"unstable"``, ``"margin"``, ``"spillover"``, ``"design"`` (design_lqg
    refused), with ``detail``.
    """

    frequencies_hz: tuple
    target_damping: float
    passed: bool
    failure: str
    detail: str
    disk_gain_db: float | None = None
    others_ratio: float | None = None
    reached: tuple = ()
    score: float = 0.0
    lqr_stop: str = ""
    seconds: float = 0.0


@dataclass
class Procedure:
    """The chosen design and how it was reached.

    Attributes
    ----------
    design : LQGDesign
    outcomes : tuple of TargetOutcome
        One per original target (dropped ones included).
    attempts : tuple of Attempt
        Every rung tried, in order.
    band_hz : (float, float)
        The band the targets were chosen in.
    asked : float
    disk_gain_db : float
        MIMO disk gain margin of the chosen design on the model [dB].
    others_ratio : float or None
    short : bool
        Some target reached less than ``0.95 * asked`` on the model.
    cpu_seconds : float
    """

    design: LQGDesign
    outcomes: tuple
    attempts: tuple
    band_hz: tuple
    asked: float
    disk_gain_db: float
    others_ratio: float | None
    short: bool
    cpu_seconds: float

    def warning(self) -> str | None:
        """One line when the design reached less than asked, else None."""
        if not self.short:
            return None
        low = [o for o in self.outcomes if o.limited_by != "reached"]
        return (f"the design reaches less than the {100 * self.asked:.1f} % asked on "
                + ", ".join(f"{o.frequency_hz:.1f} Hz ({100 * o.on_model:.2f} %, "
                            f"{o.limited_by})" for o in low)
                + f"; it is stable on the model with a {self.disk_gain_db:.1f} dB disk margin")

    def lines(self) -> list:
        """The per-target report, in plain words: the damping reached on the model and,
        when short of the asked, what limited it."""
        out = []
        for o in self.outcomes:
            head = (f"  {o.frequency_hz:7.1f} Hz: {100 * o.on_model:.2f} % on the model "
                    f"(open loop {100 * o.identified_damping:.2f} %, asked {100 * o.asked:.1f} %)")
            if o.limited_by == "reached":
                out.append(head + ": reached")
            else:
                out.append(head + f": limited by {o.limited_by}: {o.detail}")
        return out

    def choice_line(self) -> str:
        """What was kept, worded so that the state-feedback tuning is not read as the
        damping reached (the loop on the whole model reaches less, so the tuning may aim
        above the asked damping)."""
        des = self.design
        tuned = des.info["target_damping"]
        why = ("" if abs(tuned - self.asked) < 1e-9 else
               " (above the asked damping: the loop on the whole model, with its estimator "
               "and the modes the design leaves out, reaches less than its state feedback)"
               if tuned > self.asked else
               " (below the asked damping: stronger designs failed on the model, see below)")
        return (f"design: {len(self.attempts)} tried in {self.cpu_seconds:.1f} s CPU; kept a "
                f"state feedback tuned to {100 * tuned:.1f} % on {len(des.target_modes)} "
                f"modes{why}; on the model: stable, MIMO disk margin "
                f"{self.disk_gain_db:.1f} dB; per target mode:")


def default_band(fs: float, excited) -> tuple[float, float]:
    """The band [Hz] the targets are chosen in (module docstring): 0 to the lower of a
    quarter of the sample rate ``fs`` and the top of the ``excited`` band."""
    return 0.0, float(min(0.25 * fs, excited[1]))


def rank_targets(rows, band, n_modes=None, dominant_fraction: float = 0.25,
                 at_least: int = 3) -> list:
    """Blocks (rows of :func:`trussid.lqg.design.mode_rows`) to target, by residue
    (largest first): the lightly damped complex modes in ``band`` with at least
    ``dominant_fraction`` of the largest residue there, and at least the ``at_least``
    largest; or the ``n_modes`` largest."""
    lo, hi = band
    cand = [r for r in rows if r.complex and r.damping < MAX_TARGET_DAMPING
            and lo <= r.frequency_hz <= hi]
    cand.sort(key=lambda r: -r.residue)
    if not cand:
        return []
    if n_modes is not None:
        return [r.block for r in cand[:int(n_modes)]]
    rmax = cand[0].residue
    k = max(at_least, sum(r.residue >= dominant_fraction * rmax for r in cand))
    return [r.block for r in cand[:k]]


def _grade(model, des: LQGDesign, original, rows, asked, excited, min_gain_db,
           others_ratio) -> tuple:
    """``(failure, detail, disk gain, others ratio, reached per original target)``."""
    fs = 1.0 / model.dt
    tab = damping_table(model, des.controller, band=(0.0, 0.5 * fs))
    trows = tab.rows

    def near(f):
        return min(trows, key=lambda r: abs(r.frequency_hz - f))

    reached = tuple(float(near(rows[b].frequency_hz).damping_worst_visible)
                    for b in original)
    if not tab.stable:
        lam = tab.closed_loop_poles
        k = int(np.argmax(np.abs(lam)))
        f = abs(np.angle(lam[k])) / (2 * np.pi * model.dt)
        return "unstable", f"closed-loop pole at {f:.1f} Hz, |z| = {abs(lam[k]):.4f}", \
            None, None, reached
    targeted = {round(t.frequency_hz, 6) for t in des.target_modes}
    others = [r for r in trows if round(r.frequency_hz, 6) not in targeted
              and r.frequency_hz < 0.4 * fs and excited[0] <= r.frequency_hz <= excited[1]
              and 0 < r.damping_open < MODE_DAMPING_MAX]
    ratio = min((r.damping_worst_visible / r.damping_open for r in others), default=None)
    dm = disk_margins(model, des.controller).mimo
    if dm.gain_db < min_gain_db:
        return "margin", (f"MIMO disk margin {dm.gain_db:.1f} dB at "
                          f"{dm.frequency_hz:.0f} Hz, under {min_gain_db:g} dB"), \
            dm.gain_db, ratio, reached
    if ratio is not None and ratio < others_ratio:
        w = min(others, key=lambda r: r.damping_worst_visible / r.damping_open)
        return "spillover", (f"the {w.frequency_hz:.1f} Hz mode keeps {100 * ratio:.0f} % "
                             f"of its damping"), dm.gain_db, ratio, reached
    return "", "", dm.gain_db, ratio, reached


def design_procedure(model, u, y, *, K=None, target_damping: float | None = None,
                     band=None, n_modes: int | None = None, form: str = "predictor",
                     estimator: str = "record",
                     min_gain_db: float = THRESHOLDS.mimo_gm_nominal_db,
                     others_ratio: float = THRESHOLDS.other_ratio_nominal, cpu_budget_s: float = 120.0,
                     progress=None) -> Procedure:
    """The best LQG design that is stable and robust on ``model`` (module docstring).

    Parameters
    ----------
    model : control.StateSpace
        Discrete identified model, stable.
    u, y : (N, m), (N, p) float
        Its identification record.
    K : (n, p) float, optional
        The model's predictor gain (``estimator="model"``).
    target_damping : float, optional
        Damping asked of each target mode [-] (default 0.07).
    band : (float, float), optional
        Band [Hz] the targets are chosen in (default :func:`default_band`).
    n_modes : int, optional
        Target the ``n_modes`` modes of largest residue; they are then never dropped.
    form, estimator : str
        As :func:`trussid.lqg.design.design_lqg`.
    min_gain_db : float
        MIMO disk gain margin required on the model [dB] (default: the nominal loop's,
        :data:`trussid.lqg.grading.THRESHOLDS`).
    others_ratio : float
        Fraction of its open-loop damping every other mode below 0.4 fs in the excited band
        must keep on the model [-] (default: the nominal loop's).
    cpu_budget_s : float
        CPU time after which no further rung is tried [s] (the best so far is kept).
    progress : callable, optional
        Called with one line per rung.

    Returns
    -------
    Procedure

    Raises
    ------
    ControlError
        When no rung is stable on the model with ``min_gain_db`` (naming the best one).
    """
    # Long: the ladder (target sets x damping rungs, then the aim-higher step) and its
    # bookkeeping in one place, read top to bottom; grading and wording are helpers.
    say = progress or (lambda msg: None)
    t_cpu = time.process_time()
    asked = 0.07 if target_damping is None else float(target_damping)
    if not 0 < asked < 1:
        raise ControlError(f"target damping must lie in (0, 1), got {target_damping!r}")
    u = np.asarray(u, dtype=float).reshape(len(u), -1)
    y = np.asarray(y, dtype=float).reshape(len(y), -1)
    fs = 1.0 / model.dt
    excited = excited_band(u, fs)
    if band is None:
        band_used = default_band(fs, excited)
    else:
        band_used = tuple(map(float, band))
    rows = mode_rows(model, _levels(u))
    original = rank_targets(rows, band_used, n_modes)
    if not original:
        if band is not None:  # design_lqg words the refusal of a user's band
            design_lqg(model, u, y, band=band, form=form, K=K, estimator=estimator,
                       verify=False)
        raise ControlError(f"the model has no lightly damped complex mode in "
                           f"{band_used[0]:.0f}-{band_used[1]:.0f} Hz to damp")
    fixed = n_modes is not None
    sets = [original] if fixed else [original[:k] for k in range(len(original), 0, -1)]
    attempts, best = [], None
    open_loop = [rows[b].damping for b in original]

    def attempt(tset, zeta):
        """Design for ``tset`` at ``zeta``, graded on the model: ``(Attempt, design)``."""
        t0 = time.process_time()
        freqs = tuple(rows[b].frequency_hz for b in tset)
        try:
            des = design_lqg(model, u, y, target_damping=zeta, form=form, K=K,
                             estimator=estimator, verify=False, blocks=tset)
        except ControlError as exc:
            att = Attempt(freqs, zeta, False, "design", str(exc),
                          seconds=time.process_time() - t0)
            attempts.append(att)
            say(f"design for {_hz(freqs)} at {100 * zeta:.1f} %: refused ({exc})")
            return att, None
        failure, detail, gm, ratio, reached = _grade(
            model, des, original, rows, asked, excited, min_gain_db, others_ratio)
        score = _score(reached, open_loop, asked)
        if not failure and score <= 0.05:
            failure, detail = "no gain", ("the targets gain less than 5 % of the way from "
                                          "their open-loop damping to the target")
        att = Attempt(freqs, zeta, not failure, failure, detail, gm, ratio, reached,
                      score if not failure else 0.0, des.info.get("lqr_stop", ""),
                      time.process_time() - t0)
        attempts.append(att)
        say(f"design for {_hz(freqs)} at {100 * zeta:.1f} %: "
            + (f"stable, disk margin {gm:.1f} dB, targets on the model "
               + ", ".join(f"{100 * z:.2f}" for z in reached) + " %" if not failure
               else f"{failure} ({detail})"))
        return att, des

    def over_budget():
        return time.process_time() - t_cpu > cpu_budget_s and best is not None

    for tset in sets:
        if best is not None and best[0].score >= len(tset) / len(original) + 1e-9:
            break  # fewer modes cannot score more than the best so far
        floor = 2 * max(rows[b].damping for b in tset)
        failed_above, passed = None, None
        for frac in LADDER:
            if over_budget():
                break
            zeta = asked * frac
            if zeta < floor and frac != LADDER[0]:
                break  # less than twice the open-loop damping is not worth a controller
            att, des = attempt(tset, zeta)
            if att.passed:
                passed = (att, des)
                break
            failed_above = zeta
        if passed is None:
            continue
        # The loop on the whole model reaches less than the state feedback was tuned for
        # (the estimator and the modes left out take some). With margin to spare, aim
        # higher: scale the design damping by what was missing (at most twice, at most 3x
        # the asked); after a failed rung, try once between it and the one that passed.
        cands = [passed]

        def reachable(att, des):
            """Reached damping of the targets whose state feedback got to its tuning: a
            mode the iteration left short (actuator authority) gains nothing from aiming
            higher, which would only overdrive the others."""
            short = {round(f, 6) for f in des.info.get("lqr_short_hz", [])}
            return [z for b, z in zip(original, att.reached)
                    if b in tset and round(rows[b].frequency_hz, 6) not in short]

        mine = reachable(*passed)
        for _ in range(2):
            att0 = cands[-1][0]
            if over_budget() or not mine or min(mine) >= 0.95 * asked:
                break
            if failed_above is None:
                zeta = min(att0.target_damping * asked / max(min(mine), 1e-6),
                           3 * asked, 0.45)
            else:
                zeta = float(np.sqrt(att0.target_damping * failed_above))
            if zeta <= att0.target_damping * 1.05:
                break
            att, des = attempt(tset, zeta)
            if not att.passed:
                failed_above = zeta
                if len(cands) > 1 or failed_above is None:
                    break
                continue
            cands.append((att, des))
            mine = reachable(att, des)
        for att, des in cands:
            if best is None or att.score > best[0].score + 1e-9:
                best = (att, des, tset)
        if best is not None and best[0].score >= 0.95:
            break  # every target (nearly) at the damping asked
    if best is None:
        tried = [a for a in attempts if a.failure != "design"]
        def closeness(a):  # stable ones first, by margin; unstable ones by |z|
            if a.failure == "unstable":
                return (0, -float(a.detail.rsplit("= ", 1)[1]))
            return (1, a.disk_gain_db if a.disk_gain_db is not None else -1e9)

        last = max(tried, key=closeness, default=attempts[-1] if attempts else None)
        raise ControlError(
            f"no design is stable on the model with a {min_gain_db:g} dB disk margin: "
            f"{len(attempts)} tried (targets {_hz([rows[b].frequency_hz for b in original])}, "
            f"damping {100 * asked * LADDER[-1]:.1f}-{100 * asked:.1f} %)"
            + ("" if last is None else f"; the best, {_hz(last.frequencies_hz)} at "
               f"{100 * last.target_damping:.1f} %, was {last.failure}: {last.detail}"))
    att, des, tset = best
    outcomes = _outcomes(att, des, tset, original, rows, asked, attempts, model)
    short = any(o.limited_by != "reached" for o in outcomes)
    return Procedure(des, tuple(outcomes), tuple(attempts), band_used, asked,
                     float(att.disk_gain_db), att.others_ratio, short,
                     time.process_time() - t_cpu)


def _score(reached, open_loop, asked) -> float:
    """Mean over the original targets of the fraction of the way each went from its
    open-loop damping to ``asked`` (0 to 1; a mode damped less than in open loop counts
    negative)."""
    return float(np.mean([min((z - z0) / max(asked - z0, 1e-9), 1.0)
                          for z, z0 in zip(reached, open_loop)]))


def _hz(freqs) -> str:
    return ", ".join(f"{f:.1f}" for f in freqs) + " Hz"


def _outcomes(att, des, tset, original, rows, asked, attempts, model) -> list:
    """Per original target: what it reached on the model and what limited it."""
    sf = {round(t.frequency_hz, 6): t.state_feedback_damping for t in des.target_modes}
    short_hz = {round(f, 6) for f in des.info.get("lqr_short_hz", [])}
    f_all = np.array([r.frequency_hz for r in rows if r.complex])
    out = []
    for b, z in zip(original, att.reached):
        r = rows[b]
        f = r.frequency_hz
        key = round(f, 6)
        inside = b in tset
        # the failed rungs above the chosen one: what stopped them
        above = [a for a in attempts if a.failure and a.target_damping > att.target_damping
                 and any(abs(g - f) < 1e-6 * f for g in a.frequencies_hz)]
        if not inside:
            bigger = [a for a in attempts if a.failure and
                      any(abs(g - f) < 1e-6 * f for g in a.frequencies_hz)]
            # the lowest rung with it that failed for a reason other than a weak design
            telling = [a for a in bigger if a.failure not in ("no gain", "design")]
            why = (telling or bigger or [None])[-1]
            limit = _limit(why)
            detail = ("left out of the design: with it, " + (
                why.detail if why else "no design scored better"))
        elif z >= 0.95 * asked:
            limit, detail = "reached", f"{100 * z:.2f} % on the model"
        elif key in short_hz:
            limit = "actuator authority"
            detail = (f"the state feedback itself stopped at {100 * sf[key]:.2f} % "
                      f"({des.info.get('lqr_stop', '')}): the actuators barely reach this "
                      f"mode, or only together with a close neighbour")
        elif above:
            limit = _limit(above[-1])
            detail = (f"a stronger design (state feedback tuned to "
                      f"{100 * above[-1].target_damping:.1f} %) failed on the model: "
                      f"{above[-1].detail}")
        else:
            neighbour = f_all[(np.abs(f_all - f) < CLUSTER * f) & (np.abs(f_all - f) > 1e-9 * f)]
            if neighbour.size:
                limit = "model uncertainty"
                detail = (f"another model mode at {neighbour[0]:.1f} Hz lies within "
                          f"{100 * CLUSTER:g} % of it: the model may not separate the two, "
                          f"and the loop damps a mix of them")
            else:
                limit = "spillover"
                detail = (f"the state feedback gives it {100 * sf[key]:.2f} % on the design "
                          f"model; the estimator and the modes the design model leaves out "
                          f"take the rest")
        out.append(TargetOutcome(f, r.damping, r.residue, asked,
                                 att.target_damping if inside else None,
                                 sf.get(key) if inside else None, float(z), limit, detail))
    return out


def _limit(att) -> str:
    """The :data:`LIMITS` entry for a failed rung: an unstable loop at a target mode is a
    margin problem, elsewhere spillover."""
    if att is None:
        return "margin"
    if att.failure == "unstable":
        f = float(att.detail.split(" Hz")[0].split()[-1])
        at_target = any(abs(f - g) < CLUSTER * g for g in att.frequencies_hz)
        return "margin" if at_target else "spillover"
    return {"margin": "margin", "spillover": "spillover", "design": "actuator authority",
            "no gain": "actuator authority"}.get(att.failure, "margin")


def design_controller(model, u, y, *, K=None, target_damping: float | None = None, band=None,
                      form: str = "predictor", baselines: bool = True, progress=None,
                      n_modes=None):
    """The LQG from the identified ``model`` and its record, and the baselines' gains tuned
    on the same model (:func:`trussid.lqg.tune_baseline`).

    Parameters
    ----------
    model : control.StateSpace
        The identified model (discrete, named channels).
    u, y : (N, m), (N, p) float
        Its identification record.
    K, target_damping, band, form, n_modes
        As :func:`trussid.lqg.procedure.design_procedure` (the default design path: it
        backs off from ``target_damping``, default 7 %, to a design robust on the model).
    baselines : bool
        Tune the decentralised baselines too (only with as many sensors as actuators).
    progress : callable, optional
        Called with a one-line message after each step.

    Returns
    -------
    design : trussid.lqg.LQGDesign
    baselines : dict
        ``{kind: Baseline}``.
    timings : dict
        Wall seconds per step.
    """
    say = progress or (lambda msg: None)
    timings = {}
    t0 = time.perf_counter()
    # the one design path (issue 32): the best design stable and robust on the model
    proc = design_procedure(model, u, y, K=K, target_damping=target_damping, band=band,
                            form=form, n_modes=n_modes)
    des = proc.design
    des.procedure = proc
    timings["design"] = time.perf_counter() - t0
    freqs = ", ".join(f"{t.frequency_hz:.0f}" for t in des.target_modes)
    say(f"LQG designed on {des.design_model.nstates} states ({freqs} Hz) "
        f"in {timings['design']:.1f} s ({len(proc.attempts)} designs tried, disk margin "
        f"{proc.disk_gain_db:.1f} dB on the model)")
    base = {}
    if baselines and model.ninputs != model.noutputs:
        # a decentralised baseline feeds each actuator from its own sensor: with unequal
        # counts there is no such pairing, so there is nothing to compare the LQG with
        say(f"no decentralised baselines: they pair each actuator with one sensor, and the "
            f"model has {model.ninputs} actuators and {model.noutputs} sensors")
    elif baselines:
        t0 = time.perf_counter()
        f = [t.frequency_hz for t in des.target_modes]
        bp_band = (0.85 * min(f), 1.15 * max(f))
        direct = np.any(np.asarray(model.D) != 0)
        for kind in BASELINE_KINDS:
            if direct and not kind.endswith("+delay"):
                # a baseline without the delay has a direct term: with the plant's
                # feed-through the loop would be algebraic
                say(f"no {kind} baseline: the model has a direct term (an algebraic loop)")
                continue
            g, info = tune_baseline(model, kind, bp_band)
            base[kind] = Baseline(g, list(bp_band), info)
        timings["baselines_tuning"] = time.perf_counter() - t0
        say(f"baselines tuned on the model in {timings['baselines_tuning']:.1f} s")
    return des, base, timings
