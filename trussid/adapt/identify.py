"""The plant from closed-loop records: PLID's direct method beside N4SID.

Direct method: the model maps what the D/A sent (``plant_input``) to the measurements, as
an open-loop identification would, ignoring the feedback. A prediction-error method with a
noise model (PLID identifies the predictor, i.e. the plant and its innovations gain) is
then consistent although the input is correlated with the past noise; a subspace method
that uses past inputs as instruments is not (N4SID's closed-loop bias; the adapt
feasibility study measured it in the dominant-mode damping at 10x and 30x the demo's sensor
noise).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import control
import numpy as np

from trussid.lqg.modal import modal_data
from trussid.plid.estimator import PLIDWarning
from trussid.plid.metrics import choose_predictor
from trussid.plid.recipe import identify
from trussid.plid.subspace import subspace_prior

from .experiment import ClosedLoopRecord


@dataclass
class ClosedLoopModel:
    """A plant model identified from a closed-loop record.

    Attributes
    ----------
    model : control.StateSpace
        Discrete, D/A names in, sensor names out, ``D = 0``.
    K : (n, p) float
        One-step predictor (innovations) gain: the noise model.
    method : str
    seconds, cpu_seconds : float
        Wall and CPU (process) time of the identification [s].
    info : dict
    """

    model: control.StateSpace
    K: np.ndarray
    method: str
    seconds: float
    cpu_seconds: float
    info: dict = field(default_factory=dict)


def _named(sys, rec: ClosedLoopRecord):
    return control.ss(sys.A, sys.B, sys.C, np.zeros((rec.measured.shape[1],
                                                     rec.plant_input.shape[1])),
                      rec.dt, inputs=list(rec.input_names), outputs=list(rec.output_names))


def identify_plid(rec: ClosedLoopRecord, order: int, *, block_rows=(40, 80)) -> ClosedLoopModel:
    """PLID direct method (:func:`trussid.plid.recipe.identify`: N4SID prior, one PLID
    pass, ``D = 0`` since the lab chain is strictly proper, unstable poles reflected, the
    predictor gain with the best one-step prediction of the record)."""
    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        # a pass losing positive definiteness warns; identify recovers and says so in info
        warnings.simplefilter("ignore", PLIDWarning)
        idn = identify(rec.plant_input, rec.measured, order, rec.dt,
                       block_rows=list(block_rows), direct=False, progress=False)
    info = {"provenance": idn.provenance}
    return ClosedLoopModel(_named(idn.model, rec), np.asarray(idn.K), "PLID (direct method)",
                           time.perf_counter() - t0, time.process_time() - c0, info)


def identify_n4sid(rec: ClosedLoopRecord, order: int, *, block_rows=(40, 80)) -> ClosedLoopModel:
    """N4SID on the same record (:func:`trussid.plid.subspace.subspace_prior`: PO-MOESP,
    ``D = 0``, stabilised, ``B`` refitted by output error; PLID's prior), its predictor gain
    chosen on the record as PLID's is."""
    t0, c0 = time.perf_counter(), time.process_time()
    model, pinfo = subspace_prior(rec.plant_input, rec.measured, order, rec.dt,
                                  block_rows=list(block_rows))
    K, _, kinfo = choose_predictor(model, rec.plant_input, rec.measured)
    return ClosedLoopModel(_named(model, rec), np.asarray(K), "N4SID (PO-MOESP, B refitted)",
                           time.perf_counter() - t0, time.process_time() - c0,
                           {"subspace": pinfo, "predictor": kinfo})


def nearest_modes(model, frequencies_hz) -> list:
    """The model's complex poles nearest each of ``frequencies_hz`` [Hz]:
    ``[(frequency [Hz], damping [-])]``."""
    md = modal_data(model.A, model.B, model.C, model.dt)
    up = np.flatnonzero(md.poles.imag > 0)
    out = []
    for f0 in frequencies_hz:
        k = up[np.argmin(np.abs(md.frequency_hz[up] - f0))]
        out.append((float(md.frequency_hz[k]), float(md.damping[k])))
    return out


__all__ = ["ClosedLoopModel", "identify_plid", "identify_n4sid", "nearest_modes"]
