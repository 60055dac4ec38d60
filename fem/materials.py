"""Isotropic linear-elastic materials (SI units)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from trussid.fem.errors import ModelError

__all__ = ["Material", "ALUMINIUM", "STEEL"]


@dataclass(frozen=True)
class Material:
    """Isotropic material.

    Parameters
    ----------
    E : float
        Young's modulus [Pa].
    G : float
        Shear modulus [Pa].
    rho : float
        Density [kg/m^3].
    name : str
        Used in error messages and reports.
    """

    E: float
    G: float
    rho: float
    name: str = "material"

    def __post_init__(self):
        for key in ("E", "G", "rho"):
            value = getattr(self, key)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ModelError(f"material {self.name!r}: {key} must be positive and finite, got {value!r}")

    @classmethod
    def isotropic(cls, E: float, nu: float, rho: float, name: str = "material") -> "Material":
        """Material from Young's modulus [Pa], Poisson's ratio [-] and density [kg/m^3].

        Examples
        --------
        >>> from trussid.fem import Material
        >>> titanium = Material.isotropic(E=114e9, nu=0.34, rho=4430.0, name="Ti-6Al-4V")
        >>> print(f"G = E / (2 (1 + nu)) = {titanium.G / 1e9:.2f} GPa")
        G = E / (2 (1 + nu)) = 42.54 GPa
        """
        if not (-1.0 < nu < 0.5):
            raise ModelError(f"material {name!r}: Poisson's ratio must be in (-1, 0.5), got {nu!r}")
        return cls(E=float(E), G=float(E) / (2.0 * (1.0 + nu)), rho=float(rho), name=name)

    @property
    def nu(self) -> float:
        """Poisson's ratio implied by E and G [-]."""
        return self.E / (2.0 * self.G) - 1.0


#: 6061-T6 aluminium, the testbed's struts and adapters.
ALUMINIUM = Material.isotropic(68.9e9, 0.33, 2700.0, "aluminium 6061-T6")
#: Structural steel, the upper delta frame.
STEEL = Material.isotropic(200e9, 0.29, 7850.0, "steel")
