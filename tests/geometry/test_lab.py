"""The lab spec: one home for the lab's numbers, read from TOML with errors that name the key.

The acceptance of issue 22 item 3: the thesis lab's sample rate, converter resolution and
range, filter corners and amplifier gain are written in ``geometry/lab.py`` and nowhere
else in the library (a scan of the source tree), so no lower function can silently use a
copy of them instead of the lab it was given.
"""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import pytest

from trussid.geometry.errors import ParameterError
from trussid.geometry.lab import LabSpec, lab_record, recorded_lab
from trussid.geometry.spec import Testbed

ROOT = Path(__file__).resolve().parents[2]
LIBRARY = [ROOT / "fem", ROOT / "plid", ROOT / "geometry", ROOT / "trussid"]
LAB_MODULE = ROOT / "geometry" / "lab.py"

#: The thesis lab's numbers (Vallone 1997, sec. 2.3 and 3.2).
THESIS = {"sample_rate": 1600.0, "bits": 12, "full_scale": 10.0, "smoothing_cutoff": 1300.0,
          "lowpass_cutoff": 120.0, "amplifier_gain": 10.0, "conditioning_gain": 2000.0}
#: Names under which a lab number is handed to a function or stored.
LAB_NAMES = {"sample_rate", "fs", "FS", "bits", "dac_bits", "adc_bits", "nbits", "full_scale",
             "dac_full_scale", "adc_full_scale", "smoothing_cutoff", "lowpass_cutoff",
             "cutoff", "f_hz", "amplifier_gain", "conditioning_gain", "gain"}
#: Numbers that are the lab's wherever they appear in code (no other meaning in trussid).
ALWAYS_LAB = {1600.0, 1300.0}


def _number(node) -> float | None:
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
            and not isinstance(node.value, bool):
        return float(node.value)
    return None


def lab_literals(path: Path) -> list[str]:
    """``line: name = value`` for each lab number written in ``path``'s code (docstrings and
    comments are prose, not values)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    values = {float(v) for v in THESIS.values()}
    found = []

    def named(name: str | None, value_node, line: int):
        if isinstance(value_node, ast.Call):  # a dataclass field: param(1600.0, ...), field(default=12)
            given = value_node.args[:1] + [k.value for k in value_node.keywords if k.arg == "default"]
            value_node = given[0] if given else value_node
        v = _number(value_node)
        if v is not None and name in LAB_NAMES and v in values:
            found.append(f"{line}: {name} = {v:g}")

    for node in ast.walk(tree):
        v = _number(node)
        if v is not None and v in ALWAYS_LAB:
            found.append(f"{node.lineno}: {v:g}")
        if isinstance(node, ast.keyword):
            named(node.arg, node.value, node.value.lineno)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            a = node.args
            pos = a.posonlyargs + a.args
            for arg, default in zip(pos[len(pos) - len(a.defaults):], a.defaults):
                named(arg.arg, default, default.lineno)
            for arg, default in zip(a.kwonlyargs, a.kw_defaults):
                if default is not None:
                    named(arg.arg, default, default.lineno)
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            target = node.target
            named(getattr(target, "id", getattr(target, "attr", None)), node.value, node.lineno)
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                named(getattr(target, "id", getattr(target, "attr", None)), node.value, node.lineno)
        elif isinstance(node, ast.Dict):
            for key, value in zip(node.keys, node.values):
                if isinstance(key, ast.Constant) and isinstance(key.value, str):
                    named(key.value, value, value.lineno)
    return found


def library_modules():
    for folder in LIBRARY:
        yield from sorted(folder.rglob("*.py"))


def test_the_lab_numbers_are_written_in_one_library_module_only():
    copies = {}
    for path in library_modules():
        hits = lab_literals(path)
        if hits:
            copies[str(path.relative_to(ROOT))] = hits
    assert list(copies) == ["geometry/lab.py"], copies


def test_the_scan_finds_a_planted_copy(tmp_path):
    planted = tmp_path / "chain.py"
    planted.write_text(
        '"""A chain (1600 Hz in prose is fine)."""\n'
        "def lab_plant(structure, fs=1600.0, bits: int = 12):\n"
        "    return simulate(structure, full_scale=10.0)\n"
        "class LoopSettings:\n"
        "    full_scale: float = 10.0\n"
        "    bits: int = field(default=12)\n"
        "DEFAULTS = {'lowpass_cutoff': 120.0}\n")
    assert sorted(lab_literals(planted)) == ["2: 1600", "2: bits = 12", "2: fs = 1600",
                                             "3: full_scale = 10", "5: full_scale = 10",
                                             "6: bits = 12", "7: lowpass_cutoff = 120"]
    # the lab module itself holds every one of them, so the scan is not looking for nothing
    found = " ".join(lab_literals(LAB_MODULE))
    for value in ("1600", "1300", "120", "12", "10"):
        assert f" {value}" in found


def test_the_default_lab_is_the_thesis_lab():
    lab = LabSpec()
    assert (lab.daq.sample_rate, lab.daq.bits, lab.daq.full_scale) == (1600.0, 12, 10.0)
    assert (lab.filters.smoothing_order, lab.filters.smoothing_cutoff) == (2, 1300.0)
    assert (lab.filters.lowpass_order, lab.filters.lowpass_cutoff) == (1, 120.0)
    assert lab.electrics.amplifier_gain == 10.0
    assert lab.lsb == 20.0 / 4096                       # 2 full scale / 2^bits
    # 10 ug of sensor noise through 100 mV/g and a x2000 conditioner: 2 mV at the A/D
    assert lab.accelerometers.noise_volts == pytest.approx(10e-6 * 0.1 * 2000, rel=1e-14)


def test_the_testbed_holds_its_lab_and_takes_another():
    tb = Testbed()
    assert tb.lab == LabSpec()
    lab = LabSpec.from_dict({"daq": {"sample_rate": 3200.0, "bits": 16, "full_scale": 5.0}})
    moved = tb.with_lab(lab)
    assert moved.lab == lab and moved.daq.bits == 16 and moved.struts == tb.struts
    assert moved.replace(daq__bits=14).lab.daq.bits == 14
    with pytest.raises(ParameterError, match="lab must be a LabSpec"):
        tb.with_lab({"daq": {}})


def test_a_lab_file_is_partial_toml(tmp_path):
    path = tmp_path / "lab.toml"
    path.write_text("[daq]\nsample_rate = 3200\nbits = 16\nfull_scale = 5.0\n\n"
                    "[filters]\nlowpass_cutoff = 200.0\n")
    lab = LabSpec.from_toml(path)
    assert lab.daq == dataclasses.replace(LabSpec().daq, sample_rate=3200.0, bits=16,
                                          full_scale=5.0)
    assert lab.filters.lowpass_cutoff == 200.0
    assert lab.filters.smoothing_cutoff == LabSpec().filters.smoothing_cutoff
    assert lab.at_rate(1000.0).daq.sample_rate == 1000.0 and lab.at_rate(None) is lab
    assert LabSpec.from_dict(lab.to_dict()) == lab


@pytest.mark.parametrize("text, message", [
    ("[dac]\nbits = 16\n", r"lab.toml: unknown lab table \[dac\].*did you mean 'daq'\?"),
    ("[daq]\nbit = 16\n", r"lab.toml: unknown lab parameter daq.bit .*did you mean 'daq.bits'\?"),
    ("[daq]\nbits = 0\n", r"lab.toml: daq.bits 0 must be at least 1"),
    ("[daq]\nbits = 40\n", r"lab.toml: daq.bits 40 must be at most 32"),
    ("[daq]\nbits = 12.5\n", r"lab.toml: daq.bits must be an integer"),
    ("[daq]\nsample_rate = -1.0\n", r"lab.toml: daq.sample_rate -1.0 must be positive"),
    ("[filters]\nlowpass_cutoff = \"fast\"\n", r"lab.toml: filters.lowpass_cutoff must be a number"),
    ("daq = 3\n", r"lab.toml: daq must be a table"),
    ("[daq\n", r"lab.toml: not valid TOML"),
])
def test_a_bad_lab_file_is_refused_naming_file_and_key(tmp_path, text, message):
    path = tmp_path / "lab.toml"
    path.write_text(text)
    with pytest.raises(ParameterError, match=message):
        LabSpec.from_toml(path)


def test_a_missing_lab_file_is_named(tmp_path):
    with pytest.raises(ParameterError, match="no such lab file"):
        LabSpec.from_toml(tmp_path / "none.toml")


def test_a_plant_file_records_its_lab_and_gives_it_back():
    lab = LabSpec.from_dict({"daq": {"sample_rate": 3200.0, "bits": 16, "full_scale": 5.0}})
    assert recorded_lab(lab_record(lab), "plant.npz") == lab
    assert recorded_lab({}, "model.npz") is None
    with pytest.raises(ParameterError, match=r"plant.npz \(lab_json\): unknown lab table \[x\]"):
        recorded_lab({"lab_json": '{"x": {}}'}, "plant.npz")
