"""The Testbed parameter set: thesis defaults in SI, validation naming the parameter (item 6)."""

import dataclasses
import math

import numpy as np
import pytest

from trussid.geometry.errors import ParameterError
from trussid.geometry.spec import Testbed
from trussid._util.errors import UserError

IN = 0.0254
LB = 0.45359237


def test_defaults_are_the_documented_values_in_si():
    tb = Testbed()
    assert tb.struts.length == pytest.approx(36 * IN, rel=1e-15)
    assert tb.struts.outer_diameter == pytest.approx(0.535 * IN, rel=1e-15)  # calibrated (README)
    np.testing.assert_allclose(tb.struts.walls, np.array([0.028, 0.035, 0.042, 0.049, 0.058, 0.065]) * IN, rtol=1e-15)
    assert tb.udf.side == pytest.approx(12 * IN, rel=1e-15)
    assert tb.udf.mass == pytest.approx(35 * LB, rel=1e-15)
    assert tb.base.mass == pytest.approx(105 * LB, rel=1e-15)
    assert tb.base.diameter == pytest.approx(30 * IN, rel=1e-15)
    assert (tb.adapter.side, tb.adapter.length) == pytest.approx((1.0 * IN, 2.0 * IN), rel=1e-15)  # calibrated
    p = tb.pzt
    assert (p.width, p.length, p.thickness) == pytest.approx((1.00 * IN, 2.00 * IN, 0.020 * IN), rel=1e-15)
    assert (p.d31, p.youngs_modulus, p.density, p.wafers_per_strut) == (-171e-12, 61e9, 7750.0, 2)
    assert tb.accelerometers.mass == 0.010
    assert tb.accelerometers.sensitivity * 9.80665 == pytest.approx(0.100, rel=1e-15)  # 100 mV/g
    assert tb.electrics.actuator_capacitance == pytest.approx(0.048e-6, rel=1e-15)
    assert (tb.electrics.amplifier_gain, tb.electrics.max_pzt_voltage, tb.electrics.dac_max_voltage) == (10, 100, 10)
    assert (tb.filters.smoothing_order, tb.filters.smoothing_cutoff) == (2, 1300.0)
    assert (tb.filters.lowpass_order, tb.filters.lowpass_cutoff) == (1, 120.0)
    assert (tb.daq.sample_rate, tb.daq.bits, tb.daq.full_scale) == (1600.0, 12, 10.0)
    assert tb.damping.modal_ratio == 0.0025
    # calibrated (README "Testbed calibration"): base flexures, clamped tops
    assert tb.struts.base_rotational_stiffness == 1000.0 and math.isinf(tb.struts.top_rotational_stiffness)


def test_derived_geometry_is_the_reconstruction_of_testbed_md():
    tb = Testbed()
    assert tb.base_radius / IN == pytest.approx(13.856, abs=5e-4)
    assert tb.strut_run / IN == pytest.approx(12.0, rel=1e-14)
    assert tb.strut_height / IN == pytest.approx(33.94, abs=5e-3)
    assert tb.base.thickness / IN == pytest.approx(1.5229, abs=5e-5)
    # Overall height under the thesis's 4 ft, width 30 in.
    top = tb.strut_height + tb.udf.height + tb.udf.member_size / 2 + tb.base.thickness
    assert top < 48 * IN


def test_wafer_capacitance_is_the_parallel_plate_value():
    c = Testbed().pzt.wafer_capacitance
    assert c == pytest.approx(8.8541878128e-12 * 1700 * (1.0 * 2.0 * IN**2) / (0.020 * IN), rel=1e-12)
    assert 2 * c == pytest.approx(76.5e-9, rel=1e-3)  # vs the thesis's 48 nF per actuator


def test_default_walls_all_differ_so_the_symmetry_is_broken():
    assert len(set(Testbed().struts.walls)) == 6


@pytest.mark.parametrize("changes, message", [
    (dict(struts__walls=(0.0007, 0.0009, 0.0011, 0.007, 0.0015, 0.0017)),
     r"strut 3 wall thickness 0\.0070 m must be in \(0, 0\.00679 m\)"),
    (dict(struts__walls=(-0.001, 0.0009, 0.0011, 0.0012, 0.0015, 0.0017)), r"strut 0 wall thickness"),
    (dict(struts__walls=(0.0007, 0.0009, 0.0011, 0.0012, 0.0015, 0.0)), r"strut 5 wall thickness"),
    (dict(struts__walls=(0.0007, 0.0009, 0.0011, 0.0012, 0.0015, 0.0067945)), r"strut 5 wall thickness"),
    (dict(struts__walls=(0.001,) * 5), r"struts\.walls must hold 6 wall thicknesses"),
    (dict(struts__walls=(0.001,) * 5 + ("thin",)), r"struts\.walls\[5\] must be a number"),
    (dict(struts__length=0.0), r"struts\.length 0\.0 must be positive"),
    (dict(struts__length=-0.9), r"struts\.length -0\.9 must be positive"),
    (dict(struts__length=0.2), r"struts\.length .* must exceed the strut's horizontal run"),
    (dict(struts__outer_diameter=-0.0127), r"struts\.outer_diameter"),
    (dict(struts__density=0), r"struts\.density"),
    (dict(struts__poisson_ratio=0.6), r"struts\.poisson_ratio"),
    (dict(struts__base_rotational_stiffness=0.0), r"struts\.base_rotational_stiffness"),
    (dict(udf__mass=0), r"udf\.mass 0\.0 must be positive"),
    (dict(udf__mass=-15.9), r"udf\.mass"),
    (dict(udf__side=0), r"udf\.side"),
    (dict(base__mass=-1), r"base\.mass"),
    (dict(base__support="hanging"), r"base\.support 'hanging' must be one of 'suspended', 'clamped'"),
    (dict(base__bungee_count=0), r"base\.bungee_count 0 must be at least 1"),
    (dict(base__bungee_radius=0.5), r"base\.bungee_radius"),
    (dict(accelerometers__mass=0), r"accelerometers\.mass"),
    (dict(adapter__side=0.01), r"adapter\.side .* must exceed the tube outside diameter"),
    (dict(adapter__length=1.0), r"adapter\.length"),
    (dict(pzt__width=0.03), r"pzt\.width"),
    (dict(pzt__wafers_per_strut=3), r"pzt\.wafers_per_strut 3 must be 2 or 4"),
    (dict(daq__bits=12.5), r"daq\.bits must be an integer, got float 12\.5"),
    (dict(daq__sample_rate="1600 Hz"), r"daq\.sample_rate must be a number, got str"),
    (dict(struts__length=True), r"struts\.length must be a number, got bool"),
    (dict(struts__length=float("nan")), r"struts\.length must be a number, got NaN"),
    (dict(struts__length=float("inf")), r"struts\.length inf must be positive and finite"),
    (dict(damping__modal_ratio=1.5), r"damping\.modal_ratio"),
    (dict(electrics__amplifier_gain=0), r"electrics\.amplifier_gain"),
    (dict(filters__lowpass_cutoff=-120), r"filters\.lowpass_cutoff"),
])
def test_bad_parameters_raise_an_error_naming_the_parameter(changes, message):
    with pytest.raises(ParameterError, match=message):
        Testbed().replace(**changes)


def test_parameter_error_is_a_user_error_so_the_cli_prints_one_line():
    assert issubclass(ParameterError, UserError)


def test_sections_validate_when_built_alone():
    from trussid.geometry.spec import UdfParams
    with pytest.raises(ParameterError, match=r"udf\.mass"):
        UdfParams(mass=-1.0)


def test_wrong_section_type_is_refused():
    with pytest.raises(ParameterError, match="struts must be a StrutParams"):
        Testbed(struts={"length": 1.0})


def test_replace_changes_one_parameter_and_keeps_the_rest():
    tb = Testbed()
    new = tb.replace(struts__length=40 * IN, base__support="clamped")
    assert new.struts.length == 40 * IN and new.base.support == "clamped"
    assert new.struts.walls == tb.struts.walls and new.udf == tb.udf
    assert tb.struts.length == pytest.approx(36 * IN)  # frozen original untouched


def test_replace_refuses_unknown_names():
    with pytest.raises(ParameterError, match=r"unknown parameter struts\.lenght"):
        Testbed().replace(struts__lenght=1.0)
    with pytest.raises(ParameterError, match=r"unknown testbed section 'strut'"):
        Testbed().replace(strut__length=1.0)


def test_with_walls_accepts_arrays_and_equals_replace():
    walls = np.linspace(0.0008, 0.0018, 6)
    tb = Testbed().with_walls(walls)
    assert tb == Testbed().replace(struts__walls=tuple(walls.tolist()))
    assert isinstance(tb.struts.walls, tuple) and all(type(t) is float for t in tb.struts.walls)
    hash(tb)  # hashable: usable as a cache key in design sweeps


def test_with_walls_validates_each_wall():
    with pytest.raises(ParameterError, match="strut 2 wall thickness"):
        Testbed().with_walls([0.001, 0.001, 0.01, 0.001, 0.001, 0.001])


def test_integers_are_accepted_for_float_parameters_and_stored_as_float():
    tb = Testbed().replace(base__bungee_vertical_stiffness=1000)
    assert type(tb.base.bungee_vertical_stiffness) is float
    assert tb == Testbed().replace(base__bungee_vertical_stiffness=1000.0)


def test_testbed_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        Testbed().struts.length = 1.0


def test_none_end_stiffness_means_clamped():
    tb = Testbed().replace(struts__base_rotational_stiffness=None, struts__top_rotational_stiffness=5e3)
    assert tb.struts.base_rotational_stiffness == math.inf
    assert tb.struts.top_rotational_stiffness == 5e3
