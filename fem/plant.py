"""Structural plant by modal superposition: loads in, sensor readings out.

With mass-normalised modes ``Phi`` (full DOFs), modal coordinates ``eta`` obey::

    eta'' + 2 Z Omega eta' + Omega^2 eta = Phi^T F u

for inputs ``u`` that produce nodal loads ``F u``. The state is ``x = [eta; eta']``.
Displacement, velocity and acceleration sensors read ``S Phi eta``, ``S Phi eta'`` and
``S Phi eta''`` (the last has a direct term ``S Phi Phi^T F``).
"""

from __future__ import annotations

import control
import numpy as np

from trussid.fem.errors import ModelError
from trussid.fem.sensors import Sensor, sensor_matrix
from trussid.fem.static import solve_static

__all__ = ["modal_damping", "modal_plant", "residual_flexibility"]


def modal_damping(damping, n: int) -> np.ndarray:
    """Per-mode damping ratios from a scalar or a sequence of length ``n``."""
    z = np.asarray(damping, dtype=float)
    if z.ndim == 0:
        z = np.full(n, float(z))
    if z.shape != (n,):
        raise ModelError(f"damping: give one ratio or one per kept mode ({n}), got {z.shape[0]}")
    if not (np.isfinite(z).all() and (z >= 0).all()):
        raise ModelError(f"damping ratios must be finite and >= 0, got {z.tolist()}")
    return z


def modal_plant(modes, loads: np.ndarray, sensors: list[Sensor], damping=0.0025, *,
                n_modes: int | None = None, residual_flexibility: np.ndarray | None = None,
                input_names: list[str] | None = None, disturbances: dict | None = None,
                performance: list[Sensor] | None = None) -> control.StateSpace:
    """Continuous-time state-space plant from normal modes.

    Parameters
    ----------
    modes : fem.modal.Modes
        Mass-normalised modes (``shapes_full``, ``omega``).
    loads : (6 n_nodes,) or (6 n_nodes, m) float
        Nodal loads per unit of each input (e.g. per volt on a PZT) [N/unit, N m/unit].
    sensors : list of Sensor
    damping : float or (n_kept,) float
        Modal damping ratios [-].
    n_modes : int, optional
        Keep the lowest ``n_modes`` modes (default all in ``modes``).
    residual_flexibility : (6 n_nodes, m) float, optional
        Static displacement of the truncated modes per unit input,
        ``K^-1 F - Phi_kept Omega^-2 Phi_kept^T F`` (:func:`residual_flexibility`), added as a
        direct term on displacement outputs (static correction). Velocity and acceleration
        outputs have no constant residual and are left as they are.
    input_names : list of str, optional
    disturbances : dict of str -> (6 n_nodes,) float, optional
        Extra named inputs after the ``loads`` columns: nodal loads per unit of each
        disturbance (e.g. a force at a node [N/N], one axis of a wrench), for measuring
        rejection through the same plant.
    performance : list of Sensor, optional
        Extra named outputs after ``sensors`` (e.g. motions that matter but are not
        measured by the controller).

    Returns
    -------
    control.StateSpace
        States ``[eta; eta']`` (2 n_kept), inputs as ``loads`` columns then the
        disturbances, outputs one per sensor (then per performance sensor) named after it.

    Examples
    --------
    A force at the tip of a 1 m steel cantilever (20 x 10 mm) to the tip's displacement. Six
    modes hold 99.9 % of the static flexibility ``L^3 / (3 E I)`` = 1 mm/N; the static correction
    of the truncated modes restores the rest:

    >>> import control
    >>> import numpy as np
    >>> from trussid.fem import (STEEL, Model, Section, Sensor, assemble, modal_plant,
    ...                          residual_flexibility, solve_modes)
    >>> m = Model()
    >>> m.add_nodes(np.arange(1, 12), np.c_[np.linspace(0, 1, 11), np.zeros((11, 2))])
    >>> m.add_beams(np.arange(1, 11), np.c_[np.arange(1, 11), np.arange(2, 12)],
    ...             Section.rectangle(0.02, 0.01), STEEL, orient=[0, 0, 1])
    >>> m.fix(1)
    >>> system = assemble(m)
    >>> modes = solve_modes(system, n_modes=6)
    >>> force = np.zeros(m.n_dof)
    >>> force[6 * 10 + 1] = 1.0                       # 1 N along y at node 11 (index 10)
    >>> tip = Sensor(11, (0, 1, 0), "displacement", name="tip_y")
    >>> G = modal_plant(modes, force, [tip], damping=0.01, input_names=["force"])
    >>> G.nstates, G.input_labels, G.output_labels
    (12, ['force'], ['tip_y'])
    >>> print(f"{1e3 * control.dcgain(G):.4f} mm/N")
    0.9994 mm/N
    >>> R = residual_flexibility(system, modes, force, 6)
    >>> G = modal_plant(modes, force, [tip], damping=0.01, residual_flexibility=R)
    >>> print(f"{1e3 * control.dcgain(G):.4f} mm/N")
    1.0000 mm/N
    """
    F = np.asarray(loads, dtype=float)
    if F.ndim == 1:
        F = F[:, None]
    names_in = list(input_names or [f"u{i + 1}" for i in range(F.shape[1])])
    if len(names_in) != F.shape[1]:
        raise ModelError(f"input_names: {len(names_in)} names for {F.shape[1]} load columns")
    if disturbances:
        cols = []
        for name, col in disturbances.items():
            col = np.asarray(col, dtype=float).ravel()
            if col.shape[0] != F.shape[0]:
                raise ModelError(f"disturbance '{name}': {col.shape[0]} load entries; the model "
                                 f"has {F.shape[0]} DOFs")
            if name in names_in:
                raise ModelError(f"disturbance '{name}': the name is already an input")
            cols.append(col)
            names_in.append(str(name))
        F = np.column_stack([F, *cols])
    if performance:
        sensors = list(sensors) + list(performance)
    Phi = modes.shapes_full
    if F.shape[0] != Phi.shape[0]:
        raise ModelError(f"loads have {F.shape[0]} rows; the model has {Phi.shape[0]} DOFs")
    n = len(modes.omega) if n_modes is None else int(n_modes)
    if not 1 <= n <= len(modes.omega):
        raise ModelError(f"n_modes must be in 1..{len(modes.omega)}, got {n_modes}")
    Phi, w = Phi[:, :n], np.asarray(modes.omega[:n], dtype=float)
    z = modal_damping(damping, n)
    S = sensor_matrix(modes.node_ids, sensors)
    q = np.array([s.quantity for s in sensors])
    SPhi = S @ Phi
    Bm = Phi.T @ F
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(w**2), -np.diag(2 * z * w)]])
    B = np.vstack([np.zeros((n, F.shape[1])), Bm])
    C = np.zeros((len(sensors), 2 * n))
    D = np.zeros((len(sensors), F.shape[1]))
    disp, vel, acc = q == "displacement", q == "velocity", q == "acceleration"
    C[disp, :n] = SPhi[disp]
    C[vel, n:] = SPhi[vel]
    C[acc, :n] = -SPhi[acc] * w**2
    C[acc, n:] = -SPhi[acc] * (2 * z * w)
    D[acc] = SPhi[acc] @ Bm
    if residual_flexibility is not None:
        R = np.asarray(residual_flexibility, dtype=float).reshape(F.shape[0], -1)
        if R.shape[1] != F.shape[1]:
            raise ModelError(f"residual_flexibility has {R.shape[1]} columns; the plant has "
                             f"{F.shape[1]} inputs (loads and disturbances)")
        D[disp] += (S @ R)[disp]
    names_out = [s.name or f"y{i + 1}" for i, s in enumerate(sensors)]
    dup = sorted({n for n in names_out if names_out.count(n) > 1})
    if dup:
        raise ModelError(f"output name '{dup[0]}' is used by more than one sensor")
    states = [f"eta{i + 1}" for i in range(n)] + [f"deta{i + 1}" for i in range(n)]
    return control.ss(A, B, C, D, inputs=names_in, outputs=names_out, states=states)


def residual_flexibility(system, modes, loads: np.ndarray, n_modes: int) -> np.ndarray:
    """Static displacement of the modes above ``n_modes`` per unit input.

    ``K^-1 F - sum_{kept} phi phi^T F / omega^2``. Needs a supported model (non-singular K)
    whose kept modes are all elastic.
    """
    F = np.asarray(loads, dtype=float).reshape(len(loads), -1)
    w = np.asarray(modes.omega[:n_modes])
    if not (w > 0).all():
        raise ModelError("static correction needs a supported model: the kept modes include rigid-body modes")
    Phi = modes.shapes_full[:, :n_modes]
    return solve_static(system, F) - Phi @ ((Phi.T @ F) / w[:, None] ** 2)
