"""A flywheel: a solid disc on a coaxial solid shaft, as a trimesh solid, and its inertia.

The solid is the revolution of its half cross-section about the z axis (the shaft axis),
so it is one watertight mesh without boolean operations; the disc is centred on the shaft.
Its polar moment of inertia (about z, through the centre of mass) is what a DC-motor
identification needs as J. :func:`flywheel_inertia_closed_form` gives the same number for
the ideal (round) solid: disc ``m_d r_d^2 / 2`` plus the shaft outside the disc
``m_s r_s^2 / 2``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

from trussid.geometry.errors import ParameterError

__all__ = [
    "STEEL_DENSITY",
    "Flywheel",
    "flywheel_inertia",
    "flywheel_inertia_closed_form",
    "flywheel_solid",
    "parse_flywheel",
]

#: Density of steel [kg/m^3], the default material.
STEEL_DENSITY = 7850.0


@dataclass(frozen=True)
class Flywheel:
    """Dimensions [m] and density [kg/m^3] of a disc-and-shaft flywheel."""

    disc_radius: float
    disc_thickness: float
    shaft_radius: float
    shaft_length: float
    density: float = STEEL_DENSITY

    def __post_init__(self):
        for name in ("disc_radius", "disc_thickness", "shaft_radius", "shaft_length",
                     "density"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"flywheel.{name} must be a positive number, got {v!r}")
        if self.shaft_radius >= self.disc_radius:
            raise ParameterError(
                f"flywheel.shaft_radius ({self.shaft_radius:g} m) must be smaller than "
                f"flywheel.disc_radius ({self.disc_radius:g} m)"
            )
        if self.shaft_length < self.disc_thickness:
            raise ParameterError(
                f"flywheel.shaft_length ({self.shaft_length:g} m) must be at least "
                f"flywheel.disc_thickness ({self.disc_thickness:g} m)"
            )


def flywheel_solid(fly: Flywheel, sections: int = 256) -> trimesh.Trimesh:
    """Watertight trimesh solid of the flywheel, shaft along z, centred at the origin.

    Parameters
    ----------
    fly : Flywheel
    sections : int
        Facets around the axis. The polygonal disc is slightly smaller than the round
        one: its polar inertia is low by about ``(2 pi / sections)^2 / 3`` (2e-4 for 256).

    Returns
    -------
    trimesh.Trimesh
        With ``density`` set, so ``mass`` and ``moment_inertia`` are in kg and kg m^2.
    """
    if not isinstance(sections, (int, np.integer)) or sections < 8:
        raise ParameterError(f"flywheel sections must be an integer >= 8, got {sections!r}")
    rd, td = fly.disc_radius, fly.disc_thickness
    rs, ls = fly.shaft_radius, fly.shaft_length
    # Half cross-section (radius, z), from the axis at the bottom to the axis at the top.
    profile = [(0.0, -ls / 2), (rs, -ls / 2)]
    if ls > td:
        profile.append((rs, -td / 2))
    profile += [(rd, -td / 2), (rd, td / 2)]
    if ls > td:
        profile.append((rs, td / 2))
    profile += [(rs, ls / 2), (0.0, ls / 2)]
    # revolve() drops duplicate consecutive points only if exact; the list has none.
    mesh = trimesh.creation.revolve(np.array(profile), sections=int(sections))
    mesh.density = fly.density
    if not mesh.is_volume:  # would mean a bug in the profile, not bad input
        raise RuntimeError("flywheel solid is not a closed volume")
    return mesh


def flywheel_inertia(fly: Flywheel, sections: int = 256) -> float:
    """Polar moment of inertia [kg m^2] about the shaft axis, from the trimesh solid."""
    mesh = flywheel_solid(fly, sections)
    return float(mesh.moment_inertia[2, 2])


def flywheel_inertia_closed_form(fly: Flywheel) -> float:
    """Polar moment of inertia [kg m^2] of the ideal round disc and shaft."""
    rd, td = fly.disc_radius, fly.disc_thickness
    rs, ls = fly.shaft_radius, fly.shaft_length
    m_disc = fly.density * math.pi * rd**2 * td
    m_shaft_out = fly.density * math.pi * rs**2 * (ls - td)
    return 0.5 * m_disc * rd**2 + 0.5 * m_shaft_out * rs**2


def parse_flywheel(text: str) -> Flywheel:
    """``"disc_radius,disc_thickness,shaft_radius,shaft_length[,density]"`` -> Flywheel.

    Lengths in metres, density in kg/m^3 (default steel, 7850).
    """
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) not in (4, 5):
        raise ParameterError(
            "flywheel dimensions must be 'disc_radius,disc_thickness,shaft_radius,"
            f"shaft_length[,density]' (4 or 5 numbers), got {text!r}"
        )
    names = ("disc_radius", "disc_thickness", "shaft_radius", "shaft_length", "density")
    vals = []
    for name, p in zip(names, parts):
        try:
            vals.append(float(p))
        except ValueError:
            raise ParameterError(f"flywheel.{name} is not a number: {p!r}") from None
    return Flywheel(*vals)
