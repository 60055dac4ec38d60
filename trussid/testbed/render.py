"""The testbed drawn with its solids: adapters, PZT wafers, UDF and base ride on FE nodes.

Generic rendering is :mod:`trussid.fem.render`; this module holds what only the testbed
knows: which solid rides on which node, and the colours of its parts.
"""

from __future__ import annotations

import numpy as np

from trussid.fem.render import Decoration, decorations_from_solids
from trussid.geometry.solids import testbed_solids
from trussid.testbed.model import N_STRUTS

#: Colours of named parts (a word of the solid's name); ``None``: coloured by displacement.
PART_COLOURS = {"wafer": "#c8a23c", "adapter": None, "udf": None, "base": None}


def testbed_decorations(tbm, sections: int = 48) -> list[Decoration]:
    """The testbed's solids (adapters, PZT wafers, UDF, base) attached to its FE nodes.

    Each adapter block and its wafers ride on the strut node nearest the adapter's middle,
    the UDF on its rigid body's master node, the base on its master node when suspended
    (fixed when clamped). Strut tubes are not added: the beams are drawn as tubes of their
    real radius.

    Parameters
    ----------
    tbm : trussid.testbed.model.TestbedModel
    sections : int
        Sides of round parts (a picture needs far fewer than mass properties do).
    """
    mp, xyz = tbm.map, tbm.model.xyz
    attach: dict[str, int | None] = {"udf": int(mp.udf_master),
                                      "base": None if mp.base_master is None else int(mp.base_master)}
    for i in range(N_STRUTS):
        nodes = np.asarray(mp.strut_nodes[i])
        a, b = (int(np.flatnonzero(nodes == n)[0]) for n in mp.adapter_nodes[i])
        candidates = nodes[a:b + 1]
        p = xyz[tbm.model.index_of(candidates)]
        middle = 0.5 * (p[0] + p[-1])
        node = int(candidates[np.argmin(np.linalg.norm(p - middle, axis=1))])
        attach[f"strut {i} adapter"] = node
        for j in range(16):
            attach[f"strut {i} wafer {j}"] = node
    return decorations_from_solids(testbed_solids(tbm.testbed, sections=sections), attach,
                                   colours=PART_COLOURS)
