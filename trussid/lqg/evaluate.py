"""A discrete controller on a discrete plant: damping per mode, margins, H2, a simulation
with converters.

The loop itself (channels matched by name, the closed loop and its conventions) is
:class:`trussid.lqg.loop.Loop`; every result here is a frozen dataclass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np

from trussid.plid.frf import frequency_response
from trussid.plid.modal import assign_pairs, s_plane

from .errors import ControlError
from .loop import Loop, check_pair, match_names
from .modal import freq_damping, modal_data

__all__ = ["closed_loop", "ModeRow", "DampingTable", "damping_table", "TARGET_MATCH",
           "MODE_DAMPING_MAX", "PAIRINGS", "h2_norm",
           "margin_grid", "Margin", "ChannelMargin", "DiskMargins", "disk_margins",
           "LoopSimulation", "simulate_loop", "frequency_response", "check_pair", "match_names"]

def closed_loop(plant, controller) -> control.StateSpace:
    """The loop ``u = controller(y_measured)`` around ``plant`` (``Loop.of(plant,
    controller).closed``, :class:`trussid.lqg.loop.Loop`): states ``[plant; controller]``;
    inputs ``d_<u>``, ``n_<y>``, then the plant's other inputs; outputs the plant's outputs
    then ``u_<u>``."""
    return Loop.of(plant, controller).closed


# --------------------------------------------------------------------------- damping per mode


@dataclass(frozen=True)
class ModeRow:
    """One open-loop plant mode in the closed loop (:func:`damping_table`).

    Attributes
    ----------
    frequency_hz, damping_open, residue_open : float
        The open-loop mode [Hz], [-] and its residue from the D/A to the sensors.
    frequency_closed, damping_tracked : float
        The closed-loop pole tracked to the mode [Hz], [-].
    damping_worst_visible : float
        The least damping among the tracked pole and the visible poles near the mode [-].
    visible_controller_poles : int
        Controller poles among those visible near the mode.
    dominant : bool
        A dominant mode (a design target, or by residue: :func:`damping_table`).
    """

    frequency_hz: float
    damping_open: float
    residue_open: float
    frequency_closed: float
    damping_tracked: float
    damping_worst_visible: float
    visible_controller_poles: int
    dominant: bool


@dataclass(frozen=True)
class DampingTable:
    """The plant's modes in a band under a controller (:func:`damping_table`).

    Attributes
    ----------
    rows : tuple of ModeRow
        Plant modes in the band, ascending frequency.
    stable : bool
    spectral_radius : float
        Largest closed-loop pole magnitude.
    closed_loop_poles, controller_poles : (n,) complex
        Every closed-loop pole, and those the assignment gave no plant mode.
    loop : Loop
        The loop the table was made on (its closed loop: ``loop.closed``).
    reference_damping : tuple of float
        ``pairing="window"``: each row's open-loop damping by the same window rule (the
        reference of :attr:`others_ratio`; on an identified model a well damped spurious
        mode next to a lightly damped one would otherwise read as a large loss). Empty for
        the eigenvector pairing.
    """

    rows: tuple
    stable: bool
    spectral_radius: float
    closed_loop_poles: np.ndarray
    controller_poles: np.ndarray
    loop: Loop
    reference_damping: tuple = ()

    @property
    def dominant(self) -> tuple:
        """The dominant rows."""
        return tuple(r for r in self.rows if r.dominant)

    @property
    def others(self) -> tuple:
        """The other rows."""
        return tuple(r for r in self.rows if not r.dominant)

    @property
    def frequency_hz(self) -> np.ndarray:
        """Each row's open-loop frequency [Hz]."""
        return np.array([r.frequency_hz for r in self.rows])

    @property
    def dominant_mask(self) -> np.ndarray:
        """Which rows are dominant."""
        return np.array([r.dominant for r in self.rows], bool)

    @property
    def dominant_frequency_hz(self) -> np.ndarray:
        """The dominant modes' open-loop frequencies [Hz]."""
        return np.array([r.frequency_hz for r in self.dominant])

    @property
    def dominant_damping(self) -> np.ndarray:
        """The dominant modes' worst visible closed-loop damping [-]."""
        return np.array([r.damping_worst_visible for r in self.dominant])

    @property
    def others_ratio(self) -> float:
        """Least ratio of closed- to open-loop damping among the other rows (inf if none);
        the open-loop damping is :attr:`reference_damping` when set (``pairing="window"``),
        else each row's own."""
        ref = self.reference_damping or tuple(r.damping_open for r in self.rows)
        ratios = [r.damping_worst_visible / z for r, z in zip(self.rows, ref) if not r.dominant]
        return float(min(ratios)) if ratios else np.inf


#: A design target marks the plant mode nearest to it as dominant within this (relative).
TARGET_MATCH = 0.1
#: Weight of a closed-loop pole's relative s-plane distance from a plant mode against its
#: eigenvector share when :func:`damping_table` tracks the mode (breaks near-ties only).
TRACK_DISTANCE_WEIGHT = 0.5
#: A complex pole with more damping than this is no structural mode (filters, amplifiers).
MODE_DAMPING_MAX = 0.2
#: How :func:`damping_table` pairs closed-loop poles with plant modes.
PAIRINGS = ("eigenvector", "window")


def damping_table(plant, controller, *, band=(40.0, 450.0), targets_hz=(),
                  dominant_fraction: float = 0.25, visible_fraction: float = 0.1,
                  floor_fraction: float = 0.01, pairing: str = "eigenvector",
                  window: float = 0.03, n_dominant: int = 3) -> DampingTable:
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

    Parameters
    ----------
    plant, controller : control.StateSpace
        Discrete, matched by channel name (:class:`trussid.lqg.loop.Loop`).
    band : (float, float)
        Plant modes tabulated [Hz].
    targets_hz : sequence of float
        The design's target modes [Hz]: the tabulated mode nearest each (within
        :data:`TARGET_MATCH`) is dominant. Empty: the modes whose residue is at least
        ``dominant_fraction`` of the largest in the band are.
    dominant_fraction, visible_fraction, floor_fraction : float
        As above [-].
    pairing : {"eigenvector", "window"}
        ``"eigenvector"``: as above. ``"window"`` (the adaptive supervisor's, made for
        identified models whose eigenvectors are not trusted): the modes are the complex
        poles below :data:`MODE_DAMPING_MAX` damping, the ``n_dominant`` with the largest
        residue dominant; a mode's closed-loop damping is that of the least damped
        closed-loop pole within ``window`` (relative) of its frequency, or of the pole
        nearest it in the s-plane if none is; no controller poles are counted.
    window : float
        See ``pairing`` [-].
    n_dominant : int
        See ``pairing``.

    Returns
    -------
    DampingTable

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
    >>> table.stable
    True
    >>> for row in table.rows:
    ...     print(f"{row.frequency_hz:.0f} Hz: {100 * row.damping_open:.1f} % -> "
    ...           f"{100 * row.damping_worst_visible:.1f} %")
    50 Hz: 0.5 % -> 4.9 %
    120 Hz: 0.5 % -> 4.9 %
    """
    if pairing not in PAIRINGS:
        raise ControlError(f"pairing must be one of {', '.join(PAIRINGS)}, got {pairing!r}")
    loop = Loop.of(plant, controller)
    cl, P = loop.closed, loop.open_loop
    iy = list(loop.iy)
    npl = plant.nstates
    dt = plant.dt
    ol = modal_data(P.A, P.B, P.C, dt)
    if pairing == "window":
        return _window_table(loop, ol, band, n_dominant, window)
    Acl = np.asarray(cl.A)
    lam, V = np.linalg.eig(Acl)
    Vinv = np.linalg.inv(V)
    nu = len(loop.iu)
    Bd, Cy = np.asarray(cl.B)[:, :nu], np.asarray(cl.C)[iy]
    CV, WB = Cy @ V, Vinv @ Bd
    res_cl = np.array([np.linalg.norm(np.outer(CV[:, j], WB[j]), 2) for j in range(lam.size)])
    # share of each closed-loop eigenvector's plant part in each open-loop plant mode
    # weighted by how much each mode shows at the sensors: |w_i^H x| ||C v_i|| does not
    # depend on the plant's state basis or on how eig scaled v_i (|w_i^H x| alone does)
    proj = np.abs(ol.Vinv @ V[:npl]) * np.linalg.norm(np.asarray(P.C) @ ol.V, axis=0)[:, None]
    share = proj / np.maximum(np.linalg.norm(proj, axis=0, keepdims=True), 1e-300)
    s_ol, s_cl = s_plane(ol.poles, dt), s_plane(lam, dt)
    # Where the feedback puts two closed-loop poles near a mode (the plant pole and its
    # estimator pole), their eigenvectors mix and split the mode's share about evenly: a
    # perturbation of 1e-7 in A (a plant saved to a file and read back) flipped the 166 Hz
    # mode of the demo from its 7 %-damped pole at 165 Hz to a 40 %-damped one at 180 Hz.
    # The distance in the s-plane (relative to the mode's) breaks such near-ties.
    dist = np.abs(s_ol[:, None] - s_cl[None, :]) / np.maximum(np.abs(s_ol)[:, None], 1e-300)
    tracked = assign_pairs(-share + TRACK_DISTANCE_WEIGHT * dist)  # every mode gets a pole
    is_ctrl = np.ones(lam.size, bool)
    is_ctrl[tracked[tracked >= 0]] = False
    f_cl, z_cl = freq_damping(lam, dt)
    # every closed-loop pole also belongs to the open-loop mode nearest in the s-plane: a
    # pole whose eigenvector the assignment gave to a neighbour still rings at this mode
    owner = np.argmin(np.abs(s_ol[None, :] - s_cl[:, None]), axis=1)
    lo, hi = band
    up = (ol.poles.imag > 0)
    in_band = np.flatnonzero(up & (ol.frequency_hz >= lo) & (ol.frequency_hz <= hi))
    rmax_band = ol.residue[in_band].max() if in_band.size else 0.0
    rmax = ol.residue.max()
    order = in_band[np.argsort(ol.frequency_hz[in_band])]
    dominant = _dominant(ol.frequency_hz[order], ol.residue[order], targets_hz,
                         dominant_fraction * rmax_band)
    rows = []
    for i, dom in zip(order, dominant):
        j = tracked[i]
        near = [k for k in np.flatnonzero((owner == i) & (lam.imag > 0)) if k != j
                and res_cl[k] >= max(visible_fraction * ol.residue[i], floor_fraction * rmax)]
        ctrl = [k for k in near if is_ctrl[k]]
        zs = [z_cl[j]] + [z_cl[k] for k in near]
        rows.append(ModeRow(float(ol.frequency_hz[i]), float(ol.damping[i]), float(ol.residue[i]),
                            float(f_cl[j]), float(z_cl[j]), float(min(zs)), len(ctrl), bool(dom)))
    rho = float(np.max(np.abs(lam)))
    return DampingTable(tuple(rows), rho < 1, rho, lam, lam[is_ctrl], loop)


def _window_table(loop: Loop, ol, band, n_dominant: int, window: float) -> DampingTable:
    """:func:`damping_table` with ``pairing="window"``."""
    dt = loop.plant.dt
    keep = np.flatnonzero((ol.poles.imag > 0) & (ol.damping < MODE_DAMPING_MAX)
                          & (ol.frequency_hz >= band[0]) & (ol.frequency_hz <= band[1]))
    keep = keep[np.argsort(ol.frequency_hz[keep])]
    f, z, r = ol.frequency_hz[keep], ol.damping[keep], ol.residue[keep]
    dom = np.zeros(f.size, bool)
    dom[np.argsort(-r)[:n_dominant]] = True
    lam = np.linalg.eigvals(np.asarray(loop.closed.A))
    rho = float(np.max(np.abs(lam)))
    fcl, zcl = _window_damping(lam, f, z, dt, window)
    _, zol = _window_damping(np.linalg.eigvals(np.asarray(loop.plant.A)), f, z, dt, window)
    rows = tuple(ModeRow(float(fi), float(zi), float(ri), float(fc), float(zc), float(zc), 0,
                         bool(d)) for fi, zi, ri, fc, zc, d in zip(f, z, r, fcl, zcl, dom))
    return DampingTable(rows, rho < 1, rho, lam, lam[:0], loop,
                        tuple(float(v) for v in zol))


def _window_damping(lam, f, z, dt, window):
    """Per mode (f, z): the frequency and the least damping of the poles ``lam`` within
    ``window`` of f, or of the pole nearest the mode in the s-plane if none is."""
    fc, zc = freq_damping(lam, dt)
    up = lam.imag > 0
    s_cl = np.log(lam[up].astype(complex)) / dt
    out_f, out_z = np.empty(f.size), np.empty(f.size)
    for i, (fi, zi) in enumerate(zip(f, z)):
        near = np.flatnonzero(up & (np.abs(fc / fi - 1) <= window))
        if near.size:
            k = near[np.argmin(zc[near])]
        else:
            s0 = 2 * np.pi * fi * (-zi + 1j * np.sqrt(1 - zi**2))
            k = np.flatnonzero(up)[np.argmin(np.abs(s_cl - s0))]
        out_f[i], out_z[i] = fc[k], zc[k]
    return out_f, out_z


def _dominant(f, residue, targets_hz, floor) -> np.ndarray:
    """Which modes (frequencies ``f``, residues) are dominant: the nearest to each target
    within :data:`TARGET_MATCH`, or without targets those with a residue at least ``floor``."""
    if not len(targets_hz):
        return residue >= floor
    dom = np.zeros(f.size, bool)
    for t in targets_hz:
        if f.size:
            k = int(np.argmin(np.abs(f - t)))
            if abs(f[k] / t - 1) < TARGET_MATCH:
                dom[k] = True
    return dom


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


@dataclass(frozen=True)
class Margin:
    """A balanced disk margin: ``alpha`` [-], the gain [dB] and phase [deg] variations it
    allows, at the frequency where it is smallest [Hz]."""

    alpha: float
    gain_db: float
    phase_deg: float
    frequency_hz: float


@dataclass(frozen=True)
class ChannelMargin(Margin):
    """A loop-at-a-time disk margin (:class:`Margin`) of the actuator channel ``channel``."""

    channel: str = ""


@dataclass(frozen=True)
class DiskMargins:
    """What :func:`disk_margins` measured.

    Attributes
    ----------
    mimo : Margin
        Every channel perturbed at once (mu).
    loops : tuple of ChannelMargin
        Each channel broken with the others closed.
    n_frequencies, mu_evaluations : int
        Grid size, and the calls of slycot's ``ab13md``.
    """

    mimo: Margin
    loops: tuple
    n_frequencies: int
    mu_evaluations: int


def disk_margins(plant, controller, f=None) -> DiskMargins:
    """Balanced (skew 0) disk margins at the plant input.

    ``L = -Ck P`` (the loop broken at the D/A, negative-feedback sign), ``S = (I + L)^-1``,
    margin ``alpha = 1 / mu(S - I/2)`` with ``mu`` over independent complex perturbations of
    each channel (slycot's ``ab13md``, as :func:`control.disk_margins` uses). Loop at a time:
    each channel broken with the others closed. Hand-written around ``ab13md`` because
    :func:`control.disk_margins` evaluates the 177-state loop by dense solves at each of
    thousands of frequencies; the result is checked against it in the tests.

    Parameters
    ----------
    plant, controller : control.StateSpace
        Discrete, matched by channel name (:class:`trussid.lqg.loop.Loop`).
    f : array of float, optional
        Frequencies [Hz]; default :func:`margin_grid` of the plant and the controller.

    Returns
    -------
    DiskMargins
    """
    from slycot import ab13md

    P = Loop.of(plant, controller).open_loop
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
    mimo = Margin(float(alpha[k]), float(gm), float(pm), float(f[k]))
    loops = []
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
        loops.append(ChannelMargin(float(a[k]), float(gm), float(pm), float(f[k]),
                                   channel=list(controller.output_labels)[i]))
    return DiskMargins(mimo, tuple(loops), int(f.size), int(need.size))


# --------------------------------------------------------------------------- time domain


@dataclass(frozen=True)
class LoopSimulation:
    """What :func:`simulate_loop` recorded.

    Attributes
    ----------
    y : (N, p) float
        The measurements (after the A/D).
    u : (N, m) float
        The controller's commands.
    dac : (N, m) float
        What the D/A sent (command plus disturbance, quantised and clipped).
    u_rms, y_rms : (m,), (p,) float
        RMS of the commands and of the measurements over the whole record.
    dac_clipped, adc_clipped : list of int
        Clipped samples per channel.
    dac_lsb, adc_lsb : list of float
        The converters' LSB per channel (1 for ideal converters).
    """

    y: np.ndarray
    u: np.ndarray
    dac: np.ndarray
    u_rms: np.ndarray
    y_rms: np.ndarray
    dac_clipped: list
    adc_clipped: list
    dac_lsb: list
    adc_lsb: list


def simulate_loop(plant, controller, d, noise_rms, *, bits: int | None, dac_full_scale,
                  adc_full_scale, seed: int = 0) -> LoopSimulation:
    """Closed loop in the time domain with quantising, clipping converters and sensor noise.

    ``y_meas = ADC(C xp + D v + n)``, ``u = controller(y_meas)``, the D/A sends
    ``v = DAC(u + d)``. A plant feed-through ``D`` (accelerometers) is taken with a
    controller without one (then the command of sample k comes first, the measurement it
    moves after it); both having one is an algebraic loop, refused.

    Parameters
    ----------
    plant, controller : control.StateSpace
        Discrete, matched by channel name (:class:`trussid.lqg.loop.Loop`).
    d : (N, m) float
        Disturbance added to the command at the D/A [V] (e.g. the demo's excitation).
    noise_rms : float or (p,) float
        White sensor noise RMS [V].
    bits : int or None
        D/A and A/D resolution (the lab's; no default); ``None``: ideal converters (no
        quantising, no clipping).
    dac_full_scale, adc_full_scale : float or per-channel array
        Converter ranges +-V (the lab's; no default).
    seed : int
        Seed of the sensor noise.

    Returns
    -------
    LoopSimulation
    """
    loop = Loop.of(plant, controller)
    iu, iy = list(loop.iu), list(loop.iy)
    Ap, Bp, Cp = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C))
    Bu, Cy = Bp[:, iu], Cp[iy]
    Dyu = np.asarray(plant.D, dtype=float)[np.ix_(iy, iu)]
    Ac, Bc, Cc, Dc = (np.asarray(M, dtype=float) for M in
                      (controller.A, controller.B, controller.C, controller.D))
    command_first = not np.any(Dc != 0)  # Loop.of refused Dc and Dyu both non-zero
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
    return LoopSimulation(Y, U, V, np.sqrt(np.mean(U**2, axis=0)), np.sqrt(np.mean(Y**2, axis=0)),
                          clip_d.tolist(), clip_a.tolist(), lsb_d.tolist(), lsb_a.tolist())
