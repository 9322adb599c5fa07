"""A sweep cell: a mapping of every parameter, an id and a seed that depend on the cell only."""

from __future__ import annotations

from amlip_qp.sweep.cells import Cell


def test_cell_is_the_mapping_of_fixed_and_swept_parameters():
    cell = Cell(3, (("vx", 0.5), ("tracker", "qp")), (("robot", "rabbit"),))
    assert dict(cell) == {"robot": "rabbit", "vx": 0.5, "tracker": "qp"} and len(cell) == 3
    assert cell.task()["params"] == dict(cell) and cell.task()["index"] == 3


def test_id_and_seed_depend_on_the_values_not_on_order_or_index():
    a = Cell(0, (("vx", 0.5), ("tracker", "qp")))
    b = Cell(7, (("tracker", "qp"), ("vx", 0.5)))
    assert (a.id, a.seed) == (b.id, b.seed)
    c = Cell(0, (("vx", 0.6), ("tracker", "qp")))
    assert c.id != a.id and c.seed != a.seed
    assert Cell(0, a.swept, bisect=("push_impulse_Ns", 0.0, 60.0, 4)).id != a.id
    assert 0 <= a.seed < 2**31 and len(a.id) == 12


def test_a_swept_seed_is_the_walk_seed():
    assert [Cell(i, (("seed", s),)).seed for i, s in enumerate((0, 5, 12))] == [0, 5, 12]


def test_a_swept_seed_that_is_not_a_non_negative_integer_is_an_input_error():
    import pytest

    from amlip_qp.exceptions import InputError

    for bad in ("a", 1.5, -1, True):
        with pytest.raises(InputError, match="seed must be a non-negative integer"):
            _ = Cell(0, (("seed", bad), ("tracker", "qp"))).seed
