"""Parametric testbed geometry and solids (trimesh). Knows nothing of finite elements.

Names load on first use, so parameter sweeps that only need ``Testbed`` and
``testbed_layout`` never import trimesh.
"""

from geometry.errors import ParameterError
from trussid.lazy import lazy_exports

_LAZY = {
    "Testbed": "testbed", "StrutParams": "testbed", "AdapterParams": "testbed", "PztParams": "testbed",
    "UdfParams": "testbed", "BaseParams": "testbed", "AccelerometerParams": "testbed",
    "ElectricsParams": "testbed", "FilterParams": "testbed", "DaqParams": "testbed",
    "DampingParams": "testbed", "INCH": "testbed", "POUND": "testbed", "G0": "testbed",
    "Layout": "layout", "testbed_layout": "layout",
    "load_testbed": "params_toml", "save_testbed": "params_toml", "dumps_testbed": "params_toml",
    "Solid": "solids", "MassProperties": "solids", "mass_properties": "solids",
    "testbed_solids": "solids", "udf_rigid_body": "solids", "base_rigid_body": "solids",
    "Flywheel": "flywheel", "flywheel_solid": "flywheel", "flywheel_inertia": "flywheel",
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["ParameterError", *_LAZY]
