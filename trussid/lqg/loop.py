"""A discrete controller around a discrete plant, matched by channel name: :class:`Loop`.

Conventions: the plant's control inputs are the D/A commands named like the controller's
outputs, its sensor outputs are named like the controller's inputs; ``u = controller(y)``
(no sign hidden). The closed loop (:attr:`Loop.closed`) has the plant's inputs as additive
disturbances at the D/A (``d_<name>``), sensor noise at each sensor (``n_<name>``), every
other plant input unchanged, and as outputs the plant's outputs and the commands
(``u_<name>``).

This module is the one place where a controller's channel names are mapped to the plant's
indices (:func:`channels`); everything that needs the plant seen from the controller's
channels asks a :class:`Loop` (or :func:`restrict`) for it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import control
import numpy as np

from .errors import ControlError

__all__ = ["Loop", "channels", "restrict", "match_names", "check_pair"]


def channels(names, available, what: str = "channel") -> tuple[int, ...]:
    """Indices of ``names`` in ``available`` (a :class:`ControlError` naming the first one
    missing; ``what`` names the kind in the message)."""
    available = list(available)
    missing = [n for n in names if n not in available]
    if missing:
        raise ControlError(f"{what} '{missing[0]}' is not one of {', '.join(available)}")
    return tuple(available.index(n) for n in names)


def restrict(plant, inputs, outputs) -> control.StateSpace:
    """``plant`` seen from the inputs named ``inputs`` to the outputs named ``outputs``, in
    that order (same states, names kept)."""
    iu = channels(inputs, plant.input_labels, "input")
    iy = channels(outputs, plant.output_labels, "output")
    return _restricted(plant, iu, iy)


def _restricted(plant, iu, iy) -> control.StateSpace:
    iu, iy = list(iu), list(iy)
    p_in, p_out = list(plant.input_labels), list(plant.output_labels)
    return control.ss(np.asarray(plant.A), np.asarray(plant.B)[:, iu], np.asarray(plant.C)[iy],
                      np.asarray(plant.D)[np.ix_(iy, iu)], plant.dt,
                      inputs=[p_in[j] for j in iu], outputs=[p_out[i] for i in iy])


def match_names(plant, controller):
    """``controller`` with its channel names matched to ``plant``'s, and the renames made.

    A model identified from a CSV record carries the record's column names (``y_acc``,
    ``u_shaker``: :mod:`trussid.plid.datafile`'s convention), so its controller does too;
    each name that is not a plant channel but is one without its ``u_``/``y_`` prefix is
    renamed. Names that match neither way are left for :func:`check_pair` to refuse.

    Returns
    -------
    controller : control.StateSpace
    renamed : list of (str, str)
    """
    p_in, p_out = set(plant.input_labels), set(plant.output_labels)

    def fix(names, known, prefix):
        out, ren = [], []
        for n in names:
            if n not in known and n.startswith(prefix) and n[len(prefix):] in known:
                ren.append((n, n[len(prefix):]))
                n = n[len(prefix):]
            out.append(n)
        return out, ren

    ins, r1 = fix(list(controller.input_labels), p_out, "y_")
    outs, r2 = fix(list(controller.output_labels), p_in, "u_")
    if not (r1 or r2):
        return controller, []
    c = control.ss(controller.A, controller.B, controller.C, controller.D, controller.dt,
                   inputs=ins, outputs=outs, name=controller.name)
    return c, r1 + r2


def check_pair(plant, controller, label: str = "plant") -> None:
    """Refuse a controller that cannot close a loop around ``plant`` (names, sizes, dt),
    with one line naming the item; ``label`` names the plant in the message."""
    Loop.of(plant, controller, label)


@dataclass(frozen=True)
class Loop:
    """``controller`` closed around ``plant``, its channels mapped by name.

    Make it with :meth:`of`, which checks the pair. ``iu`` are the plant inputs the
    controller drives (in the controller's output order), ``iy`` the plant outputs it
    measures (in its input order).

    Examples
    --------
    >>> import control
    >>> plant = control.ss([[0.9]], [[1.0, 0.5]], [[1.0]], [[0.0, 0.0]], 0.01,
    ...                    inputs=["shaker", "pzt"], outputs=["acc"])
    >>> gain = control.ss([], [], [], [[-0.2]], 0.01, inputs=["acc"], outputs=["pzt"])
    >>> loop = Loop.of(plant, gain)
    >>> loop.iu, loop.iy, loop.open_loop.input_labels
    ((1,), (0,), ['pzt'])
    >>> round(float(loop.closed.A[0, 0]), 2)
    0.8
    """

    plant: control.StateSpace
    controller: control.StateSpace
    iu: tuple
    iy: tuple

    @classmethod
    def of(cls, plant, controller, label: str = "plant") -> "Loop":
        """The loop of ``controller`` around ``plant``; a :class:`ControlError` naming the
        item (prefixed by ``label`` unless it is ``"plant"``) when they cannot close one:
        continuous systems, different sample intervals, a controller channel the plant does
        not have, or both with a direct term (an algebraic loop)."""
        try:
            iu, iy = _pair(plant, controller)
        except ControlError as exc:
            raise (ControlError(f"{label}: {exc}") if label != "plant" else exc) from None
        return cls(plant, controller, iu, iy)

    @property
    def other_inputs(self) -> tuple:
        """Indices of the plant inputs the controller does not drive."""
        return tuple(j for j in range(self.plant.ninputs) if j not in self.iu)

    @cached_property
    def open_loop(self) -> control.StateSpace:
        """The plant from the controller's actuators to its sensors (same states)."""
        return _restricted(self.plant, self.iu, self.iy)

    @cached_property
    def closed(self) -> control.StateSpace:
        """The closed loop (module docstring): states ``[plant; controller]``; inputs
        ``d_<u>`` (one per controlled plant input), ``n_<y>`` (one per measured output),
        then the plant's other inputs; outputs the plant's outputs then ``u_<u>``."""
        return _closed(self)

    @cached_property
    def poles(self) -> np.ndarray:
        """The closed loop's poles (eigenvalues of :attr:`closed`'s ``A``)."""
        return np.linalg.eigvals(np.asarray(self.closed.A))

    @cached_property
    def disturbance_to_sensors(self) -> control.StateSpace:
        """The closed loop from the D/A disturbances ``d_<u>`` to the measured outputs."""
        cl, nu = self.closed, len(self.iu)
        iy = list(self.iy)
        return control.ss(cl.A, np.asarray(cl.B)[:, :nu], np.asarray(cl.C)[iy],
                          np.asarray(cl.D)[np.ix_(iy, list(range(nu)))], self.plant.dt)


def _pair(plant, controller):
    for what, sys in (("plant", plant), ("controller", controller)):
        if not control.isdtime(sys, strict=True):
            raise ControlError(f"{what}: continuous (dt = 0); a discrete system is needed")
    if not math.isclose(plant.dt, controller.dt, rel_tol=1e-9):
        raise ControlError(f"sample interval: the plant has dt = {plant.dt:g} s, the controller "
                           f"{controller.dt:g} s")
    p_in, p_out = list(plant.input_labels), list(plant.output_labels)
    for name in controller.input_labels:
        if name not in p_out:
            raise ControlError(f"controller input '{name}' is not a plant output "
                               f"(plant outputs: {', '.join(p_out)})")
    for name in controller.output_labels:
        if name not in p_in:
            raise ControlError(f"controller output '{name}' is not a plant input "
                               f"(plant inputs: {', '.join(p_in)})")
    iu = channels(controller.output_labels, p_in, "controller output")
    iy = channels(controller.input_labels, p_out, "controller input")
    Dp = np.asarray(plant.D)[np.ix_(list(iy), list(iu))]
    if np.any(Dp != 0) and np.any(np.asarray(controller.D) != 0):
        raise ControlError("algebraic loop: both the plant and the controller have a direct term")
    return iu, iy


def _closed(loop: Loop) -> control.StateSpace:
    plant, controller = loop.plant, loop.controller
    iu, iy, other = list(loop.iu), list(loop.iy), list(loop.other_inputs)
    Ap, Bp, Cp, Dp = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C, plant.D))
    Ac, Bc, Cc, Dc = (np.asarray(M, dtype=float) for M in
                      (controller.A, controller.B, controller.C, controller.D))
    nc = Ac.shape[0]
    p_all = Cp.shape[0]
    Bu, Cy = Bp[:, iu], Cp[iy]
    Dyu = Dp[np.ix_(iy, iu)]
    Bo, Dyo = Bp[:, other], Dp[np.ix_(iy, other)]
    # With Dc Dyu = 0 (checked): ym = Cy xp + Dyu u + Dyo w + n,  u = Cc xc + Dc ym
    # => u = Cc xc + Dc (Cy xp + Dyo w + n) + Dc Dyu u, and Dc Dyu = 0 when either is zero.
    DcCy = Dc @ Cy
    A = np.block([[Ap + Bu @ DcCy, Bu @ Cc + 0 * Bu @ Cc],
                  [Bc @ (Cy + Dyu @ DcCy), Ac + Bc @ Dyu @ Cc]])
    # inputs: d (at the D/A, same path as u), n (sensor noise), w (other plant inputs)
    Bd = np.vstack([Bu, Bc @ Dyu])
    Bn = np.vstack([Bu @ Dc, Bc + Bc @ Dyu @ Dc])
    Bw = np.vstack([Bo + Bu @ Dc @ Dyo, Bc @ (Dyo + Dyu @ Dc @ Dyo)])
    B = np.hstack([Bd, Bn, Bw])
    # outputs: all plant outputs (y = Cp xp + Dp v, v the plant input vector), then u
    u_x = np.hstack([DcCy, Cc])
    u_in = np.hstack([np.zeros((len(iu), len(iu))), Dc, Dc @ Dyo])
    Cpu, Dpu, Dpo = Cp, Dp[:, iu], Dp[:, other]
    C = np.vstack([np.hstack([Cpu, np.zeros((p_all, nc))]) + Dpu @ u_x, u_x])
    D = np.vstack([np.hstack([Dpu, np.zeros((p_all, len(iy))), Dpo]) + Dpu @ u_in, u_in])
    p_in, p_out = list(plant.input_labels), list(plant.output_labels)
    inputs = ([f"d_{p_in[j]}" for j in iu] + [f"n_{p_out[i]}" for i in iy]
              + [p_in[j] for j in other])
    outputs = p_out + [f"u_{p_in[j]}" for j in iu]
    return control.ss(A, B, C, D, plant.dt, inputs=inputs, outputs=outputs, name="closed_loop")
