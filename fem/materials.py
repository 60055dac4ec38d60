"""Isotropic linear-elastic materials (SI units)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from trussid.fem.errors import ModelError

__all__ = ["Material", "ALUMINIUM", "STEEL", "wave_speed_problem"]


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


#: Bar wave speeds sqrt(E / rho) of structural solids [m/s]: from soft polymers (~300) to
#: beryllium and ceramics (~1.3e4), with margin.
SOLID_WAVE_SPEED = (250.0, 2.0e4)

#: Length units of the consistent unit systems decks are written in (time in s): one
#: length unit in metres.
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254, "ft": 0.3048}


def wave_speed_problem(E: float, rho: float, wtmass: float = 1.0) -> str | None:
    """Why ``E`` and ``rho`` (in one unknown consistent unit system, ``rho`` already times
    ``wtmass``) cannot be a solid's, or None.

    ``sqrt(E / rho)`` is a speed in the system's length unit per second; a solid's lies in
    :data:`SOLID_WAVE_SPEED` m/s, i.e. in that range divided by the length unit in metres
    for one of :data:`LENGTH_UNITS`. A value in none of them (a deck in mm and MPa with the
    density left in kg/m^3 gives about 5) means the units are mixed. A deck that looks
    like inch-pound units with a weight density and no WTMASS (E 1e6-5e7 psi, RHO
    0.02-0.4 lbf/in^3) is named too: its masses are 386 times too large.
    """
    if not (E > 0 and rho > 0 and math.isfinite(E) and math.isfinite(rho)):
        return None
    c = math.sqrt(E / rho)
    lo, hi = SOLID_WAVE_SPEED
    ok = [u for u, metre in LENGTH_UNITS.items() if lo / metre <= c <= hi / metre]
    if not ok:
        ranges = ", ".join(f"{lo / m:.3g}-{hi / m:.3g} {u}/s" for u, m in LENGTH_UNITS.items())
        return (f"sqrt(E/rho) = {c:.3g} length units per second is no solid's wave speed in "
                f"any consistent unit system ({ranges}): E and the density are probably in "
                f"different systems (e.g. MPa with kg/m^3, where mm, N, s need t/mm^3)")
    if wtmass == 1.0 and 1e6 <= E <= 5e7 and 0.02 <= rho <= 0.4:
        return (f"E = {E:.3g} and density {rho:.3g} look like inch-pound units with a weight "
                f"density (lbf/in^3) and no PARAM,WTMASS: the masses are then 386 times too "
                f"large (NASTRAN decks in these units set PARAM,WTMASS,0.00259)")
    return None
