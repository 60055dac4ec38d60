"""The campaign's simulated records (:func:`run_experiments`): the drive, the conditioner
ranging, the records through the lab's converters with sensor noise, and one summary row per
record (:func:`experiment_summary`). The signal chain is described in
:mod:`trussid.campaign.demo`'s module docstring.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trussid.campaign.plan import DemoSettings
from trussid.campaign.structure import DEFAULT_SNR_DB
from trussid.campaign.summary import ExperimentRow
from trussid.plid.experiment import excitation, run_experiment, simulate
from trussid.testbed.plant import TestbedPlant

__all__ = ["Record", "conditioner_steps", "drive", "range_conditioners", "take_record",
           "sensor_noise", "run_experiments", "experiment_summary"]


@dataclass
class Record:
    """One simulated record and how it was taken."""

    name: str
    purpose: str                      # "identification" or "validation"
    channels: tuple                   # driven actuator channels (0-based)
    experiment: object                # plid.experiment.Experiment
    gain_steps: list                  # conditioner step per output
    adc_full_scale: list              # A/D range per output, in plant output units [V]
    seed: int

    @property
    def data(self):
        return self.experiment.data


def conditioner_steps(y_rms, full_scale: float, target: float, steps=(1.0, 2.0, 5.0)):
    """Conditioner gain step per channel relative to the nominal gain: the largest 1-2-5
    step from 0.5 up that keeps ``rms * step <= target * full_scale`` (0.5 when even that
    is passed).

    Steps run from 0.5 to 5e4; a channel that is silent gets the largest.
    """
    ladder = np.sort(np.concatenate([np.asarray(steps) * 10.0**k for k in range(-1, 5)]))
    ladder = ladder[ladder >= 0.5]
    out = []
    for r in np.atleast_1d(y_rms):
        ok = ladder[ladder * r <= target * full_scale] if r > 0 else ladder
        out.append(float(ok.max() if ok.size else ladder.min()))
    return out


def drive(settings: DemoSettings, plant, n: int, channels, seed: int) -> np.ndarray:
    """The excitation of the driven ``channels`` (others zero), at the plant's own rate."""
    u = np.zeros((n, plant.ninputs))
    u[:, list(channels)] = excitation(settings.excitation, n, len(channels), 1.0 / plant.dt,
                                      settings.excitation_rms, settings.excitation_band, seed)
    return u


def range_conditioners(plant, settings: DemoSettings, channels, seed: int, n_samples: int,
                       noise_v: float, full_scale: float) -> list:
    """Conditioner steps from a noise-free trial run of the experiment (its own seed), for an
    A/D range of +-``full_scale`` [V]."""
    trial = drive(settings, plant, n_samples, channels, seed)
    rms = np.sqrt(np.mean(simulate(plant, trial) ** 2, axis=0) + noise_v**2)
    return conditioner_steps(rms, full_scale, settings.range_target, settings.gain_steps)


def take_record(plant, settings: DemoSettings, name: str, purpose: str, channels, seed: int,
                n_samples: int, noise_v: float, steps, lab) -> Record:
    """One record with the conditioners at ``steps`` (see the module docstring), through the
    converters of ``lab`` (:class:`trussid.geometry.lab.LabSpec`)."""
    full_scale, bits = lab.daq.full_scale, lab.daq.bits
    adc_fs = [full_scale / g for g in steps]
    u = drive(settings, plant, n_samples, channels, seed)
    exp = run_experiment(plant, n_samples, u=u, seed=seed + 1, sensor_noise_rms=noise_v,
                         dac_bits=bits, adc_bits=bits, dac_full_scale=full_scale,
                         adc_full_scale=np.asarray(adc_fs),
                         input_names=list(plant.input_labels),
                         output_names=list(plant.output_labels))
    return Record(name, purpose, tuple(channels), exp, steps, adc_fs, seed)


def sensor_noise(tp, settings: DemoSettings):
    """Sensor noise RMS in plant output units: the testbed lab's accelerometer noise at the
    nominal conditioning gain, or for a deck :data:`trussid.campaign.structure.
    DEFAULT_SNR_DB` under each output in a noise-free trial of the all-channel record."""
    if isinstance(tp, TestbedPlant):
        return tp.lab.accelerometers.noise_volts
    trial = drive(settings, tp.discrete, settings.n_identification,
                  range(tp.discrete.ninputs), settings.seed + 99)
    rms = np.sqrt(np.mean(simulate(tp.discrete, trial) ** 2, axis=0))
    return rms * 10 ** (-DEFAULT_SNR_DB / 20)


def run_experiments(tp, settings: DemoSettings, progress=None) -> dict:
    """All records of the campaign: ``{model name: (identification, validation)}``.

    Model names are ``simo_ch<k>`` (k = 1..3) and ``mimo``.
    """
    plant, lab = tp.discrete, tp.lab
    noise_v = sensor_noise(tp, settings)
    plan = [(f"simo_ch{c + 1}", (c,)) for c in settings.simo_channels]
    if settings.mimo_order:
        plan.append(("mimo", tuple(range(plant.ninputs))))
    out = {}
    for k, (name, channels) in enumerate(plan):
        base = settings.seed + 1000 * k
        steps = range_conditioners(plant, settings, channels, base + 250,
                                   settings.n_identification, noise_v, lab.daq.full_scale)
        rid = take_record(plant, settings, name, "identification", channels, base,
                          settings.n_identification, noise_v, steps, lab)
        rval = take_record(plant, settings, name, "validation", channels, base + 500,
                           settings.n_validation, noise_v, steps, lab)
        out[name] = (rid, rval)
        if progress:
            progress(f"recorded {name}: {rid.data.n_samples} + {rval.data.n_samples} samples")
    return out


def experiment_summary(records: dict, settings: DemoSettings) -> list[ExperimentRow]:
    """One row per record: its size, rate, drive, converters, ranges and signal-to-noise."""
    rows = []
    for name, pair in records.items():
        for rec in pair:
            e = rec.experiment
            d = e.data
            y_rms = np.sqrt(np.mean(e.y_clean**2, axis=0))
            noise = np.asarray(e.sensor_noise_rms)
            lsb = np.asarray(e.lsb["adc"], dtype=float)
            rows.append(ExperimentRow(
                model=name, purpose=rec.purpose, samples=d.n_samples,
                sample_rate_hz=d.fs,
                driven_channels=[d.input_names[c] for c in rec.channels], seed=rec.seed,
                excitation=settings.excitation, excitation_rms_v=settings.excitation_rms,
                excitation_band_hz=list(settings.excitation_band),
                dac_clipped=e.clipping["dac"], adc_clipped=e.clipping["adc"],
                conditioner_steps=rec.gain_steps,
                adc_full_scale_v=rec.adc_full_scale,
                # the converters' LSB as the experiment applied them [V]
                dac_lsb_v=np.atleast_1d(np.asarray(e.lsb["dac"], dtype=float)).tolist(),
                adc_lsb_v=np.atleast_1d(lsb).tolist(),
                # converter resolution from the LSB the experiment used: 2 FS / 2^bits
                adc_bits=[int(round(np.log2(2 * fs / q)))
                          for fs, q in zip(rec.adc_full_scale, np.atleast_1d(lsb))],
                output_rms_v=y_rms.tolist(),
                output_rms_fraction_of_range=(y_rms / np.asarray(rec.adc_full_scale)).tolist(),
                sensor_snr_db=(20 * np.log10(y_rms / noise)).tolist(),
                quantisation_snr_db=(20 * np.log10(y_rms / (lsb / np.sqrt(12)))).tolist(),
            ))
    return rows
