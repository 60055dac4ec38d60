"""Wall sweeps on the testbed's FE model, and its eigen solution.

:func:`wall_basis` assembles the model once and splits ``K`` and ``M`` (reduced DOFs) into a
constant part plus, per strut, terms proportional to ``A_t(t_i)`` and ``I_t(t_i)``, all as
data vectors on one sparse pattern. :func:`wall_matrices` then forms the dense reduced
matrices for new walls with a matrix-vector product, and :func:`wall_modes` solves for the
lowest modes with :func:`trussid.fem.modal.dense_modes` (LAPACK's subset generalised
eigensolver; shift-invert above :data:`trussid.fem.modal.DENSE_MAX_DOF`): no topology,
geometry, layout or rigid-body work per design. The eigen solution of a whole testbed,
:func:`solve_testbed_modes`, is :func:`trussid.fem.modal.solve_modes`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from trussid.fem.assembly import System, assemble
from trussid.fem.elements import frame_matrices, local_axes
from trussid.fem.errors import ModelError
from trussid.fem.modal import DENSE_MAX_DOF, Modes, dense_modes, solve_modes

from .model import N_STRUTS, TestbedModel, tube_properties

__all__ = ["WallBasis", "wall_basis", "wall_matrices", "wall_modes", "design_at_walls",
           "solve_testbed_modes"]


@dataclass
class WallBasis:
    """Reduced ``K``, ``M`` of a testbed as affine functions of the six tube sections.

    ``K(t) = K_ref + sum_i (A_t(t_i) - A_t(t_ref_i)) KA_i + (I_t(t_i) - I_t(t_ref_i)) KI_i``
    and likewise ``M``, all stored as data on the sparse pattern ``(rows, cols)``.

    Attributes
    ----------
    n : int
        Number of reduced DOFs.
    rows, cols : (nnz,) int
        Sparse pattern shared by every matrix.
    K_ref, M_ref : (nnz,) float
        Data of ``K`` and ``M`` at the reference walls.
    KA, KI, MA, MI : (6, nnz) float
        Per strut: data of ``dK/dA_t``, ``dK/dI_t``, ``dM/dA_t``, ``dM/dI_t``.
    walls_ref : (6,) float
        Reference walls [m].
    r_out : float
        Tube outside radius [m].
    system : fem.assembly.System
        The system assembled at the reference walls (``T``, ``dofs``, node ids).
    """

    n: int
    rows: np.ndarray
    cols: np.ndarray
    K_ref: np.ndarray
    M_ref: np.ndarray
    KA: np.ndarray
    KI: np.ndarray
    MA: np.ndarray
    MI: np.ndarray
    walls_ref: np.ndarray
    r_out: float
    system: System

    def check_walls(self, walls) -> np.ndarray:
        """Walls as a (6,) array; an error naming the strut if one is not in (0, r_out)."""
        w = np.asarray(walls, float).reshape(-1)
        if w.shape != (N_STRUTS,):
            raise ModelError(f"walls must hold {N_STRUTS} thicknesses (one per strut), got {w.shape[0]}")
        bad = ~((w > 0) & (w < self.r_out))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ModelError(f"strut {i} wall thickness {float(w[i])!r} m must be in (0, {self.r_out:.5g} m)")
        return w

    def coefficients(self, walls) -> tuple[np.ndarray, np.ndarray]:
        """``A_t(t) - A_t(t_ref)`` and ``I_t(t) - I_t(t_ref)`` per strut."""
        w = self.check_walls(walls)
        A, I = tube_properties(self.r_out, w)
        A0, I0 = tube_properties(self.r_out, self.walls_ref)
        return A - A0, I - I0

    def data(self, walls) -> tuple[np.ndarray, np.ndarray]:
        """Data vectors of ``K`` and ``M`` at ``walls`` on the shared pattern."""
        dA, dI = self.coefficients(walls)
        return self.K_ref + dA @ self.KA + dI @ self.KI, self.M_ref + dA @ self.MA + dI @ self.MI

    def sparse(self, data: np.ndarray) -> sp.csr_matrix:
        """A data vector as a CSR matrix."""
        return sp.csr_matrix((data, (self.rows, self.cols)), shape=(self.n, self.n))

    def dense(self, data: np.ndarray) -> np.ndarray:
        """A data vector as a dense (n, n) array."""
        out = np.zeros((self.n, self.n))
        out[self.rows, self.cols] = data
        return out

    def projected(self, V: np.ndarray) -> "WallBasis":
        """The basis Ritz-projected onto the columns of ``V`` (n, r): every matrix ``B``
        becomes ``V^T B V``, stored densely (the pattern is all ``(r, c)``).

        The result is still affine in the tube properties, so it is exact in how the walls
        enter and :func:`wall_modes` and the wall sensitivities work on it unchanged; its
        only error is the Ritz error of the fixed subspace. Its shapes are amplitudes of
        ``V``'s columns: ``V q`` expands them to this basis's DOFs (``system`` stays the
        full model's).

        Raises
        ------
        ModelError
            If ``V`` is not (n, r) with 1 <= r <= n.
        """
        V = np.asarray(V, float)
        if V.ndim != 2 or V.shape[0] != self.n or not 1 <= V.shape[1] <= self.n:
            raise ModelError(f"a Ritz basis for {self.n} DOFs must be ({self.n}, r) with "
                             f"1 <= r <= {self.n}, got shape {V.shape}")
        r = V.shape[1]

        def proj(data):
            return (V.T @ (self.sparse(data) @ V)).ravel()

        rr, cc = np.divmod(np.arange(r * r), r)
        return replace(self, n=r, rows=rr, cols=cc, K_ref=proj(self.K_ref), M_ref=proj(self.M_ref),
                       KA=np.array([proj(d) for d in self.KA]), KI=np.array([proj(d) for d in self.KI]),
                       MA=np.array([proj(d) for d in self.MA]), MI=np.array([proj(d) for d in self.MI]))


def _reduced_data(T: sp.csr_matrix, Tt: sp.csr_matrix, blocks: np.ndarray, dofs: np.ndarray, n_full: int):
    """``T^T B T`` of element blocks summed into full DOFs, as a COO-ish (rows, cols, data)."""
    rows = np.broadcast_to(dofs[:, :, None], blocks.shape).ravel()
    cols = np.broadcast_to(dofs[:, None, :], blocks.shape).ravel()
    B = sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(n_full, n_full))
    return (Tt @ B @ T).tocoo()


def wall_basis(tbm: TestbedModel, system: System | None = None) -> WallBasis:
    """Split the reduced ``K`` and ``M`` of ``tbm`` into a constant part and wall terms.

    Parameters
    ----------
    tbm : TestbedModel
        Built with ``beam_theory="euler-bernoulli"`` (the Timoshenko shear factor makes the
        element matrices non-linear in the section properties) and consistent mass.
    system : fem.assembly.System, optional
        ``assemble(tbm.model)`` if already available.

    Returns
    -------
    WallBasis
    """
    model = tbm.model
    if model.beam_theory != "euler-bernoulli":
        raise ModelError("wall sweeps need the Euler-Bernoulli beam theory (Timoshenko matrices are "
                         "not linear in the section properties)")
    if model.mass_formulation != "consistent":
        raise ModelError("wall sweeps need the consistent mass (lumped mass leaves rotations massless, "
                         "which the dense subset eigensolver of wall_modes does not condense)")
    tb = tbm.testbed
    system = assemble(model) if system is None else system
    T = system.T.tocsr()
    Tt = T.T.tocsr()
    n_full = model.n_dof
    s = tb.struts
    E, G, rho = s.youngs_modulus, s.youngs_modulus / (2.0 * (1.0 + s.poisson_ratio)), s.density

    xyz = model.xyz
    idx = model.index_of(tbm.map.strut_nodes)  # (6, n)
    pieces = []  # per strut: KA, KI, MA, MI as COO
    for i in range(N_STRUTS):
        a, b = idx[i, :-1], idx[i, 1:]
        orient = np.broadcast_to(tbm.map.strut_frames[i, 1], (len(a), 3))
        L, R = local_axes(xyz[a], xyz[b], orient)
        z, o = np.zeros(len(L)), np.ones(len(L))
        dofs = (6 * np.column_stack([a, b])[:, :, None] + np.arange(6)).reshape(len(a), 12)
        kw = dict(R=R, theory="euler-bernoulli", mass=model.mass_formulation)
        KA, MA = frame_matrices(L, o, z, z, z, E * o, G * o, rho * o, **kw)
        KI, MI = frame_matrices(L, z, o, o, 2 * o, E * o, G * o, rho * o, **kw)
        pieces.append([_reduced_data(T, Tt, blk, dofs, n_full) for blk in (KA, KI, MA, MI)])

    n = system.n_dof
    Kc, Mc = system.K.tocoo(), system.M.tocoo()
    allr = np.concatenate([Kc.row, Mc.row] + [p.row for ps in pieces for p in ps])
    allc = np.concatenate([Kc.col, Mc.col] + [p.col for ps in pieces for p in ps])
    lin = np.unique(allr.astype(np.int64) * n + allc)
    rows, cols = lin // n, lin % n

    def on_pattern(c) -> np.ndarray:
        out = np.zeros(len(lin))
        np.add.at(out, np.searchsorted(lin, c.row.astype(np.int64) * n + c.col), c.data)
        return out

    basis = np.array([[on_pattern(p) for p in ps] for ps in pieces])  # (6, 4, nnz)
    return WallBasis(n=n, rows=rows, cols=cols, K_ref=on_pattern(Kc), M_ref=on_pattern(Mc),
                     KA=basis[:, 0], KI=basis[:, 1], MA=basis[:, 2], MI=basis[:, 3],
                     walls_ref=np.asarray(s.walls, float), r_out=s.outer_radius, system=system)


def wall_matrices(basis: WallBasis, walls) -> tuple[np.ndarray, np.ndarray]:
    """Dense reduced ``K`` and ``M`` for the six tube walls ``walls`` [m]."""
    k, m = basis.data(walls)
    return basis.dense(k), basis.dense(m)


def wall_modes(basis: WallBasis, walls, n_modes: int = 30, driver: str = "evr"
               ) -> tuple[np.ndarray, np.ndarray]:
    """Lowest natural frequencies [Hz] and mass-normalised reduced shapes for ``walls``.

    Parameters
    ----------
    basis : WallBasis
    walls : (6,) float
        Wall thicknesses [m].
    n_modes : int
    driver : str
        LAPACK driver of :func:`trussid.fem.modal.dense_modes` ("evr" or "gvx" for a subset;
        "gvd"/"gv" compute all and are sliced). Above :data:`trussid.fem.modal.DENSE_MAX_DOF` reduced
        DOFs the modes come from sparse shift-invert instead.

    Returns
    -------
    frequencies_hz : (n_modes,) float
    shapes : (n, n_modes) float
        ``shapes.T @ M @ shapes = I`` on the reduced DOFs (``basis.system.T`` expands them).

    Examples
    --------
    The strut modes of the default testbed at its nominal walls, and with every wall 50 %
    thicker (stiffer struts, higher frequencies), without rebuilding the model:

    >>> import numpy as np
    >>> from trussid.testbed.model import build_testbed
    >>> from trussid.testbed.walls import wall_basis, wall_modes
    >>> tbm = build_testbed()
    >>> basis = wall_basis(tbm)
    >>> walls = np.array(tbm.testbed.struts.walls)
    >>> print(np.round(1e3 * walls, 4))                     # [mm]
    [0.7112 0.889  1.0668 1.2446 1.4732 1.651 ]
    >>> print(np.round(wall_modes(basis, walls, 10)[0][6:9], 2))
    [50.43 50.49 53.02]
    >>> print(np.round(wall_modes(basis, 1.5 * walls, 10)[0][6:9], 2))
    [54.89 54.96 56.65]
    """
    if basis.n > DENSE_MAX_DOF:
        k_data, m_data = basis.data(walls)
        system = replace(basis.system, K=basis.sparse(k_data), M=basis.sparse(m_data))
        modes = solve_modes(system, n_modes)
        return modes.frequencies_hz, modes.shapes
    K, M = wall_matrices(basis, walls)
    # K is positive definite (the testbed is clamped or hangs on grounded bungees): no shift.
    lam, X = dense_modes(K, M, n_modes, driver=driver, overwrite=True)
    return np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi), X


def design_at_walls(tbm: TestbedModel, basis: WallBasis, walls, n_modes: int = 30
                    ) -> tuple[TestbedModel, Modes]:
    """The testbed at other strut walls, without rebuilding it: its FE model and its modes.

    Parameters
    ----------
    tbm : TestbedModel
        The testbed at the reference walls.
    basis : WallBasis
        Its wall basis (:func:`wall_basis` of ``tbm``).
    walls : (6,) float
        Wall thicknesses [m], each in ``(0, r_out)``.
    n_modes : int
        Lowest modes wanted.

    Returns
    -------
    design : TestbedModel
        ``tbm`` at ``walls``: a real :class:`trussid.fem.Model` whose strut elements have the
        tube's ``A_t``, ``I_t`` (``J_t = 2 I_t``) moved by :meth:`WallBasis.coefficients`
        (the one rule of how a wall changes a section), and ``testbed.struts.walls`` set.
    modes : fem.modal.Modes
        Its lowest modes from the wall basis (:func:`wall_modes`), mass-normalised.
    """
    w = basis.check_walls(walls)
    dA, dI = basis.coefficients(w)
    b = tbm.model.beams
    strut = tbm.map.strut_of_element(b.ids)
    on = strut >= 0
    da, di = np.zeros(len(strut)), np.zeros(len(strut))
    da[on], di[on] = dA[strut[on]], dI[strut[on]]
    model = tbm.model.with_beam_sections(b.A + da, b.Iy + di, b.Iz + di, b.J + 2 * di)
    f, X = wall_modes(basis, w, n_modes)
    system = basis.system
    modes = Modes(frequencies_hz=f, omega=2 * np.pi * f, shapes=X, shapes_full=system.T @ X,
                  node_ids=system.node_ids, xyz=system.xyz, n_dof=basis.n,
                  method="dense" if basis.n <= DENSE_MAX_DOF else "shift-invert")
    design = TestbedModel(model=model, map=tbm.map,
                          testbed=tbm.testbed.with_walls(tuple(float(v) for v in w)),
                          elements_per_segment=tbm.elements_per_segment)
    return design, modes


def solve_testbed_modes(tbm: TestbedModel, n_modes: int = 30, system: System | None = None,
                        max_frequency_hz: float | None = None) -> Modes:
    """Lowest modes of a testbed model: :func:`trussid.fem.modal.solve_modes` of its system.

    Parameters
    ----------
    tbm : TestbedModel
    n_modes : int
        Lowest modes wanted.
    system : fem.assembly.System, optional
        ``assemble(tbm.model)`` if already available.
    max_frequency_hz : float, optional
        Every mode at or below this frequency [Hz] instead of ``n_modes`` of them.

    Returns
    -------
    fem.modal.Modes
        The sub-hertz suspension modes are kept (only a rigid-body null space is clamped
        to 0, and the testbed has none: it is clamped, or hangs on bungees).
    """
    system = assemble(tbm.model) if system is None else system
    return solve_modes(system, n_modes, max_frequency_hz=max_frequency_hz)
