"""Testbed parameter files: round trip, partial files, and errors naming the key (item 6)."""

import math
import tomllib
from pathlib import Path

import pytest

from trussid.geometry.errors import ParameterError
from trussid.geometry.params_toml import dumps_testbed, load_testbed, save_testbed, testbed_from_dict
from trussid.geometry.spec import Testbed

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "testbed.toml"


def _write(tmp_path, text, name="tb.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_save_then_load_gives_an_equal_testbed(tmp_path):
    tb = Testbed().replace(
        struts__walls=(0.0008, 0.0009, 0.001, 0.0011, 0.0012, 0.0013),
        struts__top_rotational_stiffness=2.5e3, struts__base_rotational_stiffness=None,
        base__support="clamped", pzt__wafers_per_strut=4,
    )
    (tmp_path / "sub").mkdir()  # save_testbed makes no folder it was not asked for
    path = tmp_path / "sub" / "design.toml"
    save_testbed(tb, path)
    assert load_testbed(path) == tb
    assert math.isinf(load_testbed(path).struts.base_rotational_stiffness)


def test_saved_file_is_plain_toml_with_si_keys_and_unit_comments(tmp_path):
    path = tmp_path / "tb.toml"
    save_testbed(Testbed(), path)
    text = path.read_text()
    data = tomllib.loads(text)
    assert data["struts"]["length"] == pytest.approx(36 * 0.0254)
    assert data["udf"]["mass"] == pytest.approx(35 * 0.45359237)
    assert "# strut length between end points (thesis: 36 in) [m]\nlength = 0.9144" in text


def test_shipped_example_file_holds_the_defaults():
    assert load_testbed(EXAMPLE) == Testbed()
    assert EXAMPLE.read_text() == dumps_testbed(Testbed())  # regenerate with save_testbed if not


def test_partial_file_takes_defaults_for_missing_keys(tmp_path):
    path = _write(tmp_path, '[struts]\nlength = 1.0\n\n[base]\nsupport = "clamped"\n')
    tb = load_testbed(path)
    assert tb == Testbed().replace(struts__length=1.0, base__support="clamped")


def test_empty_file_is_the_default_testbed(tmp_path):
    assert load_testbed(_write(tmp_path, "")) == Testbed()


def test_unknown_key_is_named_with_the_closest_valid_name(tmp_path):
    path = _write(tmp_path, "[struts]\nlenght = 1.0\n")
    with pytest.raises(ParameterError, match=r"unknown parameter 'struts\.lenght'; did you mean 'struts\.length'\?"):
        load_testbed(path)


def test_unknown_section_is_named_with_the_closest_valid_name(tmp_path):
    with pytest.raises(ParameterError, match=r"unknown parameter 'strut'; did you mean 'struts'\?"):
        load_testbed(_write(tmp_path, "[strut]\nlength = 1.0\n"))


def test_unknown_key_far_from_any_name_gets_no_suggestion(tmp_path):
    with pytest.raises(ParameterError, match=r"unknown parameter 'base\.colour'$"):
        load_testbed(_write(tmp_path, '[base]\ncolour = "red"\n'))


def test_error_message_names_the_file(tmp_path):
    path = _write(tmp_path, "[struts]\nlenght = 1.0\n", name="mine.toml")
    with pytest.raises(ParameterError, match=r"mine\.toml: unknown parameter"):
        load_testbed(path)


@pytest.mark.parametrize("text, message", [
    ('[struts]\nlength = "36 in"\n', r"struts\.length must be a number, got str '36 in'"),
    ("[daq]\nbits = 12.0\n", r"daq\.bits must be an integer, got float"),
    ("[base]\nsupport = 1\n", r"base\.support must be a string, got int"),
    ("[struts]\nwalls = 0.001\n", r"struts\.walls must be a list of numbers, got float"),
    ('[struts]\nwalls = [0.001, 0.001, "x", 0.001, 0.001, 0.001]\n', r"struts\.walls\[2\] must be a number"),
    ("struts = 3.0\n", r"struts must be a table \(\[struts\]\), got float"),
    ("[udf]\nmass = -1.0\n", r"udf\.mass -1\.0 must be positive"),
    ("[struts]\nwalls = [0.001, 0.001, 0.001, 0.0069, 0.001, 0.001]\n", r"strut 3 wall thickness 0\.0069 m"),
    ("[struts]\nwalls = [0.001, 0.001]\n", r"struts\.walls must hold 6"),
])
def test_wrong_type_or_value_names_the_key(tmp_path, text, message):
    with pytest.raises(ParameterError, match=message):
        load_testbed(_write(tmp_path, text))


def test_invalid_toml_and_missing_file_are_parameter_errors(tmp_path):
    with pytest.raises(ParameterError, match="not valid TOML"):
        load_testbed(_write(tmp_path, "[struts\nlength = 1\n"))
    with pytest.raises(ParameterError, match="no such parameter file"):
        load_testbed(tmp_path / "absent.toml")


def test_from_dict_without_source_has_no_prefix():
    with pytest.raises(ParameterError, match=r"^udf\.mass"):
        testbed_from_dict({"udf": {"mass": 0.0}})


def test_failed_save_leaves_no_file_behind(tmp_path):
    path = tmp_path / "out.toml"
    with pytest.raises(AttributeError):
        save_testbed("not a testbed", path)
    assert list(tmp_path.iterdir()) == []


def test_parameter_in_the_wrong_section_points_to_the_right_one(tmp_path):
    with pytest.raises(ParameterError, match=r"unknown parameter 'struts\.modal_ratio'; did you mean 'damping\.modal_ratio'\?"):
        load_testbed(_write(tmp_path, "[struts]\nmodal_ratio = 0.01\n"))
