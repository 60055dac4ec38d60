"""Piezoelectric strain actuators as equivalent nodal loads (the thermal analogy).

A wafer bonded to a beam and driven at ``V`` volts has the free (induced) strain
``Lambda = d31 V / t_p`` along the beam. Treated like a thermal strain, it enters the beam's
strain energy through the cross term ``-int E eps_t eps dA dx``, so over a uniform element
from A to B the equivalent loads per volt are (Euler-Bernoulli, perfect bond)::

    axial:              -N_T at A,  +N_T at B          N_T  = sum E_p b t_p Lambda
    faces normal to y:  +M_Tz at A, -M_Tz at B (rz)    M_Tz = sum E_p b t_p Lambda y_w
    faces normal to z:  -M_Ty at A, +M_Ty at B (ry)    M_Ty = sum E_p b t_p Lambda z_w

where ``y_w``/``z_w`` is the signed distance of each wafer's mid-plane from the beam axis.
The wafers' own stiffness belongs in the element's (composite) section; these loads are
the actuation only. Applying them on every element of the bonded segment makes the
interior contributions cancel, so the segment may be meshed with any number of elements.

Wafers in phase (equal voltage) extend the segment; in anti-phase they bend it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from trussid.fem.elements import local_axes
from trussid.fem.errors import ModelError

__all__ = ["EPSILON_0", "Wafer", "strain_actuator_loads"]

#: Vacuum permittivity [F/m].
EPSILON_0 = 8.8541878128e-12


@dataclass(frozen=True)
class Wafer:
    """A rectangular piezoceramic wafer poled through its thickness.

    Parameters
    ----------
    width : float
        Across the beam [m].
    length : float
        Along the beam [m].
    thickness : float
        Poling direction [m].
    youngs_modulus : float
        Short-circuit modulus 1/s11^E [Pa].
    d31 : float
        Piezoelectric strain constant [m/V] (negative for PZT: a positive field along the
        poling contracts the wafer in plane).
    relative_permittivity : float
        eps33^T / eps0 [-].
    """

    width: float
    length: float
    thickness: float
    youngs_modulus: float
    d31: float
    relative_permittivity: float = 1700.0

    def __post_init__(self):
        for key in ("width", "length", "thickness", "youngs_modulus", "relative_permittivity"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value > 0):
                raise ModelError(f"PZT wafer: {key} must be positive, got {value!r}")
        if not (math.isfinite(self.d31) and self.d31 != 0):
            raise ModelError(f"PZT wafer: d31 must be finite and non-zero, got {self.d31!r}")

    @property
    def capacitance(self) -> float:
        """Free (stress-free) capacitance of one wafer, eps33^T A / t [F]."""
        return EPSILON_0 * self.relative_permittivity * self.width * self.length / self.thickness

    @property
    def blocked_force_per_volt(self) -> float:
        """Axial force a fully blocked wafer exerts per volt, E_p b t_p (d31 / t_p) [N/V]."""
        return self.youngs_modulus * self.width * self.d31


def strain_actuator_loads(model, element_ids, wafer: Wafer, offset: float, *,
                          face_axis: Literal["y", "z"] = "y",
                          arrangement: Literal["extension", "bending"] = "extension",
                          n_wafers: int = 2) -> np.ndarray:
    """Equivalent nodal loads per volt of wafers bonded over the given elements.

    Parameters
    ----------
    model : fem.Model
    element_ids : sequence of int
        Beam elements the wafers cover (one actuator: all are driven together).
    wafer : Wafer
    offset : float
        Distance from the beam axis to each wafer's mid-plane [m] (half the section depth
        plus half the wafer thickness for wafers on the faces).
    face_axis : {"y", "z"}
        Local axis normal to the bonded faces.
    arrangement : {"extension", "bending"}
        Wafers on opposite faces driven in phase (pure extension) or in anti-phase (pure
        bending; the wafer on the +``face_axis`` face gets +V).
    n_wafers : int
        Wafers in the actuator, in pairs on opposite faces (2 or 4 ...).

    Returns
    -------
    (6 n_nodes,) float
        Nodal forces and moments per volt [N/V, N m/V], global axes.
    """
    if face_axis not in ("y", "z"):
        raise ModelError(f"PZT actuator: face_axis must be 'y' or 'z', got {face_axis!r}")
    if arrangement not in ("extension", "bending"):
        raise ModelError(f"PZT actuator: arrangement must be 'extension' or 'bending', got {arrangement!r}")
    if n_wafers < 2 or n_wafers % 2:
        raise ModelError(f"PZT actuator: n_wafers must be a positive even number (pairs), got {n_wafers}")
    if not (math.isfinite(offset) and offset > 0):
        raise ModelError(f"PZT actuator: offset must be positive, got {offset!r}")
    beams = model.beams
    element_ids = np.atleast_1d(np.asarray(element_ids, dtype=np.int64))
    if element_ids.size == 0:
        raise ModelError("PZT actuator: no elements given (is there an adapter on this member?)")
    order = np.argsort(beams.ids)
    pos = np.searchsorted(beams.ids[order], element_ids)
    pos = np.minimum(pos, len(order) - 1) if len(order) else pos
    found = (len(order) > 0) & (beams.ids[order][pos] == element_ids) if len(order) else np.zeros(len(element_ids), bool)
    if not np.all(found):
        raise ModelError(f"PZT actuator: element {element_ids[~found][0]} is not a beam of the model")
    sel = order[pos]
    if arrangement == "bending" and np.any(beams.rod[sel]):
        e = element_ids[np.asarray(beams.rod[sel], bool)][0]
        raise ModelError(f"PZT actuator: element {e} is a rod (axial and torsion only): a "
                         f"bending pair needs a beam with bending stiffness")
    idx = model.index_of(beams.nodes[sel], what=lambda p: f"element {element_ids[p // 2]}")
    xyz = model.xyz
    _, R = local_axes(xyz[idx[:, 0]], xyz[idx[:, 1]], beams.orient[sel], element_ids)

    force = wafer.blocked_force_per_volt          # per wafer [N/V]
    local = np.zeros((len(sel), 2, 6))            # loads at ends A, B in local axes
    if arrangement == "extension":
        N = n_wafers * force
        local[:, 0, 0], local[:, 1, 0] = -N, N
    else:
        M = n_wafers * force * offset             # half the wafers at +offset, half at -offset, opposite V
        if face_axis == "y":
            local[:, 0, 5], local[:, 1, 5] = M, -M
        else:
            local[:, 0, 4], local[:, 1, 4] = -M, M
    # global = R^T local for the force and the moment triple at each end
    glob = np.einsum("nji,nekj->neki", R, local.reshape(len(sel), 2, 2, 3)).reshape(len(sel), 2, 6)
    f = np.zeros(6 * model.n_nodes)
    np.add.at(f, (6 * idx[:, :, None] + np.arange(6)).ravel(), glob.ravel())
    return f
