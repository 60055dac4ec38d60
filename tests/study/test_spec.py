"""Study specs: sampling is deterministic and complete, the hash covers what changes results,
and every mistake is one error naming the item."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from trussid.study.spec import StudyError, sample_points, spec_from_dict, spec_hash

NOMINAL = 0.0008


def wall_spec(**params):
    return {"study": {"evaluate": "modes"}, "evaluate": {"n_modes": 8},
            "parameters": params or {"wall0": {"low": 0.0006, "high": 0.0012, "num": 3},
                                     "wall1": {"values": [0.0007, 0.0009]}, "wall2": NOMINAL}}


def test_grid_is_the_product_of_the_axes_in_written_order_last_fastest():
    names, pts = sample_points(spec_from_dict(wall_spec()))
    assert names == ["wall0", "wall1", "wall2"]
    expected = list(itertools.product(np.linspace(0.0006, 0.0012, 3), [0.0007, 0.0009], [NOMINAL]))
    assert pts == [tuple(float(v) for v in p) for p in expected]


def test_latin_hypercube_is_seeded_stratified_and_within_the_ranges():
    d = {"study": {"evaluate": "modes"}, "sample": {"method": "lhs", "n": 50, "seed": 7},
         "parameters": {"wall0": {"low": 0.0006, "high": 0.0012}, "wall1": {"low": 0.001, "high": 0.002},
                        "wall2": NOMINAL}}
    _, a = sample_points(spec_from_dict(d))
    _, b = sample_points(spec_from_dict(d))
    assert a == b and len(a) == 50
    x = np.array(a)
    assert np.all(x[:, 2] == NOMINAL)
    # Latin hypercube: exactly one point in each of the n equal strata of every range.
    for j, (lo, hi) in enumerate([(0.0006, 0.0012), (0.001, 0.002)]):
        strata = np.floor((x[:, j] - lo) / (hi - lo) * 50).astype(int)
        assert sorted(strata) == list(range(50))
    d["sample"]["seed"] = 8
    assert sample_points(spec_from_dict(d))[1] != a


def test_list_sampling_zips_the_columns_and_repeats_fixed_values():
    d = {"study": {"evaluate": "identify"}, "sample": {"method": "list"},
         "parameters": {"seed": [1, 2, 3], "method": ["n4sid", "plid-subspace", "n4sid"], "order": 24}}
    names, pts = sample_points(spec_from_dict(d))
    assert pts == [(1, "n4sid", 24), (2, "plid-subspace", 24), (3, "n4sid", 24)]


def test_hash_changes_with_results_not_with_name_or_chunk():
    base = spec_from_dict(wall_spec())
    d = wall_spec()
    d["study"].update(name="renamed", chunk=3)
    assert spec_hash(spec_from_dict(d)) == spec_hash(base)
    d = wall_spec()
    d["evaluate"]["n_modes"] = 9
    assert spec_hash(spec_from_dict(d)) != spec_hash(base)
    d = wall_spec()
    d["parameters"]["wall2"] = NOMINAL * 1.01
    assert spec_hash(spec_from_dict(d)) != spec_hash(base)


def test_to_dict_reads_back_to_the_same_spec():
    s = spec_from_dict(wall_spec())
    assert spec_from_dict(s.to_dict()) == s


@pytest.mark.parametrize("change, words", [
    (lambda d: d["parameters"].update(wal3=0.001), ["'wal3'", "unknown parameter"]),
    (lambda d: d["parameters"].update(wall0={"low": 0.002, "high": 0.001, "num": 3}), ["'wall0'", "empty range"]),
    (lambda d: d["parameters"].update(wall1={"values": []}), ["'wall1'", "empty"]),
    (lambda d: d["parameters"].update(wall4=-0.001), ["'wall4'", "positive"]),
    (lambda d: d["study"].update(evaluate="modez"), ["'modez'", "evaluate"]),
    (lambda d: d["evaluate"].update(n_mode=3), ["'n_mode'", "unknown option"]),
    (lambda d: d.update(sample={"method": "sobol"}), ["'sobol'", "method"]),
    (lambda d: d["parameters"].update(wall0={"low": 0.001, "high": 0.002}), ["'wall0'", "num"]),
])
def test_a_bad_spec_is_one_error_naming_the_item(change, words):
    d = wall_spec()
    change(d)
    with pytest.raises(StudyError) as err:
        spec_from_dict(d, where="s.toml")
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("s.toml: ")
    for w in words:
        assert w in msg


def test_an_unknown_identification_method_is_named():
    d = {"study": {"evaluate": "identify"}, "parameters": {"method": ["n4sid", "plid-magic"]}}
    with pytest.raises(StudyError, match="'plid-magic'"):
        spec_from_dict(d)
