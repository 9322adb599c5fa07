"""Tests of amlip_qp.alip.planner_output: the planner's per-tick PlannerOutput, the constructor's object."""

from dataclasses import fields

import numpy as np
import pytest

from amlip_qp.alip.planner_output import planner_output
from amlip_qp.messages import PlannerOutput


def test_planner_output_is_the_constructor_with_positional_fields():
    names = [f.name for f in fields(PlannerOutput)]
    arrays = [np.arange(k, dtype=float) + i for i, k in enumerate((2, 2, 2, 2, 2, 3, 4, 4, 4))]
    values = [0.4, 0.2, *arrays, 0.1, 0.3, 0.2, -0.05]
    got, ref = planner_output(*values), PlannerOutput(**dict(zip(names, values)))
    assert type(got) is PlannerOutput and repr(got) == repr(ref)
    assert all(getattr(got, n) is v for n, v in zip(names, values))
    with pytest.raises(AttributeError):
        got.s = 0.5  # type: ignore[misc]
