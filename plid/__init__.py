"""Identification from input/output data: PLID, experiments, FRF estimates, metrics, grey-box.

Works on numpy arrays and ``control.StateSpace``; never imports :mod:`trussid.fem`,
:mod:`trussid.geometry` or :mod:`trussid.testbed`. Names load on first use.
"""

from trussid._util.lazy import lazy_exports
from trussid.plid.errors import DataError, IdentificationError

_LAZY = {
    "PLID": "estimator", "PLIDResult": "estimator",
    "identify": "recipe", "identify_reduced": "reduced", "Identification": "provenance",
    "ObserverBasis": "canonical", "rotation_basis": "bases",
    "n4sid": "subspace", "order_table": "order",
    "stabilise": "stability", "check_stability": "stability", "require_stable": "stability",
    "UnstableModelWarning": "stability", "balanced_truncation": "reduce",
    "IOData": "data", "read_data": "datafile", "write_data": "datafile",
    "read_uff": "uff", "write_uff": "uff",
    "ModeShapes": "data", "modal_table": "modal", "mac": "modal",
    "stabilisation": "stabilisation_diagram", "Stabilisation": "stabilisation_diagram",
    "pole_parameters": "modal", "pair_modes": "modal",
    "save_model": "modelfile", "load_model": "modelfile",
    "write_mat": "export", "python_code": "export", "write_python": "export",
    "excitation": "experiment", "run_experiment": "experiment", "simulate": "experiment",
    "h1": "frf", "h2": "frf", "stepped_sine": "frf", "FRF": "frf",
    "frequency_response": "frf",
    "prediction_ratio_db": "metrics", "frf_error": "metrics", "compare_poles": "metrics",
    "PoleMatch": "metrics",
    "simulation_fit": "metrics", "one_step_predict": "metrics", "predictor_gain": "metrics",
    "modal_parameters": "metrics", "choose_predictor": "metrics",
    "best_predictor": "metrics", "refine_predictor_gain": "metrics",
    "output_error_fit": "subspace", "direct_term_test": "subspace",
    "fit_parameters": "greybox", "fit_greybox": "greybox", "Constraint": "greybox",
    "identify_dc_motor": "dcmotor",
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["DataError", "IdentificationError", *_LAZY]
