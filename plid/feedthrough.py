"""A subspace prior with a direct term ``D`` for plants with a feed-through (issue 34).

An accelerometer driven by a force input responds at once: its discrete plant has ``D != 0``.
:func:`trussid.plid.subspace.subspace_prior` keeps N4SID's strictly proper model (``A, B`` of
the regression on ``[x; u]``, ``C`` of the regression on ``x`` alone). On such data that
``C`` is biased (the direct part of ``y`` is attributed to the state), and fitting ``B, D``
afterwards with that ``A, C`` fixed does not recover: measured on the testbed's accelerometer
plant (132 true states, 30- and 36-state models, 6000 samples, 60 dB SNR) its one-step ratio
stayed 4.2 dB (SIMO) and 1.4 dB (MIMO) below N4SID's own model with ``D``
(``benchmarks/results/plid_feedthrough.md``).

:func:`direct_prior` instead keeps N4SID's model *with* ``D`` (``A, B, C, D`` of the same state
sequence's least squares on ``[x; u]``), reflects unstable poles in, and refits ``B, D`` and the
initial state by output error (:func:`trussid.plid.subspace.output_error_fit`): the prior is
then N4SID-with-D's plant, which is what the demo used to add as a separate "N4SID with D"
candidate. :func:`trussid.plid.recipe.identify` uses it when its direct-term test (or the
caller) asks for ``D``; PLID then runs on ``y - D u`` from this prior.
"""

from __future__ import annotations

from trussid.plid._validate import as_2d
from trussid.plid.subspace import sweep_block_rows

__all__ = ["direct_prior"]

def direct_prior(u, y, n: int, dt: float, block_rows=None, patience: int | None = 1,
                 fits: dict | None = None):
    """An order-``n`` prior with a direct term: N4SID with ``D``, ``B, D`` refitted.

    Parameters
    ----------
    u : array (N, m)
        Inputs.
    y : array (N, p)
        Outputs.
    n : int
        Order.
    dt : float
        Sample time [s].
    block_rows : int or sequence of int, optional
        N4SID block rows to try (default
        :func:`trussid.plid.subspace.default_block_rows`), swept in increasing order and
        stopped after ``patience`` candidates that do not improve or one that gains under
        :data:`trussid.plid.subspace.MIN_GAIN_DB`, as
        :func:`trussid.plid.subspace.subspace_prior` does (one sweep for both:
        :func:`trussid.plid.subspace.sweep_block_rows`).
    patience : int or None
        See ``block_rows`` (None: try them all). Given ``block_rows`` are all tried.
    fits : dict, optional
        N4SID runs on the same data by block rows, shared with
        :func:`trussid.plid.subspace.subspace_prior` (its ``fits``).

    Returns
    -------
    model : control.StateSpace
        Stable, with ``D``; ``B, D`` fitted by output error with ``A, C`` fixed.
    choice : SubspaceChoice
        The block rows kept and every candidate's output-error ratio [dB] on the data.

    Examples
    --------
    An accelerometer-like plant (a mode at 50 Hz and a feed-through of 0.5) from 3000
    samples: the prior's direct term is the plant's.

    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import excitation, simulate
    >>> from trussid.plid.feedthrough import direct_prior
    >>> s = control.tf("s")
    >>> w = 2 * np.pi * 50.0
    >>> G = control.c2d(control.ss(0.5 * s**2 / (s**2 + 0.04 * w * s + w**2)), 1e-3)
    >>> u = excitation("white", 3000, fs=1000.0, seed=1)
    >>> model, choice = direct_prior(u, simulate(G, u), 2, 1e-3, block_rows=[20])
    >>> print(np.round(model.D, 3))
    [[0.5]]
    """
    u = as_2d(u, "u", finite=True)
    y = as_2d(y, "y", finite=True)
    return sweep_block_rows(u, y, n, dt, block_rows, direct=True, patience=patience,
                            fits=fits)
