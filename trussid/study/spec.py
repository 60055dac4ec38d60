"""Study specifications: what varies, how it is sampled, what is computed per point.

A study is plain data (:class:`StudySpec`), written in TOML or built in Python::

    [study]
    name = "wall-study"
    evaluate = "modes"          # modes | sensitivities | plant | identify | deck (any deck)
    chunk = 20                  # points per task (engine granularity; no effect on results)

    [evaluate]                  # options of the evaluator (evaluators.EVALUATORS)
    n_modes = 20

    [sample]
    method = "grid"             # grid | lhs | random | list
    # n = 200, seed = 1         # lhs and random

    [parameters]
    wall0 = {low = 0.0005, high = 0.0010, num = 5}   # grid axis (numpy.linspace)
    wall1 = {values = [0.0006, 0.0008]}              # grid axis, explicit
    wall2 = 0.0008                                   # fixed
    # lhs / random: {low = ..., high = ...}; list: {values = [...]} of one common length

Points are numbered 0..N-1 in a fixed order (grid: ``itertools.product`` of the axes in the
order written, last fastest); that number is the ``point`` column of the results. The spec
hash (:func:`spec_hash`) covers everything that changes results (evaluator, options,
sampling, parameters) and nothing that does not (name, chunk size), so that a run on an
existing output can tell "same study, resume" from "another study, refuse".
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from trussid.study.errors import StudyError
from trussid.study.evaluators import get_evaluator

SAMPLERS = ("grid", "lhs", "random", "list")


@dataclass(frozen=True)
class Axis:
    """How one parameter varies.

    Exactly one of ``values`` (explicit values, grid or list) or ``low``/``high`` (with
    ``num`` for a grid; a range for lhs/random) is set; ``fixed`` marks a constant.
    """

    name: str
    values: tuple | None = None
    low: float | None = None
    high: float | None = None
    num: int | None = None

    @property
    def fixed(self) -> bool:
        return self.values is not None and len(self.values) == 1 and self.low is None

    def table(self) -> dict:
        """The axis as its TOML table (the keys that are set)."""
        return {k: v for k, v in (("values", None if self.values is None else list(self.values)),
                                  ("low", self.low), ("high", self.high), ("num", self.num))
                if v is not None}


@dataclass(frozen=True)
class StudySpec:
    """A study: evaluator, its options, the parameters and how they are sampled.

    Attributes
    ----------
    evaluate : str
        Name of the per-point computation (``modes``, ``sensitivities``, ``plant``,
        ``identify``; :data:`trussid.study.evaluators.EVALUATORS`).
    parameters : tuple of Axis
    sample : str
        ``grid``, ``lhs`` (Latin hypercube, scipy.stats.qmc), ``random`` (uniform) or ``list``.
    n : int or None
        Points drawn by ``lhs`` / ``random``.
    seed : int
        Seed of ``lhs`` / ``random``.
    options : dict
        Evaluator options (e.g. ``n_modes``, ``testbed`` parameter file).
    name : str
    chunk : int or None
        Points per engine task; default chosen by the evaluator.
    """

    evaluate: str
    parameters: tuple
    sample: str = "grid"
    n: int | None = None
    seed: int = 0
    options: dict = field(default_factory=dict)
    name: str = "study"
    chunk: int | None = None

    def _axes(self) -> dict:
        return {a.name: a.table() for a in self.parameters}

    def _sample(self) -> dict:
        samp = {"method": self.sample}
        if self.sample in ("lhs", "random"):
            samp.update(n=self.n, seed=self.seed)
        return samp

    def identity(self) -> dict:
        """The part of the spec that determines results (what :func:`spec_hash` hashes)."""
        return {"evaluate": self.evaluate, "options": _plain(self.options), "sample": self._sample(),
                "parameters": self._axes()}

    def to_dict(self) -> dict:
        """A TOML/JSON-ready dict that :func:`spec_from_dict` reads back."""
        study = {"name": self.name, "evaluate": self.evaluate}
        if self.chunk is not None:
            study["chunk"] = self.chunk
        params = {a.name: (a.values[0] if a.fixed else a.table()) for a in self.parameters}
        return {"study": study, "evaluate": _plain(self.options), "sample": self._sample(), "parameters": params}


def _plain(x):
    """JSON-canonical form of options (tuples as lists, numpy scalars as Python)."""
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in sorted(x.items())}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    return x


def spec_hash(spec: StudySpec) -> str:
    """SHA-256 (hex, 16 characters) of :meth:`StudySpec.identity` as canonical JSON."""
    blob = json.dumps(spec.identity(), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


# ----------------------------------------------------------------------------- reading
def _axis(name: str, raw, where: str) -> Axis:
    if isinstance(raw, (int, float, str, bool)):
        return Axis(name, values=(raw,))
    if isinstance(raw, (list, tuple)):
        raw = {"values": list(raw)}
    if not isinstance(raw, dict):
        raise StudyError(f"{where}: parameter {name!r} must be a value, a list or a table, got {raw!r}")
    unknown = set(raw) - {"values", "low", "high", "num"}
    if unknown:
        raise StudyError(f"{where}: parameter {name!r}: unknown key {sorted(unknown)[0]!r} "
                         "(expected values, or low/high[/num])")
    if "values" in raw:
        if set(raw) != {"values"}:
            raise StudyError(f"{where}: parameter {name!r}: give either values or low/high, not both")
        vals = raw["values"]
        if not isinstance(vals, (list, tuple)) or len(vals) == 0:
            raise StudyError(f"{where}: parameter {name!r} has an empty list of values")
        return Axis(name, values=tuple(_plain(v) for v in vals))
    if "low" not in raw or "high" not in raw:
        raise StudyError(f"{where}: parameter {name!r} needs values, or both low and high")
    try:
        lo, hi = float(raw["low"]), float(raw["high"])
    except (TypeError, ValueError):
        raise StudyError(f"{where}: parameter {name!r}: low and high must be numbers") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or not lo <= hi:
        raise StudyError(f"{where}: parameter {name!r} has an empty range [{lo:g}, {hi:g}]")
    num = raw.get("num")
    if num is not None and (not isinstance(num, int) or isinstance(num, bool) or num < 1):
        raise StudyError(f"{where}: parameter {name!r}: num must be a positive integer, got {num!r}")
    if num is not None and num > 1 and lo == hi:
        raise StudyError(f"{where}: parameter {name!r} has an empty range [{lo:g}, {hi:g}] for {num} levels")
    return Axis(name, low=lo, high=hi, num=num)


def spec_from_dict(d: dict, where: str = "spec") -> StudySpec:
    """Build and validate a :class:`StudySpec` from the TOML layout (module docstring)."""
    if not isinstance(d, dict):
        raise StudyError(f"{where}: a study must be a table")
    unknown = set(d) - {"study", "evaluate", "sample", "parameters"}
    if unknown:
        raise StudyError(f"{where}: unknown section [{sorted(unknown)[0]}] "
                         "(expected [study], [evaluate], [sample], [parameters])")
    st = d.get("study", {})
    bad = set(st) - {"name", "evaluate", "chunk"}
    if bad:
        raise StudyError(f"{where}: [study]: unknown key {sorted(bad)[0]!r} (expected name, evaluate, chunk)")
    if "evaluate" not in st:
        raise StudyError(f"{where}: [study] needs evaluate = one of modes, sensitivities, plant, identify, "
                         "deck")
    chunk = st.get("chunk")
    if chunk is not None and (not isinstance(chunk, int) or isinstance(chunk, bool) or chunk < 1):
        raise StudyError(f"{where}: [study] chunk must be a positive integer, got {chunk!r}")
    samp = dict(d.get("sample", {"method": "grid"}))
    method = samp.pop("method", "grid")
    if method not in SAMPLERS:
        raise StudyError(f"{where}: [sample] method {method!r} is unknown (expected one of {', '.join(SAMPLERS)})")
    n, seed = samp.pop("n", None), samp.pop("seed", 0)
    if samp:
        raise StudyError(f"{where}: [sample]: unknown key {sorted(samp)[0]!r} (expected method, n, seed)")
    params = d.get("parameters", {})
    if not isinstance(params, dict) or not params:
        raise StudyError(f"{where}: [parameters] is empty: a study needs at least one parameter")
    axes = tuple(_axis(k, v, where) for k, v in params.items())
    spec = StudySpec(evaluate=str(st["evaluate"]), parameters=axes, sample=method, n=n,
                     seed=seed, options=dict(d.get("evaluate", {})), name=str(st.get("name", "study")),
                     chunk=chunk)
    validate(spec, get_evaluator(spec.evaluate, where), where)
    return spec


def load_spec(path) -> StudySpec:
    """Read a study from a TOML file (:func:`spec_from_dict`)."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            raw = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{path}: not valid TOML: {exc}") from None
    return spec_from_dict(raw, where=str(path))


def validate(spec: StudySpec, evaluator, where: str = "spec") -> None:
    """Check sampling against the axes, and parameters and options against the evaluator."""
    if spec.sample in ("lhs", "random"):
        if not isinstance(spec.n, int) or isinstance(spec.n, bool) or spec.n < 1:
            raise StudyError(f"{where}: [sample] {spec.sample} needs n = a positive number of points, got {spec.n!r}")
        if not isinstance(spec.seed, int) or isinstance(spec.seed, bool):
            raise StudyError(f"{where}: [sample] seed must be an integer, got {spec.seed!r}")
        for a in spec.parameters:
            if a.num is not None or (a.values is not None and not a.fixed):
                raise StudyError(f"{where}: parameter {a.name!r}: {spec.sample} sampling takes low/high ranges "
                                 "(or a single fixed value)")
    elif spec.sample == "grid":
        for a in spec.parameters:
            if a.low is not None and a.num is None:
                raise StudyError(f"{where}: parameter {a.name!r}: a grid axis needs num (levels) with low/high")
    elif spec.sample == "list":
        lens = {len(a.values) for a in spec.parameters if a.values is not None and not a.fixed}
        if any(a.low is not None for a in spec.parameters):
            bad = next(a for a in spec.parameters if a.low is not None)
            raise StudyError(f"{where}: parameter {bad.name!r}: list sampling takes values, not low/high")
        if len(lens) > 1:
            raise StudyError(f"{where}: list sampling needs all value lists of one length, got {sorted(lens)}")
    evaluator.check(spec, where)


# ----------------------------------------------------------------------------- sampling
def sample_points(spec: StudySpec) -> tuple[list[str], list[tuple]]:
    """Parameter names and the value tuple of every point, in point order."""
    names = [a.name for a in spec.parameters]
    if spec.sample == "grid":
        levels = [list(a.values) if a.values is not None else
                  [float(v) for v in np.linspace(a.low, a.high, a.num)] for a in spec.parameters]
        return names, list(itertools.product(*levels))
    if spec.sample == "list":
        n = max(len(a.values) for a in spec.parameters)
        cols = [list(a.values) * n if a.fixed else list(a.values) for a in spec.parameters]
        return names, list(zip(*cols))
    ranged = [a for a in spec.parameters if not a.fixed]
    if spec.sample == "lhs":
        from scipy.stats import qmc

        unit = qmc.LatinHypercube(d=len(ranged), seed=np.random.default_rng(spec.seed)).random(spec.n)
    else:
        unit = np.random.default_rng(spec.seed).random((spec.n, len(ranged)))
    cols, j = [], 0
    for a in spec.parameters:
        if a.fixed:
            cols.append([a.values[0]] * spec.n)
        else:
            cols.append([float(v) for v in a.low + unit[:, j] * (a.high - a.low)])
            j += 1
    return names, list(zip(*cols))


__all__ = ["Axis", "StudySpec", "StudyError", "spec_hash", "spec_from_dict", "load_spec", "validate",
           "sample_points", "SAMPLERS"]
