"""The bisection of one parameter per cell: the largest value survived, on monotone outcomes with known edges."""

from __future__ import annotations

import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sweep.bisect import largest_surviving


@pytest.mark.parametrize("edge", [0.7, 17.3, 41.9999, 59.5])
def test_bisection_brackets_a_monotone_edge(edge):
    value, capped, trials = largest_surviving(lambda v: v <= edge, 0.0, 60.0, 6)
    assert not capped and value <= edge < value + 60.0 / 2**6
    assert trials[0] == (60.0, False) and len(trials) == 7
    assert all(ok == (v <= edge) for v, ok in trials)


def test_bisection_known_steps_and_cap():
    assert largest_surviving(lambda v: v < 20.0, 0.0, 60.0, 2) == (
        15.0,
        False,
        [(60.0, False), (30.0, False), (15.0, True)],
    )
    assert largest_surviving(lambda v: True, 10.0, 60.0, 5) == (60.0, True, [(60.0, True)])
    assert largest_surviving(lambda v: False, 0.0, 8.0, 3)[:2] == (0.0, False)


def test_bisection_refuses_an_empty_interval():
    with pytest.raises(InputError):
        largest_surviving(lambda v: True, 5.0, 5.0, 3)
