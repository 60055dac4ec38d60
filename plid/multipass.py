"""The identification recipes under the module name they have always been imported from.

This module holds no code of its own. What it used to hold lives, one job per module, in
:mod:`trussid.plid.passes` (the pass schedule :class:`Pass`, :data:`SCRATCH_SCHEDULE`,
:func:`multipass`), :mod:`trussid.plid.provenance` (the result types :class:`Identification`,
:class:`Provenance`, :class:`Stabilised`, :class:`DirectTerm`), :mod:`trussid.plid.recipe`
(:func:`identify`, :func:`check_data`), :mod:`trussid.plid.reduced` (the reduced-order
search :func:`identify_reduced`, :class:`Candidate`, :func:`default_via`) and
:mod:`trussid.plid.frontend` (:func:`fit_model`, :data:`RECIPES`). Its names stay importable
from here for code written against it; new code imports from those modules or from
:mod:`trussid.plid`.
"""

from __future__ import annotations

from trussid.plid.frontend import RECIPES, fit_model
from trussid.plid.passes import SCRATCH_SCHEDULE, Pass, PassRecord, multipass
from trussid.plid.provenance import DirectTerm, Identification, Provenance, Stabilised
from trussid.plid.recipe import check_data, identify
from trussid.plid.reduced import Candidate, default_via, identify_reduced

__all__ = ["Pass", "multipass", "identify", "identify_reduced", "fit_model", "default_via",
           "Identification", "PassRecord", "Provenance", "Stabilised", "DirectTerm", "Candidate", "RECIPES",
           "SCRATCH_SCHEDULE", "check_data"]
