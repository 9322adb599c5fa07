"""The constraint interface: rows placed one block after another, named row blocks, the optional constant entries."""

import numpy as np
import pytest

from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.constraint_base import Constraint
from amlip_qp.robots import load_robot
from wbc_cases import FIELDS, kin_at, target_for


class _Rows(Constraint):
    """Writes ``b[rows] = 1, 2, ...``: enough to see where its rows went."""

    def write(self, inputs, dynamics, problem):
        problem.b[self.rows] = np.arange(1.0, self.size + 1.0)

    def symbolic(self, sym, dyn):
        return {}


def test_place_moves_the_rows_and_keeps_the_size():
    c = _Rows("block", slice(0, 3))
    assert c.kind == "eq" and c.size == 3
    assert c.place(5) == 8
    assert c.rows == slice(5, 8) and c.size == 3
    assert c.row_blocks() == [("block", slice(5, 8))]
    assert _Rows("empty", slice(0, 0)).place(7) == 7


def test_an_implementation_must_write_and_give_its_symbolic_entries():
    with pytest.raises(TypeError, match="abstract"):
        Constraint("bare", slice(0, 1))


def test_the_default_initialize_writes_nothing_and_write_fills_only_its_rows():
    kin = kin_at(load_robot("rabbit"), seed=2)
    builder = WholeBodyQP(kin.robot)
    P = builder.build(kin, target_for(kin, "left")).copy()
    for name in FIELDS:
        getattr(P, name)[...] = 777.0
    before = {name: getattr(P, name).copy() for name in FIELDS}
    c = _Rows("block", slice(0, 2))
    c.place(1)
    c.initialize(P)
    for name in FIELDS:
        assert np.array_equal(getattr(P, name), before[name]), name
    c.write(builder.inputs, builder.dynamics, P)
    assert P.b[:4].tolist() == [777.0, 1.0, 2.0, 777.0]
    assert np.all(P.b[3:] == 777.0)
