"""Finite elements for 3-D frames: model, element matrices, assembly, modes, plants, I/O.

Generic: nothing here knows of the thesis testbed (that is :mod:`trussid.testbed`). The
model-building names (``Model``, ``Section``, ``Material``...) load at once; the rest
(``assemble``, ``solve_modes``, ``read_bdf``, ``render_mode``...) load on first use.
"""

from trussid._util.lazy import lazy_exports
from trussid.fem.errors import ModelError
from trussid.fem.materials import ALUMINIUM, STEEL, Material
from trussid.fem.model import Beams, Model, PointMasses, RigidBody, Springs, parse_dofs
from trussid.fem.properties import MaterialArrays, SectionArrays
from trussid.fem.sections import Section

_LAZY = {
    "System": "assembly", "assemble": "assembly",
    "Modes": "modal", "solve_modes": "modal",
    "solve_static": "static",
    "read_bdf": "nastran", "write_bdf": "nastran",
    "write_op2": "op2", "read_op2_modes": "op2", "guyan": "reduction",
    "Wafer": "actuators", "strain_actuator_loads": "actuators",
    "Sensor": "sensors", "sensor_matrix": "sensors",
    "modal_plant": "plant", "residual_flexibility": "plant",
    "IOSpec": "iospec", "read_io": "iospec", "io_loads": "iospec", "io_plant": "iospec",
    "Decoration": "render", "decorations_from_solids": "render", "mode_scene": "render",
    "render_mode": "render", "render_mode_gif": "render", "render_mode_grid": "render",
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["ALUMINIUM", "STEEL", "Beams", "Material", "MaterialArrays", "Model", "ModelError",
           "PointMasses", "RigidBody", "Section", "SectionArrays", "Springs", "parse_dofs", *_LAZY]
