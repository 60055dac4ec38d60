"""Per-element section and material arrays (fem.properties; issue 31, item 7): what
Model.add_beams takes besides one Section and one Material, checked where they are made,
naming the property."""

import numpy as np
import pytest

from trussid.fem import (ALUMINIUM, STEEL, MaterialArrays, Model, ModelError, Section, SectionArrays,
                         solve_modes)

TUBE = Section.tube(0.01, 0.001, name="tube")


def cantilever(sections, materials) -> Model:
    """Four elements along x, clamped at node 1; element k gets ``sections[k]``..."""
    m = Model()
    m.add_nodes(np.arange(1, 6), np.c_[np.linspace(0, 1, 5), np.zeros(5), np.zeros(5)])
    for k, (s, mat) in enumerate(zip(sections, materials)):
        m.add_beams([k + 1], [[k + 1, k + 2]], s, mat, orient=[0, 1, 0])
    m.fix(1)
    return m


def test_per_element_arrays_give_the_model_of_one_call_per_element():
    """One add_beams call with arrays over four elements equals four calls of one Section
    and one Material each: same beams, same frequencies."""
    secs = [TUBE, Section.tube(0.012, 0.001), Section.rectangle(0.02, 0.01), TUBE]
    mats = [ALUMINIUM, STEEL, ALUMINIUM, STEEL]
    one_by_one = cantilever(secs, mats)
    arrays = Model()
    arrays.add_nodes(np.arange(1, 6), np.c_[np.linspace(0, 1, 5), np.zeros(5), np.zeros(5)])
    sec = SectionArrays(*([getattr(s, k) for s in secs] for k in ("A", "Iy", "Iz", "J", "Asy", "Asz")),
                        name="mixed")
    mat = MaterialArrays(*([getattr(m, k) for m in mats] for k in ("E", "G", "rho")), name="mixed")
    arrays.add_beams([1, 2, 3, 4], np.c_[np.arange(1, 5), np.arange(2, 6)], sec, mat, orient=[0, 1, 0])
    arrays.fix(1)
    a, b = one_by_one.beams, arrays.beams
    for key in ("A", "Iy", "Iz", "J", "Asy", "Asz", "E", "G", "rho"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key))
    np.testing.assert_allclose(solve_modes(arrays, n_modes=4).frequencies_hz,
                               solve_modes(one_by_one, n_modes=4).frequencies_hz, rtol=1e-12)


def test_a_mapping_is_read_as_the_arrays_it_names():
    """The compatibility path (the testbed builder passes dicts): a mapping of the fields
    gives the same beams as the typed arrays."""
    fields = dict(A=TUBE.A, Iy=TUBE.Iy, Iz=TUBE.Iz, J=TUBE.J)
    from_dict = cantilever([fields], [dict(E=70e9, G=26e9, rho=2700.0)]).beams
    typed = cantilever([SectionArrays(**fields)], [MaterialArrays(70e9, 26e9, 2700.0)]).beams
    for key in ("A", "Iy", "Iz", "J", "Asy", "Asz", "E", "G", "rho"):
        np.testing.assert_array_equal(getattr(from_dict, key), getattr(typed, key))
    assert np.isinf(typed.Asy).all()  # no shear area given: no shear deformation


@pytest.mark.parametrize("make, message", [
    (lambda: SectionArrays(A="wide", Iy=1.0, Iz=1.0, J=1.0, name="PBAR 3"),
     r"section 'PBAR 3': A must be numbers, got 'wide'"),
    (lambda: SectionArrays(A=np.ones((2, 2)), Iy=1.0, Iz=1.0, J=1.0, name="PBAR 3"),
     r"section 'PBAR 3': A must be one value or one per element, got shape \(2, 2\)"),
    (lambda: SectionArrays(A=[1.0, 2.0], Iy=1.0, Iz=1.0, J=1.0, name="PBAR 3").per_element(3),
     r"section 'PBAR 3': A has 2 values for 3 elements"),
    (lambda: SectionArrays.of({"A": 1.0, "Iy": 1.0, "Iz": 1.0}, "strut 2"),
     r"section 'strut 2': J not given"),
    (lambda: SectionArrays.of({"A": 1.0, "Iy": 1.0, "Iz": 1.0, "J": 1.0, "Ix": 2.0}, "strut 2"),
     r"section 'strut 2': unknown field\(s\) Ix"),
    (lambda: MaterialArrays.of({"E": 1.0, "G": 1.0}, "MAT1 4"), r"material 'MAT1 4': rho not given"),
    (lambda: MaterialArrays(E=[1.0, 2.0, 3.0], G=1.0, rho=["dense"], name="MAT1 4"),
     r"material 'MAT1 4': rho must be numbers, got \['dense'\]"),
    (lambda: SectionArrays.of(3.0), r"a section must be a Section, SectionArrays or a mapping"),
])
def test_a_bad_field_is_named_with_its_property(make, message):
    with pytest.raises(ModelError, match=message):
        make()


def test_add_beams_names_the_property_whose_arrays_do_not_fit_the_elements():
    m = Model()
    m.add_nodes([1, 2, 3], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    with pytest.raises(ModelError, match=r"material 'PBAR 7': E has 3 values for 2 elements"):
        m.add_beams([1, 2], [[1, 2], [2, 3]], TUBE, {"E": [1.0, 2.0, 3.0], "G": 1.0, "rho": 1.0},
                    orient=[0, 1, 0], label="PBAR 7")
