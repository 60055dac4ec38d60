"""The testbed's parametric description and its solids (trimesh). Knows nothing of FE.

:class:`Testbed` is the validated, provenance-tagged parameter set of the thesis testbed
(structure, transducers, electronics, acquisition, damping); :class:`LabSpec` (:mod:`.lab`)
is the lab around it (converters, electronics, filters, sensors), the one home of the lab's
numbers; :mod:`.layout` turns the testbed into node positions, :mod:`.solids` into solids
and mass properties. Names load on first use,
so parameter sweeps that only need ``Testbed`` and ``testbed_layout`` never import trimesh.
"""

from trussid._util.lazy import lazy_exports
from trussid.geometry.errors import ParameterError

_LAZY = {
    "Testbed": "spec", "StrutParams": "spec", "AdapterParams": "spec", "PztParams": "spec",
    "UdfParams": "spec", "BaseParams": "spec", "DampingParams": "spec", "INCH": "spec",
    "POUND": "spec",
    "LabSpec": "lab", "AccelerometerParams": "lab", "ElectricsParams": "lab",
    "FilterParams": "lab", "DaqParams": "lab", "G0": "lab",
    "Layout": "layout", "testbed_layout": "layout",
    "load_testbed": "params_toml", "save_testbed": "params_toml", "dumps_testbed": "params_toml",
    "Solid": "solids", "MassProperties": "solids", "mass_properties": "solids",
    "testbed_solids": "solids", "udf_rigid_body": "solids", "base_rigid_body": "solids",
    "Flywheel": "flywheel", "flywheel_solid": "flywheel", "flywheel_inertia": "flywheel",
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["ParameterError", *_LAZY]
