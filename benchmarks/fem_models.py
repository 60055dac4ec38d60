"""Benchmark structures for the FE comparison with OpenSeesPy, built from one set of arrays.

Each generator returns a :class:`FrameSpec`: plain arrays (nodes, element connectivity,
orientation vectors, one tube section per element group, one material, clamped nodes). The
same spec becomes a trussid :class:`trussid.fem.Model` (:func:`to_trussid`) and an OpenSeesPy
domain (:func:`build_opensees`), so both tools solve the very same structure.

Structures (issue 2, acceptance item 9):

- :func:`truss_boom`: a long truss boom of equilateral-triangle section: three longerons, a
  triangular batten frame at every station, one diagonal per face per bay; every member is
  split into two elements (a mid-member node); station 0 is clamped. Free DOFs
  ``72 * n_bays + 18``.
- :func:`cubic_lattice`: an ``n x n x n`` grid of nodes joined by beams along x, y and z
  (one element per member); the base face ``z = 0`` is clamped. Free DOFs ``6 n^2 (n - 1)``.

Only circular tubes are used, so the torsion constant equals the polar moment
(``J = Iy + Iz``). That matters for the comparison: OpenSees' ``elasticBeamColumn -cMass``
consistent mass is the Euler-Bernoulli one *without rotary inertia* and with torsional
inertia ``rho A (J / A)``, which is exactly ``rho Ip`` only when ``J = Ip``.

Running this file, ``python benchmarks/fem_models.py CASE [--modes N]`` prints a JSON line
with OpenSeesPy's lowest frequencies for CASE (``boom:<n_bays>`` or ``lattice:<n>``); it is
how tests and the benchmark run OpenSeesPy in a subprocess with the library path its Linux
wheel needs (see :func:`opensees_env`).
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from trussid.fem.materials import ALUMINIUM, Material
from trussid.fem.model import Model
from trussid.fem.sections import Section

#: Benchmark sizes named in the issue: case name -> (spec name, approximate free DOFs).
SIZES = {
    "boom-1.5e4": "boom:208",      # 72 * 208 + 18 = 14 994 free DOFs
    "boom-1.5e5": "boom:2083",     # 149 994 free DOFs
    "lattice-3e3": "lattice:8",    # 6 * 64 * 7 = 2 688 free DOFs (3 072 before the base clamp)
    "lattice-3e4": "lattice:17",   # 6 * 289 * 16 = 27 744 free DOFs (the 2.8e4 case)
    "lattice-1.4e5": "lattice:29",  # 6 * 841 * 28 = 141 288 free DOFs (issue 18's next size)
}
SMALL = ("boom-1.5e4", "lattice-3e3")


@dataclass
class FrameSpec:
    """A frame structure as plain arrays, shared by both FE tools.

    Attributes
    ----------
    name : str
    node_ids : (n,) int
    xyz : (n, 3) float
        Node coordinates [m].
    elem_ids : (m,) int
    elem_nodes : (m, 2) int
        Node ids of the element ends.
    orient : (m, 3) float
        Orientation vector in the local x-y plane (NASTRAN's v, trussid's ``orient``).
    group : (m,) int
        Index into ``sections`` per element.
    sections : list of Section
    material : Material
    clamped : (k,) int
        Node ids with all six DOFs fixed.
    """

    name: str
    node_ids: np.ndarray
    xyz: np.ndarray
    elem_ids: np.ndarray
    elem_nodes: np.ndarray
    orient: np.ndarray
    group: np.ndarray
    sections: list[Section]
    material: Material = ALUMINIUM
    clamped: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def n_free_dof(self) -> int:
        """DOFs after the clamped nodes are removed."""
        return 6 * (len(self.node_ids) - len(np.unique(self.clamped)))

    @property
    def n_elements(self) -> int:
        return len(self.elem_ids)


def _least_aligned_axis(d: np.ndarray) -> np.ndarray:
    """Per row of directions ``d`` (m, 3), the global unit axis least parallel to it.

    A valid orientation vector for every element; the sections are round tubes, so the
    choice changes neither tool's result, but both receive the same one.
    """
    axes = np.eye(3)[np.argmin(np.abs(d), axis=1)]
    return axes


def _split_members(xyz: np.ndarray, members: np.ndarray, group: np.ndarray, first_node_id: int):
    """Split every member (k, 2) (node indices) into two elements through a new mid node.

    Returns the new node coordinates, element connectivity in node indices (2k, 2) and the
    element groups (2k,).
    """
    k = len(members)
    mid = 0.5 * (xyz[members[:, 0]] + xyz[members[:, 1]])
    mid_idx = first_node_id + np.arange(k)
    elems = np.empty((2 * k, 2), dtype=np.int64)
    elems[0::2, 0], elems[0::2, 1] = members[:, 0], mid_idx
    elems[1::2, 0], elems[1::2, 1] = mid_idx, members[:, 1]
    return mid, elems, np.repeat(group, 2)


def truss_boom(n_bays: int, side: float = 0.4, bay: float = 0.4,
               longeron: Section | None = None, lacing: Section | None = None,
               material: Material = ALUMINIUM) -> FrameSpec:
    """A clamped-free truss boom of equilateral-triangle section along global x.

    Parameters
    ----------
    n_bays : int
        Number of bays; stations 0..n_bays, station 0 clamped.
    side : float
        Side of the triangular section [m].
    bay : float
        Bay length [m].
    longeron, lacing : Section, optional
        Tube sections of the longerons and of battens and diagonals (defaults: 12 x 1 mm and
        8 x 0.8 mm aluminium tubes).
    material : Material

    Returns
    -------
    FrameSpec
        ``12 n_bays + 6`` nodes, ``18 n_bays + 6`` elements, ``72 n_bays + 18`` free DOFs.
    """
    if n_bays < 1:
        raise ValueError(f"truss_boom: n_bays must be >= 1, got {n_bays}")
    longeron = longeron or Section.tube(0.006, 0.001, name="longeron tube 12x1")
    lacing = lacing or Section.tube(0.004, 0.0008, name="lacing tube 8x0.8")
    n_st = n_bays + 1
    ang = np.pi / 2 + 2 * np.pi * np.arange(3) / 3
    r = side / math.sqrt(3.0)
    corner = np.column_stack([np.zeros(3), r * np.cos(ang), r * np.sin(ang)])  # (3, 3)
    # Station node index = 3 * station + corner.
    xyz = (corner[None, :, :] + np.array([bay, 0.0, 0.0]) * np.arange(n_st)[:, None, None]).reshape(-1, 3)
    st = np.arange(n_st)[:, None] * 3
    bays = np.arange(n_bays)[:, None] * 3
    c = np.arange(3)[None, :]
    c_next = (c + 1) % 3
    longerons = np.stack([bays + c, bays + 3 + c], axis=-1).reshape(-1, 2)
    battens = np.stack([st + c, st + c_next], axis=-1).reshape(-1, 2)
    # One diagonal per face per bay: corner c at station s to corner c+1 at station s+1.
    diagonals = np.stack([bays + c, bays + 3 + c_next], axis=-1).reshape(-1, 2)
    members = np.concatenate([longerons, battens, diagonals])
    group = np.concatenate([np.zeros(len(longerons), np.int64), np.ones(len(battens) + len(diagonals), np.int64)])
    mid, elems, egroup = _split_members(xyz, members, group, len(xyz))
    xyz = np.concatenate([xyz, mid])
    node_ids = np.arange(1, len(xyz) + 1)
    d = xyz[elems[:, 1]] - xyz[elems[:, 0]]
    return FrameSpec(
        name=f"boom:{n_bays}", node_ids=node_ids, xyz=xyz,
        elem_ids=np.arange(1, len(elems) + 1), elem_nodes=node_ids[elems],
        orient=_least_aligned_axis(d), group=egroup, sections=[longeron, lacing],
        material=material, clamped=node_ids[:3],
    )


def cubic_lattice(n: int, spacing: float = 0.5, tube: Section | None = None,
                  material: Material = ALUMINIUM) -> FrameSpec:
    """A cubic 3-D lattice frame: ``n^3`` nodes, beams between grid neighbours, base clamped.

    Parameters
    ----------
    n : int
        Nodes per edge (>= 2).
    spacing : float
        Grid spacing [m].
    tube : Section, optional
        Beam section (default a 20 x 2 mm aluminium tube).
    material : Material

    Returns
    -------
    FrameSpec
        ``3 n^2 (n - 1)`` elements, ``6 n^2 (n - 1)`` free DOFs.
    """
    if n < 2:
        raise ValueError(f"cubic_lattice: n must be >= 2, got {n}")
    tube = tube or Section.tube(0.010, 0.002, name="lattice tube 20x2")
    idx = np.arange(n**3).reshape(n, n, n)  # [ix, iy, iz]
    g = np.arange(n) * spacing
    X, Y, Z = np.meshgrid(g, g, g, indexing="ij")
    xyz = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    members = np.concatenate([
        np.column_stack([idx[:-1, :, :].ravel(), idx[1:, :, :].ravel()]),
        np.column_stack([idx[:, :-1, :].ravel(), idx[:, 1:, :].ravel()]),
        np.column_stack([idx[:, :, :-1].ravel(), idx[:, :, 1:].ravel()]),
    ])
    node_ids = np.arange(1, n**3 + 1)
    d = xyz[members[:, 1]] - xyz[members[:, 0]]
    return FrameSpec(
        name=f"lattice:{n}", node_ids=node_ids, xyz=xyz,
        elem_ids=np.arange(1, len(members) + 1), elem_nodes=node_ids[members],
        orient=_least_aligned_axis(d), group=np.zeros(len(members), np.int64), sections=[tube],
        material=material, clamped=node_ids[idx[:, :, 0].ravel()],
    )


def spec_from_name(name: str) -> FrameSpec:
    """Build a spec from ``"boom:<n_bays>"``, ``"lattice:<n>"`` or a key of :data:`SIZES`."""
    name = SIZES.get(name, name)
    kind, _, arg = name.partition(":")
    if kind == "boom":
        return truss_boom(int(arg))
    if kind == "lattice":
        return cubic_lattice(int(arg))
    raise ValueError(f"unknown benchmark structure {name!r}: use boom:<n_bays>, lattice:<n> or one of {sorted(SIZES)}")


# ---------------------------------------------------------------------------------- trussid
def to_trussid(spec: FrameSpec) -> Model:
    """The spec as a trussid :class:`trussid.fem.Model` (Euler-Bernoulli, consistent mass)."""
    model = Model(beam_theory="euler-bernoulli", mass="consistent", name=spec.name)
    model.add_nodes(spec.node_ids, spec.xyz)
    for g, section in enumerate(spec.sections):
        sel = spec.group == g
        model.add_beams(spec.elem_ids[sel], spec.elem_nodes[sel], section, spec.material,
                        orient=spec.orient[sel])
    if len(spec.clamped):
        model.fix(spec.clamped, "123456")
    return model


# ---------------------------------------------------------------------------------- OpenSees
def opensees_lib_dir() -> str | None:
    """The bundled shared-library folder of OpenSeesPy's Linux wheel, or None if absent."""
    found = importlib.util.find_spec("openseespylinux")
    if found is None or not found.submodule_search_locations:
        return None
    return str(Path(list(found.submodule_search_locations)[0]) / "lib")


def opensees_env() -> dict[str, str]:
    """This process's environment with OpenSeesPy's library folder on LD_LIBRARY_PATH.

    The wheel's extension links against libblas/liblapack copies it ships but does not find
    them by itself, and the loader reads LD_LIBRARY_PATH only at process start, so OpenSeesPy
    must run in a child process started with this environment.
    """
    env = dict(os.environ)
    lib = opensees_lib_dir()
    if lib:
        env["LD_LIBRARY_PATH"] = os.pathsep.join(p for p in (lib, env.get("LD_LIBRARY_PATH", "")) if p)
    return env


def ensure_opensees_loadable() -> None:
    """Re-execute this process with :func:`opensees_env` unless its library path is set.

    For scripts run from the shell: the dynamic loader only honours LD_LIBRARY_PATH given
    at process start.
    """
    lib = opensees_lib_dir()
    if lib and lib not in os.environ.get("LD_LIBRARY_PATH", "").split(os.pathsep):
        sys.stdout.flush()
        os.execve(sys.executable, [sys.executable, *sys.argv], opensees_env())


def build_opensees(spec: FrameSpec, ops) -> None:
    """Define ``spec`` in the (wiped) OpenSeesPy domain ``ops``.

    ``elasticBeamColumn`` elements with ``-mass rho*A -cMass`` (consistent mass). OpenSees'
    ``vecxz`` lies in the local x-z plane while trussid's ``orient`` lies in the local x-y
    plane, so ``vecxz = x_axis cross orient`` (the local z axis). Elements sharing a
    ``vecxz`` share one ``geomTransf``, as a user would write it. The per-node and
    per-element Python calls are OpenSeesPy's only interface for defining a model.
    """
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    for nid, (x, y, z) in zip(spec.node_ids.tolist(), spec.xyz.tolist()):
        ops.node(nid, x, y, z)
    for nid in np.unique(spec.clamped).tolist():
        ops.fix(nid, 1, 1, 1, 1, 1, 1)
    index = {nid: i for i, nid in enumerate(spec.node_ids.tolist())}
    ia = np.array([index[a] for a in spec.elem_nodes[:, 0].tolist()])
    ib = np.array([index[b] for b in spec.elem_nodes[:, 1].tolist()])
    ex = spec.xyz[ib] - spec.xyz[ia]
    ex /= np.linalg.norm(ex, axis=1, keepdims=True)
    vecxz = np.cross(ex, spec.orient)
    vecxz /= np.linalg.norm(vecxz, axis=1, keepdims=True)
    uniq, transf = np.unique(np.round(vecxz, 12), axis=0, return_inverse=True)
    for t, v in enumerate(uniq.tolist(), start=1):
        ops.geomTransf("Linear", t, *v)
    mat = spec.material
    props = [(s.A, mat.E, mat.G, s.J, s.Iy, s.Iz, mat.rho * s.A) for s in spec.sections]
    for eid, (a, b), g, t in zip(spec.elem_ids.tolist(), spec.elem_nodes.tolist(),
                                 spec.group.tolist(), (transf.ravel() + 1).tolist()):
        A, E, G, J, Iy, Iz, mass = props[g]
        ops.element("elasticBeamColumn", eid, a, b, A, E, G, J, Iy, Iz, t, "-mass", mass, "-cMass")


def opensees_eigen(ops, n_modes: int, solver: str = "-genBandArpack", system: str | None = None,
                   numberer: str | None = None) -> np.ndarray:
    """Lowest ``n_modes`` frequencies [Hz] of the current OpenSeesPy domain.

    ``system``/``numberer`` set the linear system and DOF numbering the ARPACK shift-invert
    uses (OpenSees' defaults: ProfileSPD and RCM); None keeps the default.
    """
    if numberer:
        ops.numberer(numberer)
    if system:
        ops.system(*system.split())
    lam = np.asarray(ops.eigen(solver, n_modes), dtype=float)
    return np.sqrt(np.abs(lam)) / (2 * np.pi)


def opensees_frequencies(case: str, n_modes: int = 20, timeout: float = 600.0, **options) -> np.ndarray:
    """OpenSeesPy's lowest frequencies [Hz] for ``case``, computed in a child process."""
    cmd = [sys.executable, str(Path(__file__).resolve()), case, "--modes", str(n_modes)]
    for key, value in options.items():
        cmd += [f"--{key}", str(value)]
    out = subprocess.run(cmd, env=opensees_env(), capture_output=True, text=True, timeout=timeout)
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
    if out.returncode != 0 or not lines:
        raise RuntimeError(f"OpenSeesPy run for {case!r} failed (exit {out.returncode}):\n{out.stderr[-2000:]}")
    return np.asarray(json.loads(lines[-1])["frequencies_hz"])


def _main(argv: list[str] | None = None) -> int:
    import argparse

    p = argparse.ArgumentParser(description="OpenSeesPy frequencies of a benchmark structure (JSON).")
    p.add_argument("case")
    p.add_argument("--modes", type=int, default=20)
    p.add_argument("--solver", default="-genBandArpack")
    p.add_argument("--system", default=None)
    p.add_argument("--numberer", default=None)
    args = p.parse_args(argv)
    ensure_opensees_loadable()
    import openseespy.opensees as ops

    spec = spec_from_name(args.case)
    build_opensees(spec, ops)
    f = opensees_eigen(ops, args.modes, args.solver, args.system, args.numberer)
    print(json.dumps({"case": args.case, "n_dof": spec.n_free_dof, "frequencies_hz": f.tolist()}))
    return 0


if __name__ == "__main__":
    raise SystemExit(_main())
