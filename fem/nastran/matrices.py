"""Direct matrix input: DMIG matrices selected by the case control's K2GG and M2GG.

K2GG and M2GG add stiffness and mass on grid components (g-set) and so change the real modes;
K2PP, M2PP, B2PP (p-set, dynamic response only), B2GG (damping) and TF (transfer functions)
do not, and are listed as accepted. A DMIG that no K2GG/M2GG selects has no effect either.

DMIG is read from its raw fields: the header ``DMIG NAME 0 IFO TIN TOUT POLAR - NCOL`` and
column entries ``DMIG NAME GJ CJ - G1 C1 A1 B1 G2 C2 A2 B2 ...``; IFO 6 (symmetric, one
triangle given) and IFO 1 (square, must be symmetric) of real terms (TIN 1 or 2).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from trussid.fem.errors import ModelError
from trussid.fem.model import Model
from trussid.fem.nastran.cards import nastran_value
from trussid.fem.nastran.deck import BdfInfo, case_values

__all__ = ["DIRECT_MATRIX_REQUESTS"]

#: Case-control requests of direct matrices, and whether they change the real modes.
DIRECT_MATRIX_REQUESTS = {"K2GG": True, "M2GG": True, "B2GG": False, "K2PP": False, "M2PP": False,
                          "B2PP": False}


@dataclass
class _Dmig:
    """A DMIG matrix as its entries give it: form, type of terms and the terms
    ``(gj, cj, gi, ci, a)`` (column DOF, row DOF, value)."""

    ifo: int | None = None  # None: no header entry
    tin: int = 1
    terms: list = field(default_factory=list)


def _dmigs(bdf) -> dict[str, _Dmig]:
    """DMIG name -> :class:`_Dmig`, header and columns gathered."""
    out: dict[str, _Dmig] = {}
    for card in bdf.raw.get("DMIG", []):
        f = list(card.fields) + [""] * 9
        name = f[1]
        try:
            if f[2] in ("0", ""):
                dmig = out.setdefault(name, _Dmig())
                dmig.ifo, dmig.tin = int(f[3]), int(f[4] or 1)
                continue
            gj, cj = int(f[2]), int(f[3] or 0)
            vals = f[5:]
            terms = []
            for k in range(0, len(vals) - 3, 4):
                if not vals[k]:
                    continue
                terms.append((gj, cj, int(vals[k]), int(vals[k + 1] or 0), float(nastran_value(vals[k + 2]))))
        except (ValueError, TypeError):
            raise ModelError(f"{card.file}, line {card.line}: DMIG {name}: malformed entry "
                             f"({', '.join(card.fields[:6])})") from None
        out.setdefault(name, _Dmig()).terms.extend(terms)
    return out


def _selected(bdf, request: str) -> list:
    """[(scale, name), ...] of a case-control matrix request (``K2GG = 1.25*KAAX, KBB``; the
    first value given)."""
    values = case_values(bdf, request)
    if not values:
        return []
    out = []
    for item in values[0].split(","):
        item = item.strip()
        if not item:
            continue
        if "*" in item:
            scale, name = item.split("*", 1)
            try:
                out.append((float(nastran_value(scale)), name.strip()))
            except (TypeError, ValueError):
                raise ModelError(f"case control {request} = {values[0]}: scale {scale.strip()!r} is not a number") from None
        else:
            out.append((1.0, item))
    return out


def add_direct_matrices(bdf, model: Model, info: BdfInfo, dof_matrix) -> None:
    """Add the K2GG/M2GG DMIG matrices to ``model``; note what is accepted without effect.

    ``dof_matrix(dofs, card, eid) -> (grids, A)`` is the reader's map from (grid, component)
    DOFs to the grids' 6-DOF vectors (passed in: the reader imports this module).
    """
    dmigs = _dmigs(bdf)
    used = set()
    for request, changes_modes in DIRECT_MATRIX_REQUESTS.items():
        for scale, name in _selected(bdf, request):
            used.add(name)
            if not changes_modes:
                info.notes.append(f"{request} = {name}: a {'damping' if request.startswith('B') else 'p-set'} "
                                  f"matrix, no effect on the real modes: accepted, not used")
                continue
            if name not in dmigs:
                raise ModelError(f"case control {request} = {name}: no DMIG {name} is defined")
            if request == "M2GG" and info.wtmass != 1.0:
                raise ModelError(f"case control M2GG = {name} with PARAM,WTMASS,{info.wtmass:g}: whether the "
                                 f"direct mass is scaled by WTMASS differs between builds; give it in mass units "
                                 f"and WTMASS 1.0")
            _add_dmig(model, name, dmigs[name], scale, "K" if request == "K2GG" else "M", dof_matrix)
            info.notes.append(f"{request} = {name}: DMIG {name} added ({len(dmigs[name].terms)} terms"
                              f"{f', scaled by {scale:g}' if scale != 1.0 else ''})")
    idle = sorted(set(dmigs) - used)
    if idle:
        info.notes.append(f"DMIG {', '.join(idle[:5])}: not selected by K2GG or M2GG: no effect, not used")


def _add_dmig(model: Model, name: str, dmig: _Dmig, scale: float, kind: str, dof_matrix) -> None:
    card = f"DMIG {name}"
    ifo = dmig.ifo
    if ifo not in (1, 6):
        raise ModelError(f"{card}: form IFO = {ifo} is not supported (6 symmetric, 1 square)")
    if dmig.tin not in (1, 2):
        raise ModelError(f"{card}: complex terms (TIN = {dmig.tin}) are not supported")
    terms = dmig.terms
    dofs = list(dict.fromkeys([(gj, cj) for gj, cj, *_ in terms] + [(gi, ci) for _, _, gi, ci, _ in terms]))
    pos = {d: k for k, d in enumerate(dofs)}
    A = np.zeros((len(dofs), len(dofs)))
    for gj, cj, gi, ci, a in terms:
        i, j = pos[(gi, ci)], pos[(gj, cj)]
        A[i, j] += a
        if ifo == 6 and i != j:
            A[j, i] += a
    if ifo == 1 and not np.allclose(A, A.T, rtol=1e-9, atol=1e-12 * np.abs(A).max(initial=0.0)):
        raise ModelError(f"{card}: a square (IFO 1) matrix must be symmetric for real modes")
    grids, T = dof_matrix(dofs, card, 0)
    full = scale * (T.T @ (0.5 * (A + A.T)) @ T)
    model.add_matrices([0], [grids], **{kind: [full]}, label=card)
