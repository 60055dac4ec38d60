"""Where NASTRAN builds differ from the textbook elements of :mod:`trussid.fem.elements`, and
from each other: shear factors of PBARL/PBEAML shapes and element mass conventions, each
found on real NASTRAN output (the nastran-corpus diagnosis)."""

from __future__ import annotations

import numpy as np

from trussid.fem.elements import frame_matrices, local_axes
from trussid.fem.model import Model
from trussid.fem.nastran.deck import BdfInfo

__all__ = ['CONVENTIONS', 'ROD_SHEAR_FACTOR', 'BAR_SHEAR_FACTOR', 'nastran_mass_conventions']


#: Build conventions :func:`read_bdf` can follow (``conventions=``), default first.
CONVENTIONS = ("nx", "msc")

#: Shear factor K1 = K2 of a PBARL/PBEAML ROD by build conventions (see
#: :func:`trussid.fem.nastran.line_properties.line_properties`): 0.9 as NX/Simcenter and the newer MSC builds convert it, 6/7 as an MSC 2012 build did.
ROD_SHEAR_FACTOR = {"nx": 0.9, "msc": 6.0 / 7.0}

#: Shear factor of a PBARL/PBEAML BAR: 5/6, as NASTRAN converts it (MSC 2012.2 on a deep
#: CBEAM cantilever: bending modes 1e-4..7e-4 off with Cowper's 10(1+nu)/(12+11nu), 1e-6 with 5/6).
BAR_SHEAR_FACTOR = 5.0 / 6.0


def nastran_mass_conventions(bdf, model: Model, nodes, props: dict, info: BdfInfo) -> None:
    """NASTRAN's element mass where it differs from the textbook elements of fem.elements.

    ``nodes`` is the reader's node table (ids, coordinates). Each was found on real NASTRAN
    output (the nastran-corpus diagnosis) and is added as a
    correction, so that :mod:`trussid.fem.elements` stays the textbook formulation:

    * lumped CBEAM: the section's torsional inertia ``rho (I1 + I2) L / 2`` about the axis
      at each end (a CBAR's lumped mass has none);
    * coupled CBAR: no torsional inertia (the textbook element has ``rho (I1 + I2)``): done
      in :func:`trussid.fem.nastran.line_elements.add_bars`, exactly, by reading its
      structural mass as non-structural mass;
    * coupled CROD/CONROD: axial ``m [[5/12, 1/12], [1/12, 5/12]]``, transverse lumped
      ``m / 2`` (the textbook rod interpolates all three translations linearly);
    * coupled shear-flexible CBEAM (NX) and CBAR (MSC 2013 and the MSC NAS102 workshop run):
      the Euler-Bernoulli cubic translational mass without rotary inertia, on the
      shear-flexible stiffness (CBAR frames 1.7e-4 and 4.1e-4 off with the Timoshenko
      mass, 4e-7 and 7e-6 with this).
    """
    b = model.beams
    if len(b) == 0:
        return
    idx = nodes.index(b.nodes, "element", b.ids)
    xa, xb = nodes.xyz[idx[:, 0]], nodes.xyz[idx[:, 1]]
    d = xb - xa
    L = np.linalg.norm(d, axis=1)
    if not (L > 0).all():
        return  # zero-length elements are reported by the assembly, naming them
    e = d / L[:, None]
    cbeam = np.array([str(lbl).split()[0] in ("PBEAM", "PBEAML") for lbl in b.labels]) & ~b.rod
    if model.mass_formulation == "lumped":
        sel = cbeam & (b.rho * (b.Iy + b.Iz) > 0)
        if sel.any():
            polar = b.rho[sel] * (b.Iy[sel] + b.Iz[sel]) * L[sel] / 2.0
            tensor = polar[:, None, None] * e[sel][:, :, None] * e[sel][:, None, :]
            model.add_point_masses(np.concatenate([b.nodes[sel, 0], b.nodes[sel, 1]]), 0.0,
                                   inertia=np.concatenate([tensor, tensor]))
            info.notes.append(f"CBEAM lumped mass: torsional inertia rho (I1 + I2) L / 2 at each end "
                              f"({int(sel.sum())} elements), as NASTRAN")
        return
    cbar = np.array([str(lbl).split()[0] in ("PBAR", "PBARL") for lbl in b.labels]) & ~b.rod
    if cbar.any():
        info.notes.append(f"CBAR coupled mass: no torsional inertia ({int(cbar.sum())} elements: structural "
                          f"mass read as non-structural mass per length), as NASTRAN")
    rod = np.asarray(b.rod, bool)
    if rod.any():
        m = (b.rho[rod] * b.A[rod] + b.nsm[rod]) * L[rod]
        ee = e[rod][:, :, None] * e[rod][:, None, :]
        # NASTRAN minus textbook: axial 5/12 - 1/3 = 1/12, transverse 1/2 - 1/3 = 1/6 on the
        # diagonal, the opposite off the diagonal (total mass unchanged).
        B3 = m[:, None, None] * (ee / 12.0 + (np.eye(3) - ee) / 6.0)
        dM = np.zeros((int(rod.sum()), 12, 12))
        dM[:, :3, :3] = dM[:, 6:9, 6:9] = B3
        dM[:, :3, 6:9] = dM[:, 6:9, :3] = -B3
        model.add_matrices(b.ids[rod], b.nodes[rod], M=dM, label="CROD coupled mass (NASTRAN)")
        info.notes.append(f"CROD coupled mass: axial 5/12, 1/12 and lumped transverse mass "
                          f"({int(rod.sum())} rods), as NASTRAN")
    shear = (cbeam | cbar) & (np.isfinite(b.Asy) | np.isfinite(b.Asz))
    if model.beam_theory == "timoshenko" and shear.any():
        s = shear
        Ls, R = local_axes(xa[s], xb[s], b.orient[s], b.ids[s])
        args = (Ls, b.A[s], b.Iy[s], b.Iz[s], b.J[s], b.E[s], b.G[s], b.rho[s])
        kw = dict(nsm=b.nsm[s], Asy=b.Asy[s], Asz=b.Asz[s], R=R, mass="consistent")
        M_eb = frame_matrices(*args, **kw, theory="euler-bernoulli")[1]
        M_t = frame_matrices(*args, **kw, theory="timoshenko")[1]
        dM = M_eb - M_t
        dM = 0.5 * (dM + dM.transpose(0, 2, 1))
        model.add_matrices(b.ids[s], b.nodes[s], M=dM, label="CBAR/CBEAM coupled mass (NASTRAN)")
        info.notes.append(f"CBAR/CBEAM coupled mass with shear flexibility: Euler-Bernoulli cubic mass "
                          f"without rotary inertia ({int(s.sum())} elements), as NASTRAN")
