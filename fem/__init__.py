"""Finite elements for 3-D frames: model, element matrices, assembly, modes, plants, I/O.

The model-building names (``Model``, ``Section``, ``Material``...) load at once; the rest
(``assemble``, ``solve_modes``, ``read_bdf``, ``build_testbed``, ``testbed_plant``,
``render_mode``...) load on first use.
"""

from fem.errors import ModelError
from fem.materials import ALUMINIUM, STEEL, Material
from fem.model import Beams, Model, PointMasses, RigidBody, Springs, parse_dofs
from fem.sections import Section
from trussid.lazy import lazy_exports

_LAZY = {
    "System": "assembly", "assemble": "assembly",
    "Modes": "modal", "solve_modes": "modal",
    "solve_static": "static",
    "read_bdf": "nastran", "write_bdf": "nastran",
    "Wafer": "actuators", "strain_actuator_loads": "actuators",
    "Sensor": "sensors", "sensor_matrix": "sensors",
    "modal_plant": "plant", "residual_flexibility": "plant",
    "LabChain": "lab", "lab_plant": "lab",
    "TestbedModel": "testbed", "build_testbed": "testbed", "solve_testbed_modes": "testbed",
    "wall_basis": "testbed", "wall_modes": "testbed",
    "label_testbed_modes": "labels", "testbed_sensitivities": "sensitivity",
    "TestbedPlant": "testbed_plant", "testbed_plant": "testbed_plant",
    "render_mode": "render", "render_mode_gif": "render", "render_mode_grid": "render",
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["ALUMINIUM", "STEEL", "Beams", "Material", "Model", "ModelError", "PointMasses",
           "RigidBody", "Section", "Springs", "parse_dofs", *_LAZY]
