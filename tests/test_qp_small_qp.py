"""SmallQPSolver: a fixed-shape QP on one hot-started DAQP model, with soft rows."""

import numpy as np
import pytest

from amlip_qp.exceptions import InputError, QPError
from amlip_qp.qp.small_qp import SmallQPSolver

H = np.diag([2.0, 4.0])
G = np.array([-2.0, -4.0])  # unconstrained minimum (1, 1)


def test_unconstrained_and_active_row_solutions():
    s = SmallQPSolver(2, 1)
    np.testing.assert_allclose(
        s(H, G, np.array([[1.0, 1.0]]), [-1e9, -1e9, -10.0], [1e9, 1e9, 10.0]), [1.0, 1.0], atol=1e-12
    )
    # x0 + x1 <= 1: the minimum of (x0-1)^2 + 2 (x1-1)^2 on it is (1/3, 2/3)
    x = s(H, G, np.array([[1.0, 1.0]]), [-1e9, -1e9, -10.0], [1e9, 1e9, 1.0])
    np.testing.assert_allclose(x, [1.0 / 3.0, 2.0 / 3.0], atol=1e-12)
    assert s.solves == 2 and s.failures == 0


def test_a_soft_row_gives_way_to_a_hard_bound_and_a_hard_one_fails():
    C = np.array([[1.0, 0.0]])
    soft = SmallQPSolver(2, 1, soft_rows=(0,))
    x = soft(H, G, C, [-1e9, -1e9, 3.0], [2.0, 1e9, 4.0])  # the row wants x0 >= 3, the bound x0 <= 2
    assert x[0] == pytest.approx(2.0, abs=1e-9)
    hard = SmallQPSolver(2, 1)
    with pytest.raises(QPError):
        hard(H, G, C, [-1e9, -1e9, 3.0], [2.0, 1e9, 4.0])
    assert hard.failures == 1
    # after a failure the next solve starts afresh and succeeds
    np.testing.assert_allclose(hard(H, G, C, [-1e9, -1e9, -3.0], [1e9, 1e9, 4.0]), [1.0, 1.0], atol=1e-12)


@pytest.mark.parametrize("n, m, soft", [(0, 1, ()), (2, -1, ()), (2, 1, (1,)), (2.0, 1, ())])
def test_bad_sizes_raise(n, m, soft):
    with pytest.raises(QPError):
        SmallQPSolver(n, m, soft_rows=soft)


@pytest.mark.parametrize("soft", [(), (0,)])
def test_a_nan_row_fails_although_daqp_reports_it_solved(soft):
    """A hot-started DAQP update takes a NaN row and exits "solved" with a finite x: the residual
    check (NaN propagates through it, hard and soft rows alike) turns that into a QPError."""
    s = SmallQPSolver(2, 2, soft_rows=soft)
    rows, lower, upper = np.eye(2), [-1e9, -1e9, -10.0, -10.0], [1e9, 1e9, 10.0, 10.0]
    np.testing.assert_allclose(s(H, G, rows, lower, upper), [1.0, 1.0], atol=1e-12)
    with pytest.raises(QPError, match="exit flag 1"):
        s(H, G, np.array([[np.nan, 0.0], [0.0, 1.0]]), lower, upper)
    assert s.failures == 1


def test_solve_inputs_needs_a_producer_and_solves_what_it_makes():
    with pytest.raises(InputError, match="producer"):
        SmallQPSolver(2, 1).solve_inputs(np.zeros(3))
    rows = np.array([[1.0, 1.0]])

    def producer(u):  # the row's upper bound from the input: x0 + x1 <= u[0]
        return np.concatenate([H.ravel(), G, rows.ravel(), [-1e9, -1e9, -10.0], [1e9, 1e9, u[0]]])

    s = SmallQPSolver(2, 1, producer=producer)
    np.testing.assert_allclose(s.solve_inputs(np.array([1.0])), [1.0 / 3.0, 2.0 / 3.0], atol=1e-12)
    np.testing.assert_allclose(s.solve_inputs(np.array([10.0])), [1.0, 1.0], atol=1e-12)


def test_a_fast_step_or_producer_of_the_wrong_kind_is_refused_at_construction():
    with pytest.raises(InputError, match="fast_step must have a bind"):
        SmallQPSolver(2, 1, fast_step="compiled")
    with pytest.raises(InputError, match="producer must be callable"):
        SmallQPSolver(2, 1, producer=np.zeros(14))
