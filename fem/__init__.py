"""Finite elements for 3-D frames: model, element matrices, assembly, modes, plants, I/O."""

from fem.errors import ModelError
from fem.materials import ALUMINIUM, STEEL, Material
from fem.model import Beams, Model, PointMasses, RigidBody, Springs, parse_dofs
from fem.sections import Section

__all__ = ["ALUMINIUM", "STEEL", "Beams", "Material", "Model", "ModelError", "PointMasses",
           "RigidBody", "Section", "Springs", "parse_dofs"]
