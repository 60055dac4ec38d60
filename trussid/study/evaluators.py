"""What a study computes at one point: testbed modes, wall sensitivities, plant metrics, fits.

Each evaluator is a plain object with

- ``parameters``: the parameters it takes, each with a check of one value;
- ``options``: its options and their defaults;
- ``check(spec, where)``: a :class:`~trussid.study.errors.StudyError` naming the first bad
  parameter, value or option;
- ``columns(options)``: its output columns and their Arrow types (fixed per study, so that
  every chunk of the result dataset has the same schema, failed rows included);
- ``context(options)``: what every point of a study shares (the testbed model and its wall
  basis, the truth plant), built once per worker process (:func:`functools.lru_cache` keyed
  on the options' canonical JSON: a pure function of its key, so caching it hides nothing);
- ``point(ctx, params, options)``: the outputs of one point as ``{column: value}``.

A point that raises is recorded by the engine as a failed row with the one-line reason; it
never ends the study.
"""

from __future__ import annotations

import functools
import json
import math
import warnings
from dataclasses import MISSING, asdict, dataclass, field, fields, replace

import numpy as np
import pyarrow as pa

from trussid.geometry.params_toml import testbed_from_dict
from trussid.geometry.spec import Testbed
from trussid.plid.estimator import PLIDWarning
from trussid.plid.evaluate import compare
from trussid.plid.frf import frequency_response
from trussid.plid.recipe import identify
from trussid.plid.reduced import identify_reduced
from trussid.plid.subspace import n4sid
from trussid.study.deck import DeckModesEvaluator
from trussid.study.errors import StudyError
from trussid.study.plants import PLANTS, record
from trussid.testbed.labels import label_testbed_modes
from trussid.testbed.model import N_STRUTS, build_testbed
from trussid.testbed.walls import design_at_walls, wall_basis, wall_modes
from trussid.testbed.plant import testbed_plant
from trussid.testbed.sensitivity import wall_sensitivities

WALLS = tuple(f"wall{i}" for i in range(N_STRUTS))


def _number(name, v, where, *, positive=False, integer=False, minimum=None):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or (integer and not isinstance(v, int)):
        kind = "an integer" if integer else "a number"
        raise StudyError(f"{where}: parameter {name!r} must be {kind}, got {v!r}")
    if not math.isfinite(v):
        raise StudyError(f"{where}: parameter {name!r} must be finite, got {v!r}")
    if positive and v <= 0:
        raise StudyError(f"{where}: parameter {name!r} must be positive, got {v!r}")
    if minimum is not None and v < minimum:
        raise StudyError(f"{where}: parameter {name!r} must be at least {minimum}, got {v!r}")


def _values_of(axis):
    """Every value an axis can take that can be checked before running (ends of ranges)."""
    if axis.values is not None:
        return list(axis.values)
    return [axis.low, axis.high]


def _check_wall(name, v, where):
    _number(name, v, where)
    if v <= 0:
        raise StudyError(f"{where}: parameter {name!r}: wall thickness must be positive, got {v!r} m")


def _check_damping(name, v, where):
    _number(name, v, where)
    if not 0 < v < 1:
        raise StudyError(f"{where}: parameter {name!r}: damping ratio must be in (0, 1), got {v!r}")


def _defaults(options_type) -> dict:
    """The options of an evaluator and their defaults, from its options dataclass."""
    return {f.name: f.default if f.default_factory is MISSING else f.default_factory()
            for f in fields(options_type)}


class Evaluator:
    """Base of the evaluators (module docstring).

    ``Options`` is the evaluator's frozen options dataclass: a spec's ``[evaluate]`` table
    is checked against it (unknown keys named) and read through it (:meth:`typed`).
    """

    name = ""
    parameters: dict = {}
    Options: type = type(None)
    default_chunk = 1

    @property
    def options(self) -> dict:
        """Option names and their defaults."""
        return _defaults(self.Options)

    def resolved(self, options: dict) -> dict:
        """``options`` over the defaults, as plain data (the context's cache key)."""
        return {**self.options, **options}

    def typed(self, options: dict):
        """``options`` over the defaults as this evaluator's ``Options`` dataclass."""
        return self.Options(**self.resolved(options))

    def check(self, spec, where: str = "spec") -> None:
        for a in spec.parameters:
            if a.name not in self.parameters:
                raise StudyError(f"{where}: unknown parameter {a.name!r} for evaluate = {self.name!r} "
                                 f"(expected one of {', '.join(self.parameters)})")
            for v in _values_of(a):
                self.parameters[a.name](a.name, v, where)
        for k in spec.options:
            if k not in self.options:
                raise StudyError(f"{where}: [evaluate]: unknown option {k!r} for {self.name!r} "
                                 f"(expected one of {', '.join(self.options)})")
        self.check_options(self.resolved(spec.options), where)

    def check_options(self, options: dict, where: str) -> None:
        pass

    def columns(self, options: dict) -> list[tuple[str, pa.DataType]]:
        raise NotImplementedError

    def context(self, options: dict):
        return _context(self.name, json.dumps(self.resolved(options), sort_keys=True))

    def build_context(self, options: dict):
        return None

    def point(self, ctx, params: dict, options: dict) -> dict:
        raise NotImplementedError


@functools.lru_cache(maxsize=4)
def _context(name: str, options_json: str):
    # One per worker process and study: the testbed model, wall basis or truth plant.
    return EVALUATORS[name].build_context(json.loads(options_json))


# ----------------------------------------------------------------------------- testbed
@dataclass(frozen=True)
class ModesOptions:
    """Options of the ``modes`` evaluator.

    Attributes
    ----------
    n_modes : int
        Lowest modes per point.
    labels : bool
        Label each mode (where its energy sits).
    testbed : dict or None
        Testbed parameter table (default: the default testbed).
    """

    n_modes: int = 20
    labels: bool = True
    testbed: dict | None = None


@dataclass(frozen=True)
class SensitivitiesOptions:
    """Options of the ``sensitivities`` evaluator (see :class:`ModesOptions`)."""

    n_modes: int = 12
    testbed: dict | None = None


@dataclass(frozen=True)
class PlantOptions:
    """Options of the ``plant`` evaluator.

    Attributes
    ----------
    n_modes : int
        Modes in the plant (0: every mode below Nyquist).
    n_freq : int
        Frequency grid points up to Nyquist.
    testbed : dict or None
        Testbed parameter table.
    """

    n_modes: int = 0
    n_freq: int = 2000
    testbed: dict | None = None


def _testbed_of(tb: dict | None):
    return Testbed() if not tb else testbed_from_dict(tb, source="[evaluate] testbed")


def _check_n_modes(n, where, lo=1):
    if isinstance(n, bool) or not isinstance(n, int) or n < lo:
        raise StudyError(f"{where}: [evaluate] n_modes must be an integer >= {lo}, got {n!r}")


def _walls(ctx, params):
    w = np.array(ctx.basis.walls_ref, float)
    for i, name in enumerate(WALLS):
        if name in params:
            w[i] = params[name]
    return w


@dataclass(frozen=True)
class WallContext:
    """What every point of a wall study shares: the testbed model at the reference walls
    and its wall basis (:func:`trussid.testbed.walls.wall_basis`)."""

    tbm: object
    basis: object


@dataclass(frozen=True)
class TestbedContext:
    """What every point of a plant study shares: the testbed parameters."""

    __test__ = False

    tb: object


@dataclass(frozen=True)
class CaseContext:
    """What every point of a fit study shares: the benchmark plant case."""

    case: object


class ModesEvaluator(Evaluator):
    """Natural frequencies [Hz] of the testbed at the point's walls, and each mode's label.

    Frequencies from the wall basis (:func:`trussid.testbed.walls.wall_modes`: only the
    strut terms of K and M change between designs); labels from where each mode's energy
    sits (:func:`trussid.testbed.labels.label_testbed_modes`) on the model at those walls.
    """

    name = "modes"
    parameters = {w: _check_wall for w in WALLS}
    Options = ModesOptions
    default_chunk = 20

    def check_options(self, options, where):
        o = self.typed(options)
        _check_n_modes(o.n_modes, where)
        if not isinstance(o.labels, bool):
            raise StudyError(f"{where}: [evaluate] labels must be true or false, got {o.labels!r}")
        _check_testbed(o.testbed, where)

    def columns(self, options):
        o = self.typed(options)
        cols = [(f"f{k + 1}", pa.float64()) for k in range(o.n_modes)]
        if o.labels:
            cols += [(f"label{k + 1}", pa.string()) for k in range(o.n_modes)]
        return cols

    def build_context(self, options):
        tbm = build_testbed(_testbed_of(self.typed(options).testbed))
        return WallContext(tbm=tbm, basis=wall_basis(tbm))

    def modes(self, ctx, walls, n):
        return wall_modes(ctx.basis, walls, n)

    def point(self, ctx, params, options):
        opts = self.typed(options)
        w = ctx.basis.check_walls(_walls(ctx, params))
        if not opts.labels:
            f, _ = self.modes(ctx, w, opts.n_modes)
            return {f"f{k + 1}": float(v) for k, v in enumerate(f)}
        # the design at these walls (a real model and its modes) for the labels
        design, modes = design_at_walls(ctx.tbm, ctx.basis, w, opts.n_modes)
        out = {f"f{k + 1}": float(v) for k, v in enumerate(modes.frequencies_hz)}
        labels = label_testbed_modes(design, modes).labels
        out.update({f"label{k + 1}": lab for k, lab in enumerate(labels)})
        return out


def _check_testbed(tb, where):
    if tb is not None and not isinstance(tb, dict):
        raise StudyError(f"{where}: [evaluate] testbed must be a parameter table or file name")
    if tb:
        try:
            _testbed_of(tb)
        except Exception as exc:  # ParameterError, ModelError...: the testbed's message names the item
            raise StudyError(f"{where}: [evaluate] testbed: {exc}") from None


class SensitivitiesEvaluator(ModesEvaluator):
    """Frequencies [Hz] and their analytic derivatives ``df_k/dt_i`` [Hz/m] at the walls
    (:func:`trussid.testbed.sensitivity.wall_sensitivities`)."""

    name = "sensitivities"
    Options = SensitivitiesOptions
    default_chunk = 20

    def check_options(self, options, where):
        o = self.typed(options)
        _check_n_modes(o.n_modes, where)
        _check_testbed(o.testbed, where)

    def columns(self, options):
        n = self.typed(options).n_modes
        return ([(f"f{k + 1}", pa.float64()) for k in range(n)]
                + [(f"dfdt{k + 1}_{i}", pa.float64()) for k in range(n) for i in range(N_STRUTS)])

    def point(self, ctx, params, options):
        n = self.typed(options).n_modes
        with warnings.catch_warnings():
            # a repeated pair is a property of the design, reported by its values
            warnings.simplefilter("ignore", RuntimeWarning)
            f, d = wall_sensitivities(ctx.basis, ctx.basis.check_walls(_walls(ctx, params)), n)
        out = {f"f{k + 1}": float(v) for k, v in enumerate(f)}
        out.update({f"dfdt{k + 1}_{i}": float(d[k, i]) for k in range(len(f)) for i in range(N_STRUTS)})
        return out


class PlantEvaluator(Evaluator):
    """Metrics of the testbed plant (command volts to accelerometer volts) at the point's
    walls and modal damping: per actuator channel, the peak gain over the three sensors and
    its frequency [Hz] on a grid of ``n_freq`` points up to Nyquist, and the H2 norm of the
    discrete channel (``sqrt(trace(B^T Wo B + D^T D))``, Wo the observability Gramian)."""

    name = "plant"
    parameters = {**{w: _check_wall for w in WALLS}, "damping": _check_damping}
    Options = PlantOptions
    default_chunk = 1

    def check_options(self, options, where):
        o = self.typed(options)
        if isinstance(o.n_modes, bool) or not isinstance(o.n_modes, int) or o.n_modes < 0:
            raise StudyError(f"{where}: [evaluate] n_modes must be 0 (all below Nyquist) or a positive "
                             f"integer, got {o.n_modes!r}")
        if isinstance(o.n_freq, bool) or not isinstance(o.n_freq, int) or o.n_freq < 10:
            raise StudyError(f"{where}: [evaluate] n_freq must be an integer >= 10, got {o.n_freq!r}")
        _check_testbed(o.testbed, where)

    def columns(self, options):
        return [(f"{k}_ch{c}", pa.float64()) for c in (1, 2, 3) for k in ("peak_gain", "peak_hz", "h2")]

    def build_context(self, options):
        return TestbedContext(tb=_testbed_of(self.typed(options).testbed))

    def point(self, ctx, params, options):
        import scipy.linalg as la

        opts = self.typed(options)
        walls = np.array(ctx.tb.struts.walls, float)
        for i, name in enumerate(WALLS):
            if name in params:
                walls[i] = params[name]
        tb = ctx.tb.with_walls(tuple(float(v) for v in walls))
        tp = testbed_plant(tb, n_modes=opts.n_modes or None, damping=params.get("damping"))
        d = tp.discrete
        A, B, C, D = (np.asarray(x, float) for x in (d.A, d.B, d.C, d.D))
        f = np.linspace(0.0, 0.5 / d.dt, opts.n_freq)[1:]
        H_all = frequency_response(d, f)  # (n_freq, p, m)
        Wo = la.solve_discrete_lyapunov(A.T, C.T @ C)
        out = {}
        for c in range(B.shape[1]):
            H = H_all[:, :, c]
            g = np.abs(H).max(axis=1)
            k = int(np.argmax(g))
            out[f"peak_gain_ch{c + 1}"] = float(g[k])
            out[f"peak_hz_ch{c + 1}"] = float(f[k])
            out[f"h2_ch{c + 1}"] = float(np.sqrt(B[:, c] @ Wo @ B[:, c] + D[:, c] @ D[:, c]))
        return out


# ----------------------------------------------------------------------------- identification
METHODS = ("plid-subspace", "plid-scratch", "plid-reduced", "n4sid")
NOISES = ("none", "60dB", "30dB", "12bit")


def _check_seed(name, v, where):
    _number(name, v, where, integer=True, minimum=0)


def _check_order(name, v, where):
    _number(name, v, where, integer=True, minimum=1)


def _check_samples(name, v, where):
    _number(name, v, where, integer=True, minimum=100)


def _check_method(name, v, where):
    if v not in METHODS:
        raise StudyError(f"{where}: parameter {name!r}: unknown method {v!r} (expected one of {', '.join(METHODS)})")


def _check_noise(name, v, where):
    if v not in NOISES and not (isinstance(v, str) and v.endswith("dB") and _is_float(v[:-2])):
        raise StudyError(f"{where}: parameter {name!r}: unknown noise {v!r} (expected none, 12bit or "
                         "an SNR such as '60dB')")


def _is_float(s):
    try:
        float(s)
    except ValueError:
        return False
    return True


@dataclass(frozen=True)
class IdentifyOptions:
    """Options of the ``identify`` evaluator: the plant, the defaults of the point's
    parameters, and how a fit is scored (:class:`IdentifyEvaluator`).

    Attributes
    ----------
    plant : str
        Benchmark plant (:data:`trussid.study.plants.PLANTS`).
    seed, noise, order, method, n_samples
        Defaults of the point parameters of the same names.
    n_validation : int
        Samples of the noise-free validation record.
    band, mode_band : list of float
        ``[low, high]`` [Hz] of the FRF error and of the scored structural modes.
    block_rows : list of int
        N4SID's block rows tried (the best by FRF error kept).
    """

    plant: str = "case_a"
    seed: int = 11
    noise: str = "60dB"
    order: int = 24
    method: str = "plid-subspace"
    n_samples: int = 10000
    n_validation: int = 4000
    band: list = field(default_factory=lambda: [30.0, 790.0])
    mode_band: list = field(default_factory=lambda: [30.0, 400.0])
    block_rows: list = field(default_factory=lambda: [20, 30, 40, 60, 80])


@dataclass(frozen=True)
class FitPoint:
    """The parameters of one fit (a point's values over the options' defaults)."""

    seed: int
    noise: str
    order: int
    method: str
    n_samples: int


@dataclass(frozen=True)
class FitScore:
    """The row of one fit (:func:`_score`); its fields are the evaluator's columns."""

    max_db: float
    rms_db: float
    sim_db: float
    freq_err_max_pct: float
    damp_err_max_pct: float
    damp_err_median_pct: float
    fit_seconds: float
    stable: bool
    block_rows: int = -1


class IdentifyEvaluator(Evaluator):
    """Simulate a record of a known plant, fit a model, score it against the truth.

    Parameters of a point: ``seed`` (record seed; the validation record uses ``seed +
    1000``), ``noise`` (``"60dB"``-style SNR, ``"12bit"`` converters or ``"none"``),
    ``order``, ``method`` (``plid-subspace``, ``plid-scratch``: :func:`plid.recipe.identify`
    with that start; ``plid-reduced``: :func:`plid.reduced.identify_reduced`; ``n4sid``:
    :func:`plid.subspace.n4sid` at each of ``block_rows``, the best by the true FRF RMS error
    reported — an oracle choice that favours the comparator), ``n_samples``.

    Scores (as in ``benchmarks/bench_plid_thesis.py``): FRF magnitude error max and RMS
    [dB] over ``band`` against the truth; simulation fit [dB] on the noise-free validation
    output (NaN when the model is unstable); largest modal frequency and damping errors [%]
    of the structural modes in ``mode_band``; fit seconds.
    """

    name = "identify"
    parameters = {"seed": _check_seed, "noise": _check_noise, "order": _check_order,
                  "method": _check_method, "n_samples": _check_samples}
    Options = IdentifyOptions
    default_chunk = 1

    def check_options(self, options, where):
        o = self.typed(options)
        if o.plant not in PLANTS:
            raise StudyError(f"{where}: [evaluate] plant {o.plant!r} is unknown "
                             f"(expected one of {', '.join(PLANTS)})")
        for k in self.parameters:
            self.parameters[k](k, getattr(o, k), f"{where}: [evaluate]")
        for k, b in (("band", o.band), ("mode_band", o.mode_band)):
            if not (isinstance(b, list) and len(b) == 2 and all(isinstance(x, (int, float)) for x in b)
                    and 0 <= b[0] < b[1]):
                raise StudyError(f"{where}: [evaluate] {k} must be [low, high] in Hz with low < high, got {b!r}")
        br = o.block_rows
        if not (isinstance(br, list) and br and all(isinstance(x, int) and x > 0 for x in br)):
            raise StudyError(f"{where}: [evaluate] block_rows must be a list of positive integers, got {br!r}")

    def columns(self, options):
        return [(k, pa.float64()) for k in ("max_db", "rms_db", "sim_db", "freq_err_max_pct",
                                            "damp_err_max_pct", "damp_err_median_pct", "fit_seconds")] + [
            ("stable", pa.bool_()), ("block_rows", pa.int64())]

    def build_context(self, options):
        return CaseContext(case=PLANTS[self.typed(options).plant]())

    def point(self, ctx, params, options):
        import time

        opts = self.typed(options)
        p = FitPoint(**{**{k: getattr(opts, k) for k in self.parameters}, **params})
        case = ctx.case
        ex = record(case, int(p.n_samples), p.noise, int(p.seed))
        val = record(case, int(opts.n_validation), "none", int(p.seed) + 1000)
        u, y, dt, n = ex.data.u, ex.data.y, case.plant.dt, int(p.order)
        if p.method == "n4sid":
            best = None
            for i in opts.block_rows:
                if i * y.shape[1] < n + y.shape[1]:
                    continue
                t0 = time.perf_counter()
                fit = n4sid(u, y, n, i, dt)
                m = replace(_score(fit.with_d, case, val, time.perf_counter() - t0, opts), block_rows=i)
                if best is None or m.rms_db < best.rms_db:
                    best = m
            if best is None:
                raise ValueError(f"no block_rows in {opts.block_rows} gives enough rows for order {n}")
            return asdict(best)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            # the fits' convergence warnings are about one record; the scores say how it went
            warnings.simplefilter("ignore", PLIDWarning)
            # progress=False: the study's own bar counts points; one per fit would garble it
            if p.method == "plid-reduced":
                ident = identify_reduced(u, y, n, dt, progress=False)
            else:
                ident = identify(u, y, n, dt, start=p.method.split("-", 1)[1], progress=False)
        out = _score(ident.model, case, val, time.perf_counter() - t0, opts, K=ident.K)
        sub = ident.provenance.subspace
        return asdict(replace(out, block_rows=sub.block_rows if sub is not None else -1))


def _score(model, case, val, seconds, opts: IdentifyOptions, K=None) -> FitScore:
    """The row of one fit, from :func:`trussid.plid.evaluate.compare` (the evaluator of
    ``trussid compare``, the demo and the benchmarks) on the validation record."""
    c = compare(model, case.plant, u=val.data.u, y=val.data.y, y_clean=val.y_clean, K=K,
                band=tuple(opts.band))
    lo, hi = opts.mode_band
    fe, de = [], []
    for r in c.poles:
        tf = r.true_frequency_hz
        if not r.matched or not lo < tf < hi:
            continue
        fe.append(abs(r.frequency_error_percent))
        de.append(abs(r.damping - r.true_damping) / r.true_damping * 100)
    nan = float("nan")
    return FitScore(max_db=float(c.frf.max_db), rms_db=float(c.frf.rms_db),
                    sim_db=float(c.simulation.overall) if c.stable else nan,
                    freq_err_max_pct=max(fe) if fe else nan, damp_err_max_pct=max(de) if de else nan,
                    damp_err_median_pct=float(np.median(de)) if de else nan, fit_seconds=float(seconds),
                    stable=bool(c.stable))


EVALUATORS = {e.name: e for e in (ModesEvaluator(), SensitivitiesEvaluator(), PlantEvaluator(),
                                  IdentifyEvaluator(), DeckModesEvaluator())}


def get_evaluator(name: str, where: str = "spec") -> Evaluator:
    """The evaluator called ``name``; a :class:`StudyError` naming it if there is none."""
    try:
        return EVALUATORS[name]
    except KeyError:
        raise StudyError(f"{where}: [study] evaluate {name!r} is unknown "
                         f"(expected one of {', '.join(EVALUATORS)})") from None


__all__ = ["Evaluator", "ModesEvaluator", "SensitivitiesEvaluator", "PlantEvaluator", "IdentifyEvaluator",
           "EVALUATORS", "get_evaluator", "METHODS", "NOISES", "WALLS"]
