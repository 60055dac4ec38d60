"""Section and material properties of a group of elements as per-element arrays.

:class:`trussid.fem.Section` and :class:`trussid.fem.Material` describe one cross-section and
one material and insist on positive values. A model built from a deck or a parametric
description gives each element its own values, zeros included where NASTRAN allows them
(``J = 0``, a massless ``rho = 0``, a rod's unused second moments): :class:`SectionArrays`
and :class:`MaterialArrays` carry those, one value for every element or one per element,
as float arrays. They check what they can alone (numbers, one value or one per element,
known fields) and name the property on a bad one; whether a value is physical depends on
the element kind and the beam theory and is checked per element, naming it, when the model
is assembled (:func:`trussid.fem.elements.check_beam_properties`).

:meth:`trussid.fem.Model.add_beams` takes either form (and, for callers that build them, a
mapping with the same keys, read through :meth:`SectionArrays.of`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from trussid.fem.errors import ModelError
from trussid.fem.materials import Material
from trussid.fem.sections import Section

__all__ = ["SECTION_FIELDS", "MATERIAL_FIELDS", "SectionArrays", "MaterialArrays"]

#: Section fields, in the order the frame element takes them.
SECTION_FIELDS = ("A", "Iy", "Iz", "J", "Asy", "Asz")
#: Material fields.
MATERIAL_FIELDS = ("E", "G", "rho")


def _floats(value, owner: str, key: str) -> np.ndarray:
    """``value`` as a float array of at most one dimension; anything else names ``key``."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{owner}: {key} must be numbers, got {value!r}") from None
    if a.ndim > 1:
        raise ModelError(f"{owner}: {key} must be one value or one per element, got shape {a.shape}")
    return a


def _per_element(a: np.ndarray, n: int, owner: str, key: str) -> np.ndarray:
    if a.shape not in ((), (n,)):
        raise ModelError(f"{owner}: {key} has {a.shape[0]} values for {n} elements "
                         f"(give one value or one per element)")
    return np.broadcast_to(a, (n,)).copy()


def _from_mapping(cls, values: Mapping, required: tuple, name: str):
    owner = f"{cls.KIND} {name!r}"
    unknown = sorted(set(values) - set(cls.FIELDS))
    if unknown:
        raise ModelError(f"{owner}: unknown field(s) {', '.join(map(str, unknown))} "
                         f"(fields: {', '.join(cls.FIELDS)})")
    missing = [k for k in required if k not in values]
    if missing:
        raise ModelError(f"{owner}: {', '.join(missing)} not given")
    return cls(**values, name=name)


@dataclass(frozen=True)
class SectionArrays:
    """Section properties of a group of elements, each one value or one per element.

    Parameters
    ----------
    A : float or (n,) float
        Area [m^2].
    Iy, Iz : float or (n,) float
        Second moments of area about element y and z [m^4].
    J : float or (n,) float
        Torsion constant [m^4].
    Asy, Asz : float or (n,) float
        Shear areas for shear along element y and z [m^2]; ``inf`` for none (default).
    name : str
        The property's name in messages (e.g. ``"PBAR 12"``).

    Examples
    --------
    >>> from trussid.fem import Section, SectionArrays
    >>> s = SectionArrays(A=[1e-4, 2e-4], Iy=1e-9, Iz=1e-9, J=0.0, name="two rods")
    >>> s.per_element(2).Iy.shape                # one value, given to every element
    (2,)
    >>> s.per_element(3)
    Traceback (most recent call last):
    ...
    trussid.fem.errors.ModelError: section 'two rods': A has 2 values for 3 elements (give one value or one per element)
    >>> SectionArrays.of(Section.rectangle(0.02, 0.01)).A
    array(0.0002)
    """

    A: np.ndarray
    Iy: np.ndarray
    Iz: np.ndarray
    J: np.ndarray
    Asy: np.ndarray = math.inf
    Asz: np.ndarray = math.inf
    name: str = "section"

    KIND = "section"
    FIELDS = SECTION_FIELDS

    def __post_init__(self):
        for key in SECTION_FIELDS:
            object.__setattr__(self, key, _floats(getattr(self, key), f"section {self.name!r}", key))

    @classmethod
    def of(cls, section, name: str | None = None) -> "SectionArrays":
        """A :class:`SectionArrays` from a :class:`Section`, itself, or a mapping of its fields.

        Parameters
        ----------
        section : Section, SectionArrays or mapping
            A mapping needs ``A``, ``Iy``, ``Iz``, ``J``; ``Asy``, ``Asz`` default to ``inf``.
        name : str, optional
            Name for messages when ``section`` has none (a mapping).
        """
        if isinstance(section, SectionArrays):
            return section
        if isinstance(section, Section):
            return cls(*(getattr(section, k) for k in SECTION_FIELDS), name=section.name)
        if isinstance(section, Mapping):
            return _from_mapping(cls, section, ("A", "Iy", "Iz", "J"), name or "section")
        raise ModelError(f"a section must be a Section, SectionArrays or a mapping of "
                         f"{', '.join(SECTION_FIELDS)}, got {type(section).__name__}")

    def per_element(self, n: int) -> "SectionArrays":
        """Every field as ``(n,)`` floats; a field with another number of values is named.

        Parameters
        ----------
        n : int
            Number of elements.
        """
        owner = f"section {self.name!r}"
        return dataclasses.replace(self, **{k: _per_element(getattr(self, k), n, owner, k)
                                            for k in SECTION_FIELDS})


@dataclass(frozen=True)
class MaterialArrays:
    """Material of a group of elements, each property one value or one per element.

    Parameters
    ----------
    E : float or (n,) float
        Young's modulus [Pa].
    G : float or (n,) float
        Shear modulus [Pa].
    rho : float or (n,) float
        Density [kg/m^3].
    name : str
        The material's name in messages (e.g. ``"MAT1 3"``).

    Examples
    --------
    >>> from trussid.fem import ALUMINIUM, MaterialArrays
    >>> MaterialArrays.of(ALUMINIUM).per_element(3).rho
    array([2700., 2700., 2700.])
    """

    E: np.ndarray
    G: np.ndarray
    rho: np.ndarray
    name: str = "material"

    KIND = "material"
    FIELDS = MATERIAL_FIELDS

    def __post_init__(self):
        for key in MATERIAL_FIELDS:
            object.__setattr__(self, key, _floats(getattr(self, key), f"material {self.name!r}", key))

    @classmethod
    def of(cls, material, name: str | None = None) -> "MaterialArrays":
        """A :class:`MaterialArrays` from a :class:`Material`, itself, or a mapping of E, G, rho.

        Parameters
        ----------
        material : Material, MaterialArrays or mapping
            A mapping needs ``E``, ``G`` and ``rho``.
        name : str, optional
            Name for messages when ``material`` has none (a mapping).
        """
        if isinstance(material, MaterialArrays):
            return material
        if isinstance(material, Material):
            return cls(material.E, material.G, material.rho, name=material.name)
        if isinstance(material, Mapping):
            return _from_mapping(cls, material, MATERIAL_FIELDS, name or "material")
        raise ModelError(f"a material must be a Material, MaterialArrays or a mapping of "
                         f"{', '.join(MATERIAL_FIELDS)}, got {type(material).__name__}")

    def per_element(self, n: int) -> "MaterialArrays":
        """Every field as ``(n,)`` floats; a field with another number of values is named.

        Parameters
        ----------
        n : int
            Number of elements.
        """
        owner = f"material {self.name!r}"
        return dataclasses.replace(self, **{k: _per_element(getattr(self, k), n, owner, k)
                                            for k in MATERIAL_FIELDS})
