"""Linear static solution ``K q = T^T f`` by sparse direct factorisation."""

from __future__ import annotations

import numpy as np

from trussid.fem.assembly import System, assemble
from trussid.fem.errors import ModelError
from trussid.fem.factor import cholmod_available
from trussid.fem.modal import BLAS_THREADS, blas_threads, factor_stiffness

__all__ = ["solve_static"]


def solve_static(model_or_system, f_full, *, autospc: bool = False) -> np.ndarray:
    """Displacements under nodal loads.

    Parameters
    ----------
    model_or_system : fem.Model or System
        A model is assembled first (with ``autospc``).
    autospc : bool
        Constrain the DOFs no element stiffens when assembling a model
        (:func:`trussid.fem.assembly.assemble`).
    f_full : (6 n_nodes,) or (6 n_nodes, k) float
        Nodal forces and moments on every node's six DOFs [N, N m]. Loads on supported DOFs
        go to the supports; loads on rigid-body slaves act through their master.

    Returns
    -------
    (6 n_nodes,) or (6 n_nodes, k) float
        Displacements and rotations of every node [m, rad] (supported DOFs zero).

    Raises
    ------
    ModelError
        The stiffness is singular (free rigid-body motion or a mechanism), naming the
        node and component where the factorisation broke down.

    Examples
    --------
    A 10 N tip load on a 1 m steel cantilever (20 x 10 mm): the tip deflects
    ``P L^3 / (3 E I)`` = 10 mm, exactly (cubic elements):

    >>> import numpy as np
    >>> from trussid.fem import STEEL, Model, Section, solve_static
    >>> m = Model()
    >>> m.add_nodes(np.arange(1, 12), np.c_[np.linspace(0, 1, 11), np.zeros((11, 2))])
    >>> m.add_beams(np.arange(1, 11), np.c_[np.arange(1, 11), np.arange(2, 12)],
    ...             Section.rectangle(0.02, 0.01), STEEL, orient=[0, 0, 1])
    >>> m.fix(1)
    >>> f = np.zeros(m.n_dof)
    >>> f[6 * 10 + 1] = 10.0                      # node 11 (index 10), force along y [N]
    >>> u = solve_static(m, f)
    >>> print(f"{1e3 * u[6 * 10 + 1]:.4f} mm")
    10.0000 mm
    """
    system = model_or_system if isinstance(model_or_system, System) else assemble(model_or_system, autospc=autospc)
    f_full = np.asarray(f_full, dtype=float)
    n_full = system.T.shape[0]
    if f_full.shape[0] != n_full:
        raise ModelError(f"load vector has {f_full.shape[0]} rows; the model has {n_full} DOFs "
                         f"(6 per node)")
    f = system.T.T @ f_full
    cholmod_available()  # loads cvxopt's own BLAS before the thread limit is set
    with blas_threads(BLAS_THREADS):
        fac, j = factor_stiffness(system)
        if fac is None:
            where = f" at {system.dof_label(j)}" if j is not None else ""
            raise ModelError(f"the stiffness is singular{where}: the model can move freely (add "
                             f"supports) or is a mechanism")
        return system.T @ fac.solve(f)
