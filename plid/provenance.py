"""What an identification recipe returns: :class:`Identification` and its typed
:class:`Provenance` (with :class:`Stabilised` and :class:`DirectTerm`).

The recipes that fill them are :func:`trussid.plid.recipe.identify`,
:func:`trussid.plid.reduced.identify_reduced` and :func:`trussid.plid.frontend.fit_model`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import control
import numpy as np

from trussid.plid.canonical import ObserverBasis
from trussid.plid.closedloop import ClosedLoopFit
from trussid.plid.estimator import PLIDResult
from trussid.plid.subspace import SubspaceChoice

__all__ = ["Stabilised", "DirectTermTest", "DirectTerm", "Provenance", "Identification"]


@dataclass
class Stabilised:
    """Whether poles outside the unit circle were reflected in (:func:`trussid.plid.stabilise`)."""

    applied: bool = False
    reflected_poles: int = 0


@dataclass(frozen=True)
class DirectTermTest:
    """The held-out evidence for a direct term (:func:`trussid.plid.subspace.direct_term_test`).

    Attributes
    ----------
    held_out_nmse_without, held_out_nmse_with : float
        Normalised output-error power on the held-out segments, without and with D.
    margin : float
        Relative fall of that error needed to estimate D.
    folds : int
        Contiguous segments, each held out once.
    block_rows : int or None
        Block rows of the strictly proper N4SID prior whose ``A, C`` the test fixed (the
        first of the prior's sweep; None: the test ran on the identified model).
    """

    held_out_nmse_without: float
    held_out_nmse_with: float
    margin: float
    folds: int
    block_rows: int | None = None


@dataclass
class DirectTerm:
    """How the direct term D was decided, and its estimate.

    Attributes
    ----------
    mode : {"auto", True, False}
        What was asked for.
    estimated : bool
        Whether D was estimated (else D = 0, or the prior's D).
    test : DirectTermTest or None
        The held-out evidence, when the data decided.
    D, D_std : list of lists
        The direct term (p x m) and its standard errors (None when not estimated).
    start : str or None
        With D, the prior PLID started from (:func:`trussid.plid.recipe.identify`), and
        why when it is not N4SID's model with D.
    """

    mode: object
    estimated: bool
    test: DirectTermTest | None
    D: list
    D_std: list | None
    start: str | None = None


@dataclass
class Provenance:
    """How an identification was made: what the recipe ran, tried, chose and measured.

    Every field is None (or empty) when the recipe that made the model has no such step;
    :meth:`as_dict` keeps the steps that ran, for a JSON record.

    Attributes
    ----------
    subspace : SubspaceChoice or None
        The N4SID prior's choice of block rows (:func:`trussid.plid.subspace.subspace_prior`).
    subspace_seconds, recursion_seconds, recursion_cpu_seconds, seconds : float or None
        Wall seconds of the prior, wall and CPU seconds of the PLID recursion alone (the
        CPU figure stays meaningful on a loaded machine), wall seconds of the whole fit.
    passes : list of trussid.plid.passes.PassRecord
        The PLID passes run.
    stabilised : Stabilised or None
    direct : DirectTerm or None
    predictor : dict or None
        How the one-step predictor gain was chosen
        (:func:`trussid.plid.metrics.best_predictor`: ``chosen``, ``identification_ratio_db``,
        ``skip``, ...).
    structure : str or None
        An order that is not a multiple of the outputs: how the model was reduced to it.
    candidates, chosen, via : list, str, list or None
        :func:`identify_reduced`: every candidate's row, the winner's label, the via orders.
    K_source : str or None
        Where the returned predictor gain came from (:func:`fit_model`).
    closed_loop : trussid.plid.closedloop.ClosedLoopFit or None
        A closed-loop record (``identify(..., closed_loop=True)`` or a reference channel
        showing feedback): the consistent prior and refinement that replaced N4SID and
        PLID's passes, and why.
    warnings : list of str
        The estimator's warnings (:func:`fit_model`).
    """

    subspace: SubspaceChoice | None = None
    subspace_seconds: float | None = None
    passes: list = field(default_factory=list)
    recursion_seconds: float | None = None
    recursion_cpu_seconds: float | None = None
    stabilised: Stabilised | None = None
    direct: DirectTerm | None = None
    predictor: dict | None = None
    seconds: float | None = None
    structure: str | None = None
    candidates: list | None = None
    chosen: str | None = None
    via: list | None = None
    K_source: str | None = None
    closed_loop: ClosedLoopFit | None = None
    warnings: list = field(default_factory=list)

    def as_dict(self) -> dict:
        """The fields that are set (not None), in declaration order, nested dataclasses as
        they are (:func:`trussid._util.jsonio.json_safe` turns them into dicts)."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if getattr(self, f.name) is not None}


@dataclass
class Identification:
    """What :func:`identify` produced (``result`` and ``basis`` are None for a closed-loop
    record, where no PLID pass runs: ``provenance.closed_loop`` says why)."""

    result: PLIDResult | None
    model: control.StateSpace
    K: np.ndarray | None          # one-step predictor gain of ``model`` (original units)
    start: str
    basis: ObserverBasis | None
    R: np.ndarray
    prior: control.StateSpace | None
    provenance: Provenance = field(default_factory=Provenance)
