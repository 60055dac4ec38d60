"""The thesis's identification campaign on the simulated testbed (``trussid demo``)."""

from trussid._util.lazy import lazy_exports

_LAZY = {"DemoSettings": "demo", "run_demo": "demo", "DemoSummary": "summary"}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = list(_LAZY)
