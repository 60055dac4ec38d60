"""A discrete controller on a discrete plant: closed loop, damping per mode, margins, H2.

Conventions: the plant's control inputs are the D/A commands named like the controller's
outputs, its sensor outputs are named like the controller's inputs; ``u = controller(y)``
(no sign hidden). The closed loop has the plant's inputs as additive disturbances at the
D/A (``d_<name>``), sensor noise at each sensor (``n_<name>``), every other plant input
unchanged, and as outputs the plant's outputs and the commands (``u_<name>``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control
import numpy as np

from trussid.plid.frf import frequency_response
from trussid.plid.modal import assign_pairs, s_plane

from .errors import ControlError
from .modal import freq_damping, modal_data



#: Prefixes trussid's CSV convention puts on channel names (``u_shaker``, ``y_acc_tip_z``).
CSV_PREFIXES = ("u_", "y_")


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
    try:
        _check_pair(plant, controller)
    except ControlError as exc:
        raise ControlError(f"{label}: {exc}") if label != "plant" else exc from None


def _check_pair(plant, controller):
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
    iu = [p_in.index(s) for s in controller.output_labels]
    iy = [p_out.index(s) for s in controller.input_labels]
    Dp = np.asarray(plant.D)[np.ix_(iy, iu)]
    if np.any(Dp != 0) and np.any(np.asarray(controller.D) != 0):
        raise ControlError("algebraic loop: both the plant and the controller have a direct term")
    return iu, iy


def closed_loop(plant, controller) -> control.StateSpace:
    """The loop ``u = controller(y_measured)`` around ``plant`` (module docstring).

    Returns
    -------
    control.StateSpace
        States ``[plant; controller]``; inputs ``d_<u>`` (one per controlled plant input),
        ``n_<y>`` (one per measured output), then the plant's other inputs; outputs the
        plant's outputs then ``u_<u>``.
    """
    iu, iy = _check_pair(plant, controller)
    Ap, Bp, Cp, Dp = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C, plant.D))
    Ac, Bc, Cc, Dc = (np.asarray(M, dtype=float) for M in
                      (controller.A, controller.B, controller.C, controller.D))
    npl, nc = Ap.shape[0], Ac.shape[0]
    m_all, p_all = Bp.shape[1], Cp.shape[0]
    Bu, Cy = Bp[:, iu], Cp[iy]
    Dyu = Dp[np.ix_(iy, iu)]
    other = [j for j in range(m_all) if j not in iu]
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


# --------------------------------------------------------------------------- damping per mode


@dataclass
class ModeRow:
    """One open-loop plant mode in the closed loop."""

    frequency_hz: float
    damping_open: float
    residue_open: float
    frequency_closed: float
    damping_tracked: float
    damping_worst_visible: float
    visible_controller_poles: int
    dominant: bool


def damping_table(plant, controller, *, band=(40.0, 450.0), dominant_fraction: float = 0.25,
                  visible_fraction: float = 0.1, floor_fraction: float = 0.01) -> dict:
    """Closed-loop poles matched to the plant's open-loop modes.

    Each closed-loop pole is assigned (Hungarian assignment) to the open-loop plant mode
    that holds the largest share of its eigenvector's plant part (in the plant's modal
    coordinates); the poles left over are controller poles and belong to the plant mode
    nearest in the s-plane. Every closed-loop pole also *belongs* to the open-loop mode
    nearest to it in the s-plane; it is *visible* when its residue from the D/A
    disturbance to the sensors is at least ``visible_fraction`` of that mode's open-loop
    residue and at least ``floor_fraction`` of the largest open-loop residue. The worst
    visible damping of a mode is the least damping among its tracked pole and the visible
    poles that belong to it: an estimator pole left at 1 % near a mode rings in the
    response as the mode would, whichever eigenvector the assignment gave the mode.

    Dominant modes: residue at least ``dominant_fraction`` of the largest in the band.

    Returns
    -------
    dict
        ``rows`` (list of :class:`ModeRow` as dicts, plant modes in ``band``), ``stable``,
        ``spectral_radius``, ``closed_loop_poles`` (complex), ``controller_poles``.

    Examples
    --------
    The plant modes of :func:`trussid.lqg.design_lqg`'s example, open and closed loop:

    >>> import control
    >>> import numpy as np
    >>> from trussid.lqg import damping_table, design_lqg
    >>> from trussid.plid import excitation, simulate
    >>> s = control.tf("s")
    >>> G = sum(g * (2 * np.pi * f) ** 2 / (s**2 + 0.01 * 2 * np.pi * f * s + (2 * np.pi * f) ** 2)
    ...         for f, g in ((50.0, 1.0), (120.0, 0.5)))
    >>> d = control.c2d(control.ss(G), 1e-3)
    >>> plant = control.ss(d.A, d.B, d.C, d.D, 1e-3, inputs=["u"], outputs=["y"])
    >>> u = excitation("white", 2000, fs=1000.0, seed=1)
    >>> y = simulate(plant, u) + 1e-3 * np.random.default_rng(0).standard_normal((2000, 1))
    >>> table = damping_table(plant, design_lqg(plant, u, y, target_damping=0.05).controller,
    ...                       band=(10.0, 450.0))
    >>> table["stable"]
    True
    >>> for row in table["rows"]:
    ...     print(f"{row['frequency_hz']:.0f} Hz: {100 * row['damping_open']:.1f} % -> "
    ...           f"{100 * row['damping_worst_visible']:.1f} %")
    50 Hz: 0.5 % -> 4.9 %
    120 Hz: 0.5 % -> 4.9 %
    """
    iu, iy = _check_pair(plant, controller)
    cl = closed_loop(plant, controller)
    npl = plant.nstates
    dt = plant.dt
    Ap, Bp, Cp = np.asarray(plant.A), np.asarray(plant.B)[:, iu], np.asarray(plant.C)[iy]
    ol = modal_data(Ap, Bp, Cp, dt)
    Acl = np.asarray(cl.A)
    lam, V = np.linalg.eig(Acl)
    Vinv = np.linalg.inv(V)
    nu, ny = len(iu), len(iy)
    Bd, Cy = np.asarray(cl.B)[:, :nu], np.asarray(cl.C)[iy]
    CV, WB = Cy @ V, Vinv @ Bd
    res_cl = np.array([np.linalg.norm(np.outer(CV[:, j], WB[j]), 2) for j in range(lam.size)])
    # share of each closed-loop eigenvector's plant part in each open-loop plant mode
    proj = np.abs(ol.Vinv @ V[:npl])
    share = proj / np.maximum(np.linalg.norm(proj, axis=0, keepdims=True), 1e-300)
    tracked = assign_pairs(-share)  # every open-loop mode gets a closed-loop pole
    is_ctrl = np.ones(lam.size, bool)
    is_ctrl[tracked[tracked >= 0]] = False
    f_cl, z_cl = freq_damping(lam, dt)
    s_ol, s_cl = s_plane(ol.poles, dt), s_plane(lam, dt)
    # every closed-loop pole also belongs to the open-loop mode nearest in the s-plane: a
    # pole whose eigenvector the assignment gave to a neighbour still rings at this mode
    owner = np.argmin(np.abs(s_ol[None, :] - s_cl[:, None]), axis=1)
    lo, hi = band
    up = (ol.poles.imag > 0)
    in_band = np.flatnonzero(up & (ol.frequency_hz >= lo) & (ol.frequency_hz <= hi))
    rmax_band = ol.residue[in_band].max() if in_band.size else 0.0
    rmax = ol.residue.max()
    rows = []
    for i in in_band[np.argsort(ol.frequency_hz[in_band])]:
        j = tracked[i]
        near = [k for k in np.flatnonzero((owner == i) & (lam.imag > 0)) if k != j
                and res_cl[k] >= max(visible_fraction * ol.residue[i], floor_fraction * rmax)]
        ctrl = [k for k in near if is_ctrl[k]]
        zs = [z_cl[j]] + [z_cl[k] for k in near]
        rows.append(ModeRow(float(ol.frequency_hz[i]), float(ol.damping[i]), float(ol.residue[i]),
                            float(f_cl[j]), float(z_cl[j]), float(min(zs)), len(ctrl),
                            bool(ol.residue[i] >= dominant_fraction * rmax_band)).__dict__)
    rho = float(np.max(np.abs(lam)))
    return {"rows": rows, "stable": rho < 1, "spectral_radius": rho, "closed_loop_poles": lam,
            "controller_poles": lam[is_ctrl], "closed_loop": cl}


# --------------------------------------------------------------------------- norms


def h2_norm(sys) -> float:
    """H2 norm of a stable discrete system, ``sqrt(sum_k ||h[k]||_F^2)``.

    The Gramian is solved in modal coordinates, ``X_ij = (B~ B~^H)_ij / (1 - l_i conj(l_j))``:
    :func:`scipy.linalg.solve_discrete_lyapunov` returns negative variances on the
    177-state closed loop, whose 0.4-1 Hz suspension poles sit within 1e-4 of z = 1.
    """
    A, B, C, D = (np.asarray(M, dtype=float) for M in (sys.A, sys.B, sys.C, sys.D))
    if A.shape[0] == 0:
        return float(np.linalg.norm(D))
    lam, V = np.linalg.eig(A)
    if np.max(np.abs(lam)) >= 1:
        return math.inf
    Bt = np.linalg.solve(V, B)
    Ct = C @ V
    X = (Bt @ Bt.conj().T) / (1 - lam[:, None] * lam.conj()[None, :])
    val = np.real(np.trace(Ct @ X @ Ct.conj().T)) + np.sum(D**2)
    return float(math.sqrt(max(val, 0.0)))


def margin_grid(systems, dt: float, n_base: int = 1500) -> np.ndarray:
    """Frequencies [Hz] for margins: a linear grid to Nyquist plus, around every lightly
    damped pole of ``systems``, 41 points within +-6 half-power bandwidths (a 0.25 %-damped
    mode at 200 Hz is 1 Hz wide; a uniform grid would step over it)."""
    nyq = 0.5 / dt
    parts = [np.linspace(0.0, nyq, n_base)]
    for sys in systems:
        f, z = freq_damping(np.linalg.eigvals(np.asarray(sys.A)), dt)
        keep = (z < 0.3) & (f > 0) & (f < nyq)
        for fi, zi in zip(f[keep], z[keep]):
            w = max(zi * fi, 1e-3)
            parts.append(fi + w * np.linspace(-6, 6, 41))
    g = np.unique(np.concatenate(parts))
    return g[(g >= 0) & (g <= nyq)]


def _disk_from_alpha(alpha):
    alpha = np.asarray(alpha, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        gm = np.where(alpha < 2, 20 * np.log10((1 + alpha / 2) / (1 - alpha / 2)), np.inf)
        pm = np.degrees(2 * np.arctan(alpha / 2))
    return gm, pm


def disk_margins(plant, controller, f=None) -> dict:
    """Balanced (skew 0) disk margins at the plant input.

    ``L = -Ck P`` (the loop broken at the D/A, negative-feedback sign), ``S = (I + L)^-1``,
    margin ``alpha = 1 / mu(S - I/2)`` with ``mu`` over independent complex perturbations of
    each channel (slycot's ``ab13md``, as :func:`control.disk_margins` uses). Loop at a time:
    each channel broken with the others closed. Hand-written around ``ab13md`` because
    :func:`control.disk_margins` evaluates the 177-state loop by dense solves at each of
    thousands of frequencies; the result is checked against it in the tests.

    Returns
    -------
    dict
        ``mimo`` {alpha, gain_db, phase_deg, frequency_hz}, ``loops`` (one such dict per
        channel), ``n_frequencies`` (grid size), ``mu_evaluations`` (ab13md calls).
    """
    from slycot import ab13md

    iu, iy = _check_pair(plant, controller)
    P = control.ss(np.asarray(plant.A), np.asarray(plant.B)[:, iu], np.asarray(plant.C)[iy],
                   np.asarray(plant.D)[np.ix_(iy, iu)], plant.dt)
    if f is None:
        f = margin_grid([P, controller], plant.dt)
    # order the controller's inputs as the plant's outputs iy are ordered: they are, by name
    Hp = frequency_response(P, f)
    Hc = frequency_response(controller, f)
    L = -np.einsum("fij,fjk->fik", Hc, Hp)
    m = L.shape[1]
    eye = np.eye(m)
    S = np.linalg.inv(eye[None] + L)
    M = S - 0.5 * eye[None]
    # mu lies between the spectral radius and the largest singular value of M; ab13md (5 ms
    # a call) is needed only where the upper bound reaches the largest lower bound.
    upper = np.linalg.norm(M, ord=2, axis=(1, 2))
    lower = np.max(np.abs(np.linalg.eigvals(M)), axis=1)
    mu = lower.copy()
    need = np.flatnonzero(upper >= lower.max())
    mu[need] = [ab13md(M[k], np.ones(m, int), 2 * np.ones(m, int))[0] for k in need]
    alpha = 1.0 / mu
    k = int(np.argmin(alpha))
    gm, pm = _disk_from_alpha(alpha[k])
    out = {"mimo": {"alpha": float(alpha[k]), "gain_db": float(gm), "phase_deg": float(pm),
                    "frequency_hz": float(f[k])}, "loops": [], "n_frequencies": int(f.size),
           "mu_evaluations": int(need.size)}
    for i in range(m):
        rest = [j for j in range(m) if j != i]
        # L_i = L_ii - L_ir (I + L_rr)^-1 L_ri : loop i with the others closed
        Lrr = L[:, rest][:, :, rest]
        # b as a stack of column matrices (f, m-1, 1): numpy >= 2 reads a (f, m-1) b as one
        # matrix broadcast over the stack, not as a stack of vectors.
        x = np.linalg.solve(np.eye(m - 1)[None] + Lrr, L[:, rest, i][:, :, None])[:, :, 0]
        Li = L[:, i, i] - np.einsum("fr,fr->f", L[:, i, rest], x)
        a = 1.0 / np.abs(1.0 / (1.0 + Li) - 0.5)
        k = int(np.argmin(a))
        gm, pm = _disk_from_alpha(a[k])
        out["loops"].append({"channel": list(controller.output_labels)[i], "alpha": float(a[k]),
                             "gain_db": float(gm), "phase_deg": float(pm),
                             "frequency_hz": float(f[k])})
    return out


# --------------------------------------------------------------------------- time domain


def simulate_loop(plant, controller, d, noise_rms, *, bits: int | None, dac_full_scale,
                  adc_full_scale, seed: int = 0) -> dict:
    """Closed loop in the time domain with quantising, clipping converters and sensor noise.

    ``y_meas = ADC(C xp + D v + n)``, ``u = controller(y_meas)``, the D/A sends
    ``v = DAC(u + d)``. A plant feed-through ``D`` (accelerometers) is taken with a
    controller without one (then the command of sample k comes first, the measurement it
    moves after it); both having one is an algebraic loop, refused.

    Parameters
    ----------
    d : (N, m) float
        Disturbance added to the command at the D/A [V] (e.g. the demo's excitation).
    noise_rms : float or (p,) float
        White sensor noise RMS [V].
    bits : int or None
        D/A and A/D resolution (the lab's; no default); ``None``: ideal converters (no
        quantising, no clipping).
    dac_full_scale, adc_full_scale : float or per-channel array
        Converter ranges +-V (the lab's; no default).

    Returns
    -------
    dict
        ``y`` (N, p) measured, ``u`` (N, m) commands, ``dac`` (N, m) what the D/A sent,
        ``u_rms`` (m,), ``dac_clipped`` and ``adc_clipped`` sample counts per channel,
        ``dac_lsb`` and ``adc_lsb`` the converters' LSB per channel [V].
    """
    iu, iy = _check_pair(plant, controller)
    Ap, Bp, Cp = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C))
    Bu, Cy = Bp[:, iu], Cp[iy]
    Dyu = np.asarray(plant.D, dtype=float)[np.ix_(iy, iu)]
    Ac, Bc, Cc, Dc = (np.asarray(M, dtype=float) for M in
                      (controller.A, controller.B, controller.C, controller.D))
    command_first = not np.any(Dc != 0)  # _check_pair refused Dc and Dyu both non-zero
    d = np.asarray(d, dtype=float)
    N, m, p = d.shape[0], len(iu), len(iy)
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((N, p)) * np.broadcast_to(np.asarray(noise_rms, float), (p,))
    if bits is not None:
        lsb_a = 2.0 * np.broadcast_to(np.asarray(adc_full_scale, float), (p,)) / 2**bits
        lsb_d = 2.0 * np.broadcast_to(np.asarray(dac_full_scale, float), (m,)) / 2**bits
    if bits is None:  # ideal converters: no quantising, no clipping
        lsb_a, lsb_d = np.ones(p), np.ones(m)
        lo, hi = -np.inf, np.inf
        rnd = np.asarray
    else:
        lo, hi = -(2 ** (bits - 1)), 2 ** (bits - 1) - 1
        rnd = np.round
    xp, xc = np.zeros(Ap.shape[0]), np.zeros(Ac.shape[0])
    Y, U, V = np.empty((N, p)), np.empty((N, m)), np.empty((N, m))
    clip_a, clip_d = np.zeros(p, int), np.zeros(m, int)
    # A sample-by-sample loop: the converters are not linear, so lsim cannot do it.
    for k in range(N):
        if command_first:
            uk = Cc @ xc
            cd = rnd((uk + d[k]) / lsb_d)
            v = np.clip(cd, lo, hi) * lsb_d
            ca = rnd((Cy @ xp + Dyu @ v + noise[k]) / lsb_a)
            ym = np.clip(ca, lo, hi) * lsb_a
        else:
            ca = rnd((Cy @ xp + noise[k]) / lsb_a)
            ym = np.clip(ca, lo, hi) * lsb_a
            uk = Cc @ xc + Dc @ ym
            cd = rnd((uk + d[k]) / lsb_d)
            v = np.clip(cd, lo, hi) * lsb_d
        clip_a += (ca < lo) | (ca > hi)
        clip_d += (cd < lo) | (cd > hi)
        xp = Ap @ xp + Bu @ v
        xc = Ac @ xc + Bc @ ym
        Y[k], U[k], V[k] = ym, uk, v
    return {"y": Y, "u": U, "dac": V, "u_rms": np.sqrt(np.mean(U**2, axis=0)),
            "y_rms": np.sqrt(np.mean(Y**2, axis=0)), "dac_clipped": clip_d.tolist(),
            "adc_clipped": clip_a.tolist(), "dac_lsb": lsb_d.tolist(), "adc_lsb": lsb_a.tolist()}
