"""The lab's numbers, in one place: converters, electronics, filters and sensors.

Every number of the lab around a structure (sample rate, D/A and A/D resolution and range,
power amplifier, command-path filters, accelerometer sensitivity, signal conditioner, sensor
noise) is a field of :class:`LabSpec`, with its default (the lab of Vallone 1997, the
thesis) and its source. This module is the only place where those values are written:
the testbed spec (:class:`trussid.geometry.spec.Testbed`) holds these sections, and the lab
chain (:mod:`trussid.testbed.chain`), the demo campaign, the closed-loop evaluation and the
plant files take their values from a :class:`LabSpec` (``tb.lab``) or from a plant file's
recorded lab, never from defaults of their own (``tests/geometry/test_lab.py`` scans the
library for copies).

A lab file is TOML with the same tables as the testbed file's lab sections; any table or
key may be left out and takes the thesis value::

    [daq]
    sample_rate = 3200.0    # Hz
    bits = 16
    full_scale = 5.0        # V, converter range +-full_scale

    [filters]
    lowpass_cutoff = 200.0  # Hz

Read it with :meth:`LabSpec.from_toml` (or a table already parsed, e.g. the ``[plant]``
table of an IO file, with :meth:`LabSpec.from_dict`); every mistake names the file, the
table and the key.
"""

from __future__ import annotations

import dataclasses
import difflib
import json
import os
import tomllib
from dataclasses import dataclass, field
from typing import ClassVar

from trussid.geometry._params import Section, fail, param
from trussid.geometry.errors import ParameterError

__all__ = ["G0", "AccelerometerParams", "ElectricsParams", "FilterParams", "DaqParams",
           "LabSpec", "LAB_SECTIONS", "RECORD_KEY", "lab_record", "recorded_lab"]

#: Standard gravity [m/s^2] (exact), to convert accelerometer sensitivities given per g.
G0 = 9.80665


@dataclass(frozen=True)
class AccelerometerParams(Section):
    """The three vertical accelerometers at the UDF corners (thesis sec. 2.2).

    Attributes
    ----------
    mass : float
        Mass of each accelerometer [kg]. Suggested: 10 g.
    sensitivity : float
        [V/(m/s^2)]. Suggested: 100 mV/g = 0.1 / 9.80665.
    conditioning_gain : float
        Voltage gain of the signal conditioner (charge amplifier) between each
        accelerometer and the A/D [V/V]. Suggested: 2000. The thesis reached 46 dB one-step
        prediction with 12-bit +-10 V converters, so its sensor signals must have filled a
        good part of the A/D range; the bare 100 mV/g output of this structure is about
        1e-3 V RMS, under one 12-bit LSB (4.9 mV). 2000 was chosen on the demo's MIMO
        experiment (all three channels driven with independent 2.5 V RMS white noise,
        0-400 Hz, at the D/A): the conditioned outputs then have RMS of 0.17-0.30 of full
        scale (acc1 lowest, records of 8000-16000 samples) and the A/D clips rarely (9 of
        48000 samples in the identification record; ``trussid demo`` reports the counts).
        2500 put the MIMO record at 0.26-0.32 of full scale and clipped 1.4 % of one
        channel's samples: these lightly damped outputs reach 3-4 times their RMS. The
        plant's outputs are conditioned volts: sensitivity times this gain.
    noise : float
        Sensor (accelerometer and conditioner) noise referred to the accelerometer, RMS
        over 0 to half the sample rate [m/s^2]. Suggested: 10 ug (about 0.35 ug/sqrt(Hz)
        at 1600 Hz, a low-noise piezoelectric accelerometer with its charge amplifier).
        It is amplified with the signal by the conditioner, so the signal-to-noise ratio
        does not depend on the gain. In the demo's MIMO record it lies 59-64 dB under the
        signals, near the 12-bit quantisation noise, as the thesis reports ("the 12-bit
        converters give about 60 dB").
    """

    section: ClassVar[str] = "accelerometers"

    mass: float = param(0.010, "kg", "mass of each accelerometer (suggested: 10 g)")
    sensitivity: float = param(0.1 / G0, "V/(m/s^2)", "sensitivity (suggested: 100 mV/g)")
    conditioning_gain: float = param(2000.0, "V/V", "signal-conditioner gain between accelerometer "
                                  "and A/D (suggested: 2000, fills about 1/4 of the 12-bit "
                                  "range in the demo)")
    noise: float = param(10e-6 * G0, "m/s^2", "sensor noise RMS referred to the accelerometer "
                         "(suggested: 10 ug)")

    @property
    def volts_per_unit(self) -> float:
        """Output at the A/D per unit acceleration, sensitivity times conditioning gain
        [V/(m/s^2)]."""
        return self.sensitivity * self.conditioning_gain

    @property
    def noise_volts(self) -> float:
        """Sensor noise RMS at the A/D, at the nominal conditioning gain [V]."""
        return self.noise * self.sensitivity * self.conditioning_gain


@dataclass(frozen=True)
class ElectricsParams(Section):
    """Actuator electrics (thesis sec. 3.2).

    Attributes
    ----------
    actuator_capacitance : float
        Capacitance per actuator [F]. Thesis: 0.048 uF.
    amplifier_gain : float
        Power amplifier voltage gain [V/V]. Thesis: 10.
    max_pzt_voltage : float
        Largest safe voltage on the wafers [V]. Thesis: 100 V.
    dac_max_voltage : float
        D/A converter peak output [V]. Thesis: 10 V.
    """

    section: ClassVar[str] = "electrics"

    actuator_capacitance: float = param(0.048e-6, "F", "capacitance per actuator (thesis: 0.048 uF)")
    amplifier_gain: float = param(10.0, "V/V", "power amplifier gain (thesis: 10)")
    max_pzt_voltage: float = param(100.0, "V", "maximum voltage on the PZT (thesis: 100 V)")
    dac_max_voltage: float = param(10.0, "V", "D/A peak output (thesis: 10 V)")


@dataclass(frozen=True)
class FilterParams(Section):
    """Command-path filters (thesis sec. 2.3): a Butterworth smoother, then a low-pass.

    Attributes
    ----------
    smoothing_order : int
        Butterworth order [-]. Thesis: 2 poles.
    smoothing_cutoff : float
        Butterworth cutoff [Hz]. Thesis: 1300 Hz.
    lowpass_order : int
        Low-pass order [-]. Thesis: 1 pole.
    lowpass_cutoff : float
        Low-pass cutoff [Hz]. Thesis: 120 Hz.
    """

    section: ClassVar[str] = "filters"

    smoothing_order: int = param(2, "-", "Butterworth smoothing filter order (thesis: 2)", check="count", kind=int)
    smoothing_cutoff: float = param(1300.0, "Hz", "Butterworth cutoff (thesis: 1300 Hz)")
    lowpass_order: int = param(1, "-", "low-pass filter order (thesis: 1)", check="count", kind=int)
    lowpass_cutoff: float = param(120.0, "Hz", "low-pass cutoff (thesis: 120 Hz)")


@dataclass(frozen=True)
class DaqParams(Section):
    """Data acquisition (thesis sec. 2.3).

    Attributes
    ----------
    sample_rate : float
        [Hz]. Thesis: 1600 Hz.
    bits : int
        A/D and D/A resolution [-]. Thesis: 12 bit.
    full_scale : float
        Converter range is +-full_scale [V]. Thesis: 10 V.
    """

    section: ClassVar[str] = "daq"

    sample_rate: float = param(1600.0, "Hz", "sample rate (thesis: 1600 Hz)")
    bits: int = param(12, "-", "A/D and D/A resolution (thesis: 12 bit)", check="count", kind=int)
    full_scale: float = param(10.0, "V", "converter range +-full_scale (thesis: 10 V)")

    def _check_section(self) -> None:
        if self.bits > 32:
            fail("daq.bits", f"{self.bits} must be at most 32")




#: Lab section name -> section class, in file order.
LAB_SECTIONS: dict = {cls.section: cls for cls in (AccelerometerParams, ElectricsParams,
                                                   FilterParams, DaqParams)}


@dataclass(frozen=True)
class LabSpec:
    """The lab around a structure: sensors, electronics, filters and converters (SI units).

    Attributes
    ----------
    accelerometers, electrics, filters, daq
        The sections; see each class for its parameters, units and sources. The defaults
        are the thesis lab: 1600 Hz, 12-bit +-10 V converters, a 2-pole 1300 Hz Butterworth
        smoother and a 1-pole 120 Hz low-pass in front of a x10 amplifier, 100 mV/g
        accelerometers behind a x2000 conditioner, 10 ug of sensor noise.

    Examples
    --------
    >>> lab = LabSpec.from_dict({"daq": {"sample_rate": 3200.0, "bits": 16, "full_scale": 5.0}})
    >>> lab.daq.bits, lab.daq.full_scale, lab.filters.lowpass_cutoff
    (16, 5.0, 120.0)
    >>> lab.lsb  # one least significant bit of the converters [V]
    0.000152587890625
    """

    accelerometers: AccelerometerParams = field(default_factory=AccelerometerParams)
    electrics: ElectricsParams = field(default_factory=ElectricsParams)
    filters: FilterParams = field(default_factory=FilterParams)
    daq: DaqParams = field(default_factory=DaqParams)

    def __post_init__(self) -> None:
        for name, cls in LAB_SECTIONS.items():
            if not isinstance(getattr(self, name), cls):
                raise ParameterError(f"{name} must be a {cls.__name__}, got "
                                     f"{type(getattr(self, name)).__name__}")

    @property
    def sample_rate(self) -> float:
        """A/D and D/A sample rate [Hz]."""
        return self.daq.sample_rate

    @property
    def lsb(self) -> float:
        """One least significant bit of the converters, ``2 full_scale / 2**bits`` [V]."""
        return 2.0 * self.daq.full_scale / 2**self.daq.bits

    def at_rate(self, sample_rate: float | None) -> "LabSpec":
        """This lab sampled at ``sample_rate`` [Hz] (itself when None)."""
        if sample_rate is None:
            return self
        return dataclasses.replace(self, daq=dataclasses.replace(self.daq, sample_rate=sample_rate))

    def to_dict(self) -> dict:
        """The parameters as ``{section: {field: value}}`` (plain values, TOML/JSON-ready)."""
        return {name: {f.name: getattr(getattr(self, name), f.name)
                       for f in dataclasses.fields(getattr(self, name))}
                for name in LAB_SECTIONS}

    @classmethod
    def from_dict(cls, data: dict, source: str = "") -> "LabSpec":
        """A lab from ``{section: {field: value}}``; missing tables and keys take defaults.

        Parameters
        ----------
        data : dict
            Possibly partial tables ``accelerometers``, ``electrics``, ``filters``, ``daq``.
        source : str
            Prefix of the error messages (a file name, ``IO.toml [plant]``).

        Raises
        ------
        ParameterError
            For an unknown table or key (with the closest valid name) or an invalid value,
            naming it as ``section.field``.
        """
        where = f"{source}: " if source else ""
        if not isinstance(data, dict):
            raise ParameterError(f"{where}a lab is a set of tables ({', '.join(LAB_SECTIONS)}), "
                                 f"got {type(data).__name__}")
        sections = {}
        for name, values in data.items():
            if name not in LAB_SECTIONS:
                raise ParameterError(f"{where}unknown lab table [{name}] (valid: "
                                     f"{', '.join(LAB_SECTIONS)}){_hint(name, list(LAB_SECTIONS))}")
            if not isinstance(values, dict):
                raise ParameterError(f"{where}{name} must be a table ([{name}]), got "
                                     f"{type(values).__name__} {values!r}")
            valid = [f.name for f in dataclasses.fields(LAB_SECTIONS[name])]
            for key in values:
                if key not in valid:
                    raise ParameterError(f"{where}unknown lab parameter {name}.{key} (valid: "
                                         f"{', '.join(valid)}){_hint(key, valid, name)}")
            try:
                sections[name] = LAB_SECTIONS[name](**values)
            except ParameterError as exc:
                raise ParameterError(f"{where}{exc}") from None
        return cls(**sections)

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> "LabSpec":
        """Read a lab file (TOML, see the module docstring).

        Raises
        ------
        ParameterError
            If the file is missing or not TOML, or has an unknown table or key or an
            invalid value; the message names the file and the key.
        """
        try:
            with open(path, "rb") as fh:
                data = tomllib.load(fh)
        except FileNotFoundError:
            raise ParameterError(f"{os.fspath(path)}: no such lab file") from None
        except IsADirectoryError:
            raise ParameterError(f"{os.fspath(path)}: is a directory, not a lab file") from None
        except tomllib.TOMLDecodeError as exc:
            raise ParameterError(f"{os.fspath(path)}: not valid TOML: {exc}") from None
        return cls.from_dict(data, source=os.fspath(path))


#: Name of the entry in which a plant file (``trussid plant``, the demo's ``plant_true.npz``)
#: records the lab it was made with (a JSON text of :meth:`LabSpec.to_dict`).
RECORD_KEY = "lab_json"


def lab_record(lab: LabSpec) -> dict:
    """``{RECORD_KEY: JSON text}``: the extra entry that records ``lab`` in a model file
    (:func:`trussid.plid.modelfile.save_model`'s ``extra``)."""
    return {RECORD_KEY: json.dumps(lab.to_dict())}


def recorded_lab(extra: dict, source: str = "") -> LabSpec | None:
    """The lab recorded in a model file's extras (:func:`lab_record`), or None if it
    records none (an identified model, a plant of a NASTRAN deck).

    Raises
    ------
    ParameterError
        If the record is there but is not a valid lab; the message names ``source``.
    """
    if RECORD_KEY not in extra:
        return None
    where = f"{source} ({RECORD_KEY})" if source else RECORD_KEY
    try:
        data = json.loads(str(extra[RECORD_KEY]))
    except json.JSONDecodeError as exc:
        raise ParameterError(f"{where}: the recorded lab is not JSON: {exc}") from None
    return LabSpec.from_dict(data, source=where)


def _hint(name: str, valid: list, section: str | None = None) -> str:
    close = difflib.get_close_matches(name, valid, n=1, cutoff=0.6)
    if not close:
        return ""
    return f"; did you mean {(section + '.' if section else '') + close[0]!r}?"
