"""Closed-loop identification and adaptive LQG redesign (issue 27).

Plain functions over plain data, in the order a lab runs them:

- :mod:`.experiment`: closed-loop records on a discrete plant with a controller running and
  a dither added at the plant input (commands, what the D/A sent, measurements, dither);
- :mod:`.identify`: the plant from such records, PLID's direct method (prediction error with
  its noise model, the innovations predictor) and N4SID beside it;
- :mod:`.supervisor`: redesign from a closed-loop model, the checks a new controller must
  pass before it replaces the running one, and the adaptive loop.

Uses :mod:`trussid.plid` and :mod:`trussid.lqg` only; the campaign (``trussid demo --adapt``)
builds the truths and composes them.
"""

from trussid._util.lazy import lazy_exports

_LAZY = {
    "ClosedLoopRecord": "experiment", "run_loop": "experiment", "dither": "experiment",
    "closed_loop_record": "experiment", "trial_rms": "experiment",
    "ClosedLoopModel": "identify", "identify_plid": "identify", "identify_n4sid": "identify",
    "nearest_modes": "identify",
    "mode_damping": "supervisor",
    "SupervisorSettings": "supervisor", "Verdict": "supervisor", "redesign": "supervisor",
    "check_candidate": "supervisor", "check_fresh": "supervisor", "detect": "supervisor",
    "AdaptSettings": "supervisor", "AdaptRun": "supervisor", "Event": "supervisor",
    "adapt": "supervisor",
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = list(_LAZY)
