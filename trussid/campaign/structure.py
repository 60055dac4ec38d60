"""A NASTRAN deck with an IO file as the structure of a campaign, and its lab.

``trussid demo`` runs one campaign (:mod:`trussid.campaign.demo`) on a plant with a lab: the
default testbed's (:func:`trussid.testbed.plant.testbed_plant`) or, here, any deck's: the
IO file gives the actuators, sensors, ``[plant]`` sample rate and damping
(:mod:`trussid.fem.iospec`), a LAB file the converters (:class:`trussid.geometry.lab.LabSpec`,
the project's one lab specification: ``[daq] sample_rate, bits, full_scale``; its rate wins
over the IO file's).

The commands and outputs of a deck's plant are in the IO file's units (N, V, m/s^2 ...):
the converters see those numbers as volts, as if each channel had a unit-gain amplifier or
conditioner (the IO file's ``gain`` and ``sensitivity`` set the real ones). The sensor noise
is :data:`DEFAULT_SNR_DB` under each output in the all-channel record.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from trussid.fem.iospec import io_plant, read_io
from trussid.fem.modal import Modes
from trussid.fem.nastran import read_bdf
from trussid.geometry.lab import LabSpec

#: Sensor noise under each output's RMS in the all-channel record [dB].
DEFAULT_SNR_DB = 60.0
#: A true or identified pole with a damping ratio above this is not a structural mode (the
#: plant's filter and amplifier poles are real: damping 1).
STRUCTURAL_DAMPING_MAX = 0.5
#: Sample rate [Hz] and modal damping of a deck whose IO file and LAB file give none.
DEFAULT_RATE, DEFAULT_DAMPING = 1000.0, 0.02


@dataclass
class CampaignPlant:
    """A deck's plant for a campaign (the testbed's is a
    :class:`trussid.testbed.plant.TestbedPlant`; both have ``discrete``, ``modes``, ``lab``).

    Attributes
    ----------
    discrete : control.StateSpace
        The true plant (commands to sensor outputs) at the lab's sample rate.
    modes : fem.modal.Modes
        Its modes (those kept).
    lab : LabSpec
        Converters and rate.
    damping : float
        Modal damping ratio.
    description : str
        One line for the report ("deck tower.bdf with io.toml").
    lab_source : str
    model : fem.Model, optional
        The deck's FE model (the 3-D view of ``report.html``).
    sensors : tuple of fem.sensors.Sensor
        The IO file's sensors (node, axis, name), in the plant's output order.
    """

    discrete: object
    modes: object
    lab: LabSpec
    damping: float
    description: str
    lab_source: str
    model: object = None
    sensors: tuple = ()


def deck_campaign_plant(deck, io, lab_path=None, *, n_modes=None) -> CampaignPlant:
    """A NASTRAN deck's plant with the IO file's actuators and sensors, at the lab's rate
    (every mode below the Nyquist frequency, or the first ``n_modes``)."""
    model, info = read_bdf(deck)
    spec = read_io(io)
    if lab_path is not None:
        lab, source = LabSpec.from_toml(lab_path), str(lab_path)
    else:
        lab = LabSpec().at_rate(spec.fs or DEFAULT_RATE)
        source = f"{Path(io).name} [plant]" if spec.fs else "defaults"
    damping = DEFAULT_DAMPING if spec.damping is None else float(spec.damping)
    _, sd, modes, n = io_plant(model, spec, n_modes=n_modes, damping=damping,
                               fs=lab.daq.sample_rate, autospc=info.autospc)
    if n < len(modes.frequencies_hz):
        modes = Modes(modes.frequencies_hz[:n], modes.omega[:n], modes.shapes[:, :n],
                      modes.shapes_full[:, :n], modes.node_ids, modes.xyz, modes.n_dof,
                      modes.method)
    return CampaignPlant(sd, modes, lab, damping, f"deck {Path(deck).name} with "
                         f"{Path(io).name}", source, model, tuple(spec.sensors))
