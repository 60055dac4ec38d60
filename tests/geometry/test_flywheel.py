"""The flywheel solid: a closed disc-and-shaft volume whose inertia is the closed form's."""

import math

import pytest

from trussid.geometry.errors import ParameterError
from trussid.geometry.flywheel import (
    Flywheel,
    flywheel_inertia,
    flywheel_inertia_closed_form,
    flywheel_solid,
    parse_flywheel,
)


def disc_and_shaft_closed_form(rd, td, rs, ls, rho):
    """Written out independently of the module: (1/2) m r^2 for each coaxial cylinder,
    the shaft counted only outside the disc."""
    m_disc = rho * math.pi * rd**2 * td
    m_shaft = rho * math.pi * rs**2 * (ls - td)
    return 0.5 * m_disc * rd**2 + 0.5 * m_shaft * rs**2, m_disc + m_shaft


@pytest.mark.parametrize(
    "dims",
    [
        (0.10, 0.02, 0.010, 0.20, 7850.0),   # steel disc on a long shaft
        (0.075, 0.012, 0.006, 0.15, 2700.0),  # aluminium
        (0.05, 0.03, 0.02, 0.03, 7850.0),    # shaft no longer than the disc
    ],
)
def test_inertia_of_trimesh_solid_matches_closed_form_within_half_a_percent(dims):
    rd, td, rs, ls, rho = dims
    expected, _ = disc_and_shaft_closed_form(rd, td, rs, ls, rho)
    got = flywheel_inertia(Flywheel(rd, td, rs, ls, rho))
    rel = abs(got - expected) / expected
    assert rel < 5e-3
    # 256 facets: the polygon makes the solid slightly light, by about (2 pi/256)^2/3
    assert rel < 1e-3
    assert got < expected
    assert flywheel_inertia_closed_form(Flywheel(rd, td, rs, ls, rho)) == pytest.approx(
        expected, rel=1e-12)


def test_solid_is_a_closed_volume_with_the_right_mass_and_centre():
    fly = Flywheel(0.1, 0.02, 0.01, 0.2)
    mesh = flywheel_solid(fly)
    _, mass = disc_and_shaft_closed_form(0.1, 0.02, 0.01, 0.2, 7850.0)
    assert mesh.is_watertight and mesh.is_volume
    assert mesh.mass == pytest.approx(mass, rel=1e-3)
    assert abs(mesh.center_mass).max() < 1e-12
    # axisymmetric about z: the two transverse inertias agree, off-diagonals vanish
    inertia = mesh.moment_inertia
    assert inertia[0, 0] == pytest.approx(inertia[1, 1], rel=1e-9)
    assert abs(inertia[0, 1]) < 1e-12 * inertia[2, 2]


def test_finer_faceting_converges_to_the_closed_form():
    fly = Flywheel(0.1, 0.02, 0.01, 0.2)
    exact = flywheel_inertia_closed_form(fly)
    errs = [abs(flywheel_inertia(fly, n) - exact) / exact for n in (32, 64, 128)]
    assert errs[0] > errs[1] > errs[2]
    assert errs[1] / errs[2] == pytest.approx(4.0, rel=0.05)  # second order in 1/sections


def test_dims_string_parses_with_default_steel_density():
    fly = parse_flywheel("0.1, 0.02,0.01,0.2")
    assert fly == Flywheel(0.1, 0.02, 0.01, 0.2, 7850.0)
    assert parse_flywheel("0.1,0.02,0.01,0.2,2700").density == 2700.0


@pytest.mark.parametrize(
    ("make", "word"),
    [
        (lambda: Flywheel(-0.1, 0.02, 0.01, 0.2), "disc_radius"),
        (lambda: Flywheel(0.1, 0.02, 0.01, 0.2, 0.0), "density"),
        (lambda: Flywheel(0.1, 0.02, 0.2, 0.3), "shaft_radius"),
        (lambda: Flywheel(0.1, 0.02, 0.01, 0.01), "shaft_length"),
        (lambda: parse_flywheel("0.1,0.02,0.01"), "4 or 5 numbers"),
        (lambda: parse_flywheel("0.1,0.02,x,0.2"), "shaft_radius"),
        (lambda: flywheel_solid(Flywheel(0.1, 0.02, 0.01, 0.2), sections=3), "sections"),
    ],
)
def test_bad_dimensions_are_rejected_naming_the_parameter(make, word):
    with pytest.raises(ParameterError, match=word):
        make()
