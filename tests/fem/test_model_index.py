"""``Model.index_of``: node ids to node indices, sorted once per set of nodes (issue 22).

Assembly, constraints, actuators and rendering look nodes up many times (per rigid body, per
element group); the sort of all node ids is kept until nodes are added, never stale.
"""

import numpy as np
import pytest

from trussid.fem import Model, ModelError


def _model():
    m = Model()
    m.add_nodes([30, 10, 20], np.zeros((3, 3)))
    return m


def test_indices_follow_the_order_nodes_were_added_in():
    m = _model()
    np.testing.assert_array_equal(m.index_of([[10, 20], [30, 10]]), [[1, 2], [0, 1]])


def test_node_ids_are_sorted_once_for_many_lookups(monkeypatch):
    m = _model()
    calls = []
    argsort = np.argsort
    monkeypatch.setattr(np, "argsort", lambda *a, **k: calls.append(1) or argsort(*a, **k))
    for _ in range(50):
        m.index_of([20])
    assert len(calls) == 1


def test_nodes_added_after_a_lookup_are_found():
    m = _model()
    assert m.index_of([20])[0] == 2
    m.add_nodes([5], [[1.0, 0, 0]])
    np.testing.assert_array_equal(m.index_of([5, 20]), [3, 2])


def test_a_duplicate_added_after_a_lookup_is_still_an_error():
    m = _model()
    m.index_of([10])
    m.add_nodes([10], [[1.0, 0, 0]])
    with pytest.raises(ModelError, match="node 10 is defined more than once"):
        m.index_of([20])


def test_an_unknown_id_names_the_referrer():
    with pytest.raises(ModelError, match=r"undefined node 7 \(referenced by beam 3\)"):
        _model().index_of([10, 7], what=lambda pos: f"beam {pos + 2}")
