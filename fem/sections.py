"""Beam cross-sections: area, second moments, torsion constant and shear areas (SI units).

Local axes follow the element: x along the beam, y and z in the section. ``Iy`` is the
second moment about local y (bending in the x-z plane), ``Iz`` about local z (bending in
x-y). ``Asy``/``Asz`` are the effective shear areas for shear along local y/z
(Timoshenko); ``inf`` means no shear deformation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from trussid.fem.errors import ModelError

__all__ = ["Section"]


@dataclass(frozen=True)
class Section:
    """Cross-section properties.

    Parameters
    ----------
    A : float
        Area [m^2].
    Iy, Iz : float
        Second moments of area about local y and z [m^4].
    J : float
        Torsion constant [m^4].
    Asy, Asz : float
        Shear areas for shear along local y and z [m^2]; ``inf`` for none.
    name : str
        Used in error messages.
    """

    A: float
    Iy: float
    Iz: float
    J: float
    Asy: float = math.inf
    Asz: float = math.inf
    name: str = "section"

    def __post_init__(self):
        for key in ("A", "Iy", "Iz", "J", "Asy", "Asz"):
            value = getattr(self, key)
            if not isinstance(value, (int, float)) or math.isnan(value) or value <= 0:
                raise ModelError(f"section {self.name!r}: {key} must be positive, got {value!r}")
        for key in ("A", "Iy", "Iz", "J"):
            if math.isinf(getattr(self, key)):
                raise ModelError(f"section {self.name!r}: {key} must be finite")

    # ------------------------------------------------------------------ constructors
    @classmethod
    def general(cls, A, Iy, Iz, J, Asy=math.inf, Asz=math.inf, name="general") -> "Section":
        """A section from its properties directly."""
        return cls(float(A), float(Iy), float(Iz), float(J), float(Asy), float(Asz), name)

    @classmethod
    def circle(cls, r: float, nu: float = 0.3, name: str = "circle") -> "Section":
        """Solid circle of radius ``r`` [m]; Cowper shear factor 6(1+nu)/(7+6nu)."""
        _positive(name, r=r)
        A = math.pi * r**2
        I = math.pi * r**4 / 4.0
        k = 6.0 * (1 + nu) / (7 + 6 * nu)
        return cls(A, I, I, 2.0 * I, k * A, k * A, name)

    @classmethod
    def tube(cls, r_out: float, t: float, nu: float = 0.3, name: str = "tube") -> "Section":
        """Hollow circle: outer radius ``r_out`` [m], wall thickness ``t`` [m].

        Shear factor from Cowper (1966) for a hollow circle.

        Examples
        --------
        A 12.7 mm tube with a 1 mm wall: ``A = pi (r_o^2 - r_i^2)``, ``J = 2 I``:

        >>> from trussid.fem import Section
        >>> t = Section.tube(0.00635, 0.001)
        >>> print(f"A = {t.A * 1e6:.3f} mm^2, I = {t.Iy * 1e12:.1f} mm^4, J = {t.J * 1e12:.1f} mm^4")
        A = 36.757 mm^2, I = 633.5 mm^4, J = 1267.1 mm^4
        """
        _positive(name, r_out=r_out, t=t)
        if not t < r_out:
            raise ModelError(
                f"section {name!r}: wall thickness {t:.6g} m must be less than the outer radius {r_out:.6g} m"
            )
        r_in = r_out - t
        A = math.pi * (r_out**2 - r_in**2)
        I = math.pi * (r_out**4 - r_in**4) / 4.0
        m2 = (r_in / r_out) ** 2
        k = 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)
        return cls(A, I, I, 2.0 * I, k * A, k * A, name)

    @classmethod
    def rectangle(cls, b: float, h: float, nu: float = 0.3, name: str = "rectangle") -> "Section":
        """Solid rectangle, width ``b`` along local y and height ``h`` along local z [m].

        Torsion constant from Roark's series approximation (error < 0.5 %); Cowper shear
        factor 10(1+nu)/(12+11nu).

        Examples
        --------
        >>> from trussid.fem import Section
        >>> r = Section.rectangle(0.02, 0.01)         # b = 20 mm along local y, h = 10 mm along z
        >>> print(f"Iy = b h^3/12 = {r.Iy * 1e12:.1f} mm^4, Iz = h b^3/12 = {r.Iz * 1e12:.1f} mm^4")
        Iy = b h^3/12 = 1666.7 mm^4, Iz = h b^3/12 = 6666.7 mm^4
        """
        _positive(name, b=b, h=h)
        A = b * h
        k = 10 * (1 + nu) / (12 + 11 * nu)
        return cls(A, b * h**3 / 12.0, h * b**3 / 12.0, _rect_torsion(b, h), k * A, k * A, name)

    @classmethod
    def box(cls, b: float, h: float, t: float, nu: float = 0.3, name: str = "box") -> "Section":
        """Hollow rectangle of outer width ``b`` (y), height ``h`` (z), wall ``t`` [m].

        Torsion constant by Bredt's thin-wall formula on the wall mid-line; shear areas as
        the webs parallel to each shear direction.
        """
        _positive(name, b=b, h=h, t=t)
        if not 2 * t < min(b, h):
            raise ModelError(
                f"section {name!r}: wall thickness {t:.6g} m must be less than half the smaller side {min(b, h):.6g} m"
            )
        bi, hi = b - 2 * t, h - 2 * t
        A = b * h - bi * hi
        Iy = (b * h**3 - bi * hi**3) / 12.0
        Iz = (h * b**3 - hi * bi**3) / 12.0
        bm, hm = b - t, h - t
        J = 2.0 * t * bm**2 * hm**2 / (bm + hm)
        return cls(A, Iy, Iz, J, 2 * t * bm, 2 * t * hm, name)

    @classmethod
    def square_with_bore(cls, a: float, r_bore: float, name: str = "bored block") -> "Section":
        """Square block of side ``a`` [m] with a central round bore of radius ``r_bore`` [m].

        Area and second moments are exact. The torsion constant is the solid square's
        (0.1406 a^4) less the bore's polar moment, a close, slightly low estimate for a
        small bore; shear areas use 5/6 of the net area.
        """
        _positive(name, a=a, r_bore=r_bore)
        if not r_bore < a / 2:
            raise ModelError(
                f"section {name!r}: bore radius {r_bore:.6g} m must be less than half the side {a / 2:.6g} m"
            )
        A = a**2 - math.pi * r_bore**2
        I = a**4 / 12.0 - math.pi * r_bore**4 / 4.0
        J = _rect_torsion(a, a) - math.pi * r_bore**4 / 2.0
        return cls(A, I, I, J, 5 / 6 * A, 5 / 6 * A, name)


def _rect_torsion(b: float, h: float) -> float:
    a_, b_ = max(b, h), min(b, h)
    return a_ * b_**3 * (1.0 / 3.0 - 0.21 * (b_ / a_) * (1.0 - b_**4 / (12.0 * a_**4)))


def _positive(name: str, **values: float) -> None:
    for key, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ModelError(f"section {name!r}: {key} must be positive and finite, got {value!r}")
