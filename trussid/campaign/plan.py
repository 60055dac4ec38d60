"""Every number of the demo campaign (:class:`DemoSettings`): the testbed's documented
experiment, its quick variant (:func:`demo_settings`) and the experiment derived for any other
structure from its modes and sample rate (:func:`derived_settings`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

__all__ = ["DemoSettings", "demo_settings", "derived_settings"]


@dataclass(frozen=True)
class DemoSettings:
    """Every number of the demo campaign (SI units unless stated).

    Attributes
    ----------
    quick : bool
        The reduced run (``trussid demo --quick``).
    n_identification, n_validation : int
        Samples of each identification and validation record (at the lab's sample rate).
    excitation : str
        Excitation kind (:func:`trussid.plid.experiment.excitation`).
    excitation_rms : float
        RMS of each driven D/A channel [V].
    excitation_band : (float, float)
        Excitation band [Hz].
    range_target : float
        Each sensor's conditioner step is the largest 1-2-5 step (x0.5 or more) that keeps
        its RMS at most this fraction of the A/D full scale (a fifth: the lightly damped
        structure's outputs reach 4-5 times their RMS).
    gain_steps : tuple of float
        Conditioner gain steps within one decade (1-2-5).
    simo_channels : tuple of int
        Actuator channels (0-based) that get a SIMO model.
    simo_order, mimo_order : int
        States of the SIMO and MIMO models; multiples of the 3 outputs (the observer form
        gives each output n / 3 states). ``mimo_order`` 0 skips the MIMO model.
    block_rows : tuple of int
        Block rows tried by the N4SID prior of the identification recipe (it keeps the one
        with the smallest output error on the identification data). The recipe's default
        tries 20, 30, 40, 60, 80, which takes most of the run time on the shared machine;
        40 and 80 cover the winners measured on the testbed (80 for SIMO, 60-80 for MIMO).
    frf_band : (float, float)
        Band of the FRF error metrics [Hz] (the thesis's band of interest).
    plot_band : (float, float)
        Frequency range of the Bode overlays [Hz].
    h1_nperseg : int
        Welch segment length of the H1 estimate (resolution fs / nperseg).
    seed : int
        Seed of everything random (each record derives its own).
    direct : {False, True, "auto"}
        Direct term D of the identified models (:func:`trussid.plid.reduced.
        identify_reduced`): the testbed's sensors see the structure through the lab's
        low-pass filters (no feed-through, False); accelerometers on a bare structure
        respond at once to a force ("auto": the data decide).
    order_scan : tuple of int
        Orders scanned for each model (:func:`trussid.campaign.orders.scan_orders`: one-step
        prediction on the held-back quarter of its identification record); the model is
        identified at the order the data choose. Empty (the testbed): ``simo_order`` and
        ``mimo_order``, the documented orders.
    order_scan_budget_s : float
        CPU budget of each model's scan [s].
    """

    quick: bool = False
    n_identification: int = 16000
    n_validation: int = 8000
    excitation: str = "white"
    excitation_rms: float = 2.5
    excitation_band: tuple = (0.0, 400.0)
    range_target: float = 0.2
    gain_steps: tuple = (1.0, 2.0, 5.0)
    simo_channels: tuple = (0, 1, 2)
    simo_order: int = 30
    mimo_order: int = 36
    block_rows: tuple = (40, 80)
    frf_band: tuple = (50.0, 350.0)
    plot_band: tuple = (10.0, 450.0)
    h1_nperseg: int = 1024
    seed: int = 1997
    direct: object = False
    order_scan: tuple = ()
    order_scan_budget_s: float = 60.0


def demo_settings(quick: bool = False, **overrides) -> DemoSettings:
    """The full campaign, or the quick one.

    ``quick`` keeps the SIMO model of channel 1 at the full 30 states and the MIMO model
    at 18 states instead of 36, drops the SIMO models of channels 2 and 3, and uses
    records of 6000 samples (identification) and 4000 (validation) instead of 16000 and
    8000.
    """
    s = DemoSettings()
    if quick:
        s = replace(s, quick=True, n_identification=6000, n_validation=4000,
                    simo_channels=(0,), mimo_order=18, h1_nperseg=512)
    return replace(s, **overrides)


def derived_settings(cp, quick: bool = False, **overrides):
    """The experiment for a deck's plant (:class:`trussid.campaign.structure.CampaignPlant`),
    from its modes and sample rate (overridable):

    - excitation white 0 to 0.4 of the sample rate, a quarter of the D/A range RMS per
      driven channel (a crest factor of 4, as on the testbed);
    - FRF band from half the first mode to the top of the excitation; Bode plots to 0.95
      of Nyquist;
    - records of 6000 + 4000 samples (quick) or 16000 + 8000, at least 100 periods of
      the first mode;
    - model orders chosen from the data (issue 32): multiples of the outputs (PLID's
      observer form) from one to 48 states (quick: 36) are scanned for each model by
      one-step prediction on the held-back quarter of its identification record
      (:mod:`trussid.campaign.orders`), within 60 s of CPU each; the fallback, if no order
      gives a stable model, is twice the number of the plant's modes below Nyquist, capped
      likewise. SIMO models of every channel (quick: the first); the direct term estimated
      when the data show one (accelerometers).
    """
    fs = 1.0 / cp.discrete.dt
    f = np.asarray(cp.modes.frequencies_hz, dtype=float)
    f = f[f > 1e-6]
    top = 0.4 * fs
    p = cp.discrete.noutputs
    order = int(min(p * math.ceil(max(2 * f.size, 2) / p), p * ((36 if quick else 48) // p)))
    base = demo_settings(quick)
    n_min = int(math.ceil(100 * fs / f[0])) if f.size else 0
    lo = 0.5 * f[0] if f.size else 0.0
    kw = dict(direct="auto", excitation_band=(0.0, top),
              excitation_rms=0.25 * cp.lab.daq.full_scale, frf_band=(lo, top),
              plot_band=(lo, 0.95 * 0.5 * fs), n_identification=max(base.n_identification, n_min),
              n_validation=max(base.n_validation, n_min // 2), mimo_order=order,
              simo_order=order,
              order_scan=tuple(range(p, p * ((36 if quick else 48) // p) + 1, p)),
              simo_channels=(0,) if quick else tuple(range(cp.discrete.ninputs)))
    kw.update(overrides)
    return demo_settings(quick, **kw)
