"""Simulated closed-loop records of two structures for the closed-loop identification tests
(issue 34, acceptance 3) and ``benchmarks/bench_closedloop.py``.

Each truth is a structure's discrete plant with two inputs: the actuator (measured, driven
by the controller plus a small dither) and an unmeasured force elsewhere on the structure.
The controller is an LQG regulator designed on the truth (``control.dlqr``/``control.dlqe``)
in predictor form, so ``u_k`` uses the outputs up to ``k - 1`` only (a sampled controller's
computation delay). Two settings of the unmeasured excitation (:func:`record`):

- ``"output"`` (the acceptance's setting): a white disturbance added at the outputs, fed
  back by the controller, so the input is mostly that disturbance. White, because it is
  what a sensor-side disturbance with no model of its own looks like, and because it is
  the case where the true innovations model has ``K = 0`` (the predictor's poles are the
  plant's, and a consistent method has nothing to hide behind a noise model). Its truths
  are reduced to the modes the *actuator* excites best (``dominant_from="actuator"``): the
  actuator is then the only way into the structure.
- ``"force"`` (harder): the structure's unmeasured force, so the disturbance reaches the
  outputs through the structure's own modes, as the measured cantilever's push did.

- :func:`testbed_truth`: the thesis testbed (:func:`trussid.testbed.testbed_plant`: channel
  ``ch1`` in, accelerometers ``acc1, acc2`` out, an unmeasured force on the UDF), reduced
  to its three modes with the largest response above 10 Hz (modal truncation, exact poles
  and residues): 117.8/138.4/166.0 Hz from both inputs, 138.4/166.0/194.4 Hz from the
  actuator; 0.25 % damping, 1.6 kHz.
- :func:`grid_truth`: the cantilevered steel grid of ``tests/campaign/structures.py``
  (:func:`force_grid`: one shaker as the actuator, the other corner's shaker as the
  unmeasured force, two displacement sensors where the campaign has accelerometers: with
  accelerometers the force's direct term needs two delay states and every method failed),
  1 % damping, its three lowest modes (9.6, 13.5 and 14.0 Hz) or the actuator's two
  dominant ones (9.6, 13.5 Hz), 400 Hz.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from trussid.plid.experiment import simulate


#: Samples of each closed-loop record.
SAMPLES = 20000
#: The grid's sample time [s]: 400 Hz (its three lowest modes lie at 9.6-14 Hz; the campaign
#: samples it at 1 kHz for its higher modes).
GRID_DT = 2.5e-3


@dataclass(frozen=True)
class Truth:
    """A truth: ``plant`` (inputs actuator then disturbance) and its modes."""

    name: str
    plant: control.StateSpace
    frequencies_hz: np.ndarray
    damping: np.ndarray


def _modes(G):
    lam = np.linalg.eigvals(np.asarray(G.A, float)).astype(complex)
    s = np.log(lam[lam.imag > 0]) / G.dt
    f, z = np.abs(s) / (2 * np.pi), -s.real / np.abs(s)
    o = np.argsort(f)
    return f[o], z[o]


def _dominant(G, keep: int, fmin: float = 10.0, inputs=None):
    """Modal truncation of ``G`` to its ``keep`` complex modes above ``fmin`` with the
    largest peak response (residue norm over damping) from ``inputs`` (default all)."""
    from trussid.lqg.modal import modal_truncation, real_modal_basis

    T, blocks = real_modal_basis(G.A)
    Ti = np.linalg.inv(T)
    B, C = Ti @ np.asarray(G.B), np.asarray(G.C) @ T
    Bs = B if inputs is None else B[:, inputs]
    score = []
    for idx, lam in blocks:
        if lam.imag <= 0:                   # real poles (the chain's delays at z = 0)
            score.append(-1.0)
            continue
        s = np.log(lam) / G.dt
        f, z = abs(s) / (2 * np.pi), -s.real / abs(s)
        ok = lam.imag > 0 and f > fmin and z < 0.2
        score.append(np.linalg.norm(C[:, idx]) * np.linalg.norm(Bs[idx]) / max(z, 1e-6) / f
                     if ok else -1.0)
    top = np.argsort(score)[::-1][:keep]
    red, _ = modal_truncation(G, np.sort(top))
    return control.ss(red.A, red.B, red.C, np.zeros_like(np.asarray(red.D)), G.dt)


def testbed_truth(dominant_from: str = "both") -> Truth:
    """The testbed reduced to the three modes with the largest response from ``"both"``
    inputs (the structural-force records) or from the ``"actuator"`` alone (the
    output-disturbance records: there the actuator is the only way into the structure,
    and the modes the unmeasured force excites best are nearly unseen by it)."""
    from trussid.testbed import build_testbed, testbed_plant, udf_wrench

    tbm = build_testbed()
    tp = testbed_plant(tbm, disturbances=udf_wrench(tbm, ("fy",)))
    G = tp.discrete
    iu = [list(G.input_labels).index(k) for k in ("ch1", "udf_fy")]
    iy = [list(G.output_labels).index(k) for k in ("acc1", "acc2")]
    G = control.ss(G.A, np.asarray(G.B)[:, iu], np.asarray(G.C)[iy], 0, G.dt)
    red = _dominant(G, 3, inputs=_inputs(dominant_from))
    return Truth("testbed", red, *_modes(red))


def _inputs(dominant_from):
    if dominant_from not in ("both", "actuator"):
        raise ValueError(f"dominant_from must be 'both' or 'actuator', not {dominant_from!r}")
    return None if dominant_from == "both" else [0]


def grid_truth(dominant_from: str = "both") -> Truth:
    """The grid's three lowest modes (``"both"``), or the two of its lowest eight with the
    largest response from the actuator (``"actuator"``: 9.6 and 13.5 Hz; the 14.0 Hz mode
    is nearly unseen from the actuator's corner, the next, 63 Hz, peaks 40x lower)."""
    from trussid import fem

    from tests.campaign import structures

    model, _ = structures.force_grid()
    inputs = _inputs(dominant_from)
    modes = fem.solve_modes(model, n_modes=3 if inputs is None else 8)
    ids = list(np.asarray(modes.node_ids))

    def load(node):
        f = np.zeros(6 * len(ids))
        f[6 * ids.index(node) + 2] = 1.0
        return f

    sensors = [fem.Sensor(403, (0.0, 0.0, 1.0), "displacement", 1.0, name="x_403"),
               fem.Sensor(202, (0.0, 0.0, 1.0), "displacement", 1.0, name="x_202")]
    Gc = fem.modal_plant(modes, np.column_stack([load(401), load(404)]), sensors,
                         damping=0.01)
    G = control.c2d(Gc, GRID_DT, method="zoh")
    # a force to an accelerometer has a direct term: the record's A/D samples before the
    # D/A updates, which delays it by one sample (strictly proper, as the testbed's chain)
    G = _delayed(G) if np.any(np.asarray(G.D)) else G
    if inputs is not None:
        G = _dominant(G, 2, fmin=1.0, inputs=inputs)
    return Truth("grid", G, *_modes(G))


def _delayed(G):
    """``z^-1 G``: the direct term becomes one sample late (strictly proper)."""
    A, B, C, D = (np.asarray(M, float) for M in (G.A, G.B, G.C, G.D))
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    Aa = np.block([[A, np.zeros((n, p))], [C, np.zeros((p, p))]])
    Ba = np.vstack([B, D])
    Ca = np.hstack([np.zeros((p, n)), np.eye(p)])
    return control.ss(Aa, Ba, Ca, 0, G.dt)


def lqg(truth: Truth, control_weight: float = 100.0,
        design_noise: str = "force") -> control.StateSpace:
    """LQG regulator of the truth's actuator in predictor form, ``(A_c, B_c, C_c, 0)``:
    ``xc+ = A xc + B u + L (y - C xc)``, ``u = -F xc``. ``control_weight`` (relative to the
    actuator's output energy) 100 is a gentle loop (the testbed's modes go from 0.25 % to
    0.4-10 % damping); 1 damps them so far that the open-loop modes barely show in the
    record (prediction error from the truth itself then drifts 1.5 % in frequency).
    ``design_noise``: where the Kalman filter's design assumes the process noise enters,
    the unmeasured ``"force"`` (the structural-force records) or the ``"actuator"`` (the
    output-disturbance records, whose actuator-dominant modes the force barely reaches:
    a filter designed on it would not see them), with sensor noise 1 % of its output."""
    A, B, C = (np.asarray(M, float) for M in (truth.plant.A, truth.plant.B, truth.plant.C))
    if design_noise not in ("force", "actuator"):
        raise ValueError(f"design_noise must be 'force' or 'actuator', not {design_noise!r}")
    Bu = B[:, :1]
    Bd = B[:, 1:] if design_noise == "force" else Bu
    p = C.shape[0]
    Qx = C.T @ C
    Ru = control_weight * np.trace(Bu.T @ Qx @ Bu) * np.eye(1)
    F, _, _ = control.dlqr(A, Bu, Qx, Ru)
    yv = C @ Bd
    # process noise scaled to unit output (slycot's DARE fails on the actuator's tiny B)
    L, _, _ = control.dlqe(A, Bd / np.sqrt(np.mean(yv ** 2)), C, np.eye(1), 1e-2 * np.eye(p))
    Ac = A - Bu @ F - L @ C
    return control.ss(Ac, L, -F, np.zeros((1, p)), truth.plant.dt)


def record(truth: Truth, controller, n: int, *, dither_share: float = 0.1,
           noise_share: float = 0.01, seed: int = 0, disturbance: str = "force"):
    """``(u, y, r)`` of the loop, excited by an unmeasured disturbance.

    ``disturbance="force"``: a white unit force on the structure (the truth's second input),
    plus sensor noise of ``noise_share`` of each output's RMS. ``"output"``: a white
    disturbance added at the outputs (the truth's second input unused), each output's of
    the RMS that output has under the unit force in open loop (so both outputs are
    disturbed alike relative to their structural response), sensor noise on top; the
    controller feeds it back like any output. White dither ``r`` of ``dither_share`` of
    the control signal's RMS without it; ``controller=None``: open loop, ``u = r`` unit.
    """
    G = truth.plant
    A, B, C = (np.asarray(M, float) for M in (G.A, G.B, G.C))
    p = C.shape[0]
    if disturbance not in ("force", "output"):
        raise ValueError(f"disturbance must be 'force' or 'output', not {disturbance!r}")
    rng = np.random.default_rng(seed)
    d = rng.standard_normal((n, 1))
    v0 = rng.standard_normal((n, p))
    w = rng.standard_normal((n, 1))
    wo = rng.standard_normal((n, p)) if disturbance == "output" else np.zeros((n, p))
    if disturbance == "output":
        level = np.std(simulate(control.ss(A, B[:, 1:], C, 0, G.dt), d), axis=0)
        d = np.zeros_like(d)
        wo = level * wo
    if controller is None:
        u = w
        y = simulate(control.ss(A, B, C, 0, G.dt), np.hstack([u, d])) + wo
        y = y + noise_share * np.std(y, axis=0) * v0
        return u, y, u

    Ac, Bc, Cc = (np.asarray(M, float) for M in (controller.A, controller.B, controller.C))
    nc = Ac.shape[0]
    # the loop is linear: one augmented system with inputs [r, d, v] and outputs [u, y]
    # (v: whatever is added at the outputs, the output disturbance and sensor noise)
    Aa = np.block([[A, B[:, :1] @ Cc], [Bc @ C, Ac]])
    Ba = np.block([[B[:, :1], B[:, 1:], np.zeros((A.shape[0], p))],
                   [np.zeros((nc, 1)), np.zeros((nc, 1)), Bc]])
    Ca = np.block([[np.zeros((1, A.shape[0])), Cc], [C, np.zeros((p, nc))]])
    Da = np.block([[np.ones((1, 1)), np.zeros((1, 1 + p))],
                   [np.zeros((p, 2)), np.eye(p)]])
    loop = control.ss(Aa, Ba, Ca, Da, G.dt)

    def run(r, v):
        out = simulate(loop, np.hstack([r, d, v]))
        return out[:, :1], out[:, 1:]

    _, y_free = run(np.zeros((n, 1)), wo)
    v = wo + noise_share * np.std(y_free, axis=0) * v0
    u_fb, _ = run(np.zeros((n, 1)), v)
    r = dither_share * np.std(u_fb) * w
    u, y = run(r, v)
    return u, y, r
