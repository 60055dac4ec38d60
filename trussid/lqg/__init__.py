"""Active damping from an identified model: discrete LQG design and closed-loop evaluation.

Works on identified models (:mod:`trussid.plid` files) and any discrete plant given as a
``control.StateSpace`` with named signals; never builds FE models itself.
"""

from trussid._util.lazy import lazy_exports

_LAZY = {
    "LQGDesign": "design", "design_lqg": "design", "controller_matrices": "design",
    "select_modes": "design", "lqr_for_damping": "design", "TargetMode": "design",
    "DesignCheck": "design", "verify_design": "design",
    "Loop": "loop", "restrict": "loop", "match_names": "loop", "check_pair": "loop",
    "closed_loop": "evaluate", "damping_table": "evaluate", "disk_margins": "evaluate",
    "h2_norm": "evaluate", "simulate_loop": "evaluate", "frequency_response": "evaluate",
    "ModeRow": "evaluate", "DampingTable": "evaluate", "Margin": "evaluate",
    "ChannelMargin": "evaluate", "DiskMargins": "evaluate", "LoopSimulation": "evaluate",
    "LoopSettings": "grading", "Thresholds": "grading", "THRESHOLDS": "grading",
    "plant_loop_settings": "grading", "LoopEvaluation": "grading", "evaluate_loop": "grading",
    "Checks": "grading", "check": "grading", "design_controller": "procedure",
    "design_procedure": "procedure",
    "Robustness": "grading", "robustness": "grading",
    "decentralised": "baselines", "tune_baseline": "baselines",
    "modal_data": "modal", "modal_truncation": "modal",
    "ControlError": "errors", "InputWeight": "shaping",
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = list(_LAZY)
