"""Point sensors: displacement, velocity or acceleration at a node along a direction."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from trussid.fem.errors import ModelError

__all__ = ["QUANTITIES", "Sensor", "sensor_matrix"]

QUANTITIES = ("displacement", "velocity", "acceleration")


@dataclass(frozen=True)
class Sensor:
    """A single-axis sensor at a node.

    Parameters
    ----------
    node : int
        Node id.
    direction : (3,) float
        Measuring axis, global coordinates (normalised here).
    quantity : {"displacement", "velocity", "acceleration"}
    sensitivity : float
        Output per unit of the quantity [V/m, V/(m/s), V/(m/s^2)]; 1 gives SI units out.
    name : str
        Output signal name.
    """

    node: int
    direction: tuple
    quantity: Literal["displacement", "velocity", "acceleration"] = "acceleration"
    sensitivity: float = 1.0
    name: str = ""

    def __post_init__(self):
        d = np.asarray(self.direction, dtype=float)
        label = self.name or f"sensor at node {self.node}"
        if d.shape != (3,) or not np.isfinite(d).all() or not np.linalg.norm(d) > 0:
            raise ModelError(f"{label}: direction must be a non-zero 3-vector, got {self.direction!r}")
        if self.quantity not in QUANTITIES:
            raise ModelError(f"{label}: quantity must be one of {', '.join(QUANTITIES)}, got {self.quantity!r}")
        if not (np.isfinite(self.sensitivity) and self.sensitivity != 0):
            raise ModelError(f"{label}: sensitivity must be finite and non-zero, got {self.sensitivity!r}")
        object.__setattr__(self, "direction", tuple(d / np.linalg.norm(d)))


def sensor_matrix(node_ids: np.ndarray, sensors: list[Sensor]) -> np.ndarray:
    """Rows picking each sensor's reading from a full DOF vector.

    Parameters
    ----------
    node_ids : (n_nodes,) int
        Node ids in index order (``Model.node_ids``, ``Modes.node_ids``).
    sensors : list of Sensor

    Returns
    -------
    (p, 6 n_nodes) float
        ``S @ u_full`` is the sensor output per unit displacement (velocity, acceleration),
        sensitivity included.
    """
    node_ids = np.asarray(node_ids)
    S = np.zeros((len(sensors), 6 * len(node_ids)))
    lookup = {int(n): i for i, n in enumerate(node_ids)}
    for r, s in enumerate(sensors):  # a handful of sensors: a loop is clearer than indexing
        if int(s.node) not in lookup:
            raise ModelError(f"{s.name or 'sensor'}: unknown node {s.node}")
        i = lookup[int(s.node)]
        S[r, 6 * i:6 * i + 3] = s.sensitivity * np.asarray(s.direction)
    return S
