"""QPProblem: validation, residuals and the qpsolvers conversion."""

import copy
import pickle

import numpy as np
import pytest

from amlip_qp.exceptions import QPError
from amlip_qp.qp import QPProblem


def random_problem(seed: int, n: int = 8, n_eq: int = 2, n_in: int = 4) -> QPProblem:
    """A feasible, strictly convex random QP (x = 0 is feasible)."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(n, n))
    A = rng.normal(size=(n_eq, n))
    C = rng.normal(size=(n_in, n))
    return QPProblem(
        H=M @ M.T + np.eye(n),
        g=rng.normal(size=n),
        A=A,
        b=np.zeros(n_eq),
        C=C,
        l=-rng.uniform(0.1, 1.0, n_in),
        u=np.r_[rng.uniform(0.1, 1.0, n_in - 1), np.inf],
        lb=-np.ones(n),
        ub=np.ones(n),
        variables={"x": slice(0, n)},
    )


def test_residuals_measure_violations():
    p = random_problem(0)
    x = np.full(p.n, 2.0)
    r = p.residuals(x)
    assert r["box"] == pytest.approx(1.0)
    assert r["eq"] == pytest.approx(np.max(np.abs(p.A @ x)))
    assert p.residuals(np.zeros(p.n)) == {"eq": 0.0, "in": 0.0, "box": 0.0}


def test_objective_value():
    p = random_problem(1)
    x = np.linspace(-0.5, 0.5, p.n)
    assert p.objective(x) == pytest.approx(0.5 * x @ p.H @ x + p.g @ x)


def test_validate_names_nan_field():
    p = random_problem(2)
    p.g[3] = np.nan
    with pytest.raises(QPError, match="g contains NaN") as info:
        p.validate()
    assert info.value.problem is p


def test_validate_names_bad_shape_and_crossed_bounds():
    p = random_problem(3)
    p.b = np.zeros(5)
    with pytest.raises(QPError, match="b has shape"):
        p.validate()
    p = random_problem(3)
    p.lb[0] = 2.0
    with pytest.raises(QPError, match="lower bound above its upper bound"):
        p.validate()


@pytest.mark.parametrize(
    ("field", "index", "value"), [("H", (1, 2), np.inf), ("A", (1, 0), np.nan), ("C", (3, 7), -np.inf)]
)
def test_validate_names_non_finite_matrix_entry(field, index, value):
    p = random_problem(6)
    p.validate()
    getattr(p, field)[index] = value
    with pytest.raises(QPError, match=f"{field} contains NaN or inf"):
        p.validate()


def test_validate_accepts_infinite_bounds_and_names_nan_bound():
    p = random_problem(7)
    p.l[0], p.ub[2] = -np.inf, np.inf
    p.validate()
    p.ub[2] = np.nan
    with pytest.raises(QPError, match="bound ub contains NaN"):
        p.validate()


def test_qpsolvers_conversion_drops_infinite_rows_and_solves():
    p = random_problem(4)
    qp = p.to_qpsolvers()
    # one row has u = +inf: 4 upper rows minus 1, plus 4 lower rows
    assert qp.G.shape == (7, p.n)
    x = p.solve_with("quadprog")
    r = p.residuals(x)
    assert max(r.values()) < 1e-9


def test_unknown_backend_is_a_typed_error():
    with pytest.raises(QPError, match="not installed"):
        random_problem(5).solve_with("no-such-solver")


def test_leading_block_has_the_optimum_of_a_problem_with_trailing_variables_pinned_to_zero():
    p = random_problem(6, n=10, n_eq=3, n_in=6)
    p.variables = {"a": slice(0, 7), "b": slice(7, 10)}
    p.in_rows = [("kept", slice(0, 4)), ("free", slice(4, 6))]
    p.lb[7:] = p.ub[7:] = 0.0  # the last three variables pinned to zero
    p.l[4:], p.u[4:] = -np.inf, np.inf  # the last two rows free
    lead = p.leading(7, 4)
    assert (lead.n, lead.n_eq, lead.n_in) == (7, 3, 4)
    assert lead.variables == {"a": slice(0, 7)} and lead.in_rows == [("kept", slice(0, 4))]
    pairs = ((lead.H, p.H), (lead.g, p.g), (lead.A, p.A), (lead.b, p.b), (lead.C, p.C), (lead.l, p.l), (lead.u, p.u))
    for mine, whole in (*pairs, (lead.lb, p.lb), (lead.ub, p.ub)):
        assert np.shares_memory(mine, whole)  # views: later writes into the problem show
    x_full = p.solve_with("quadprog")
    x_lead = lead.solve_with("quadprog")
    np.testing.assert_allclose(x_lead, x_full[:7], atol=1e-9)
    assert np.all(x_full[7:] == 0.0)
    p.g[0] += 1.0
    assert lead.g[0] == p.g[0]
    with pytest.raises(QPError, match="leading"):
        p.leading(11, 4)
    with pytest.raises(QPError, match="leading"):
        p.leading(7, 7)


def allocated_problem(n: int = 6, n_eq: int = 2, n_in: int = 3) -> QPProblem:
    """An allocated problem filled from a valid random one."""
    src = random_problem(8, n, n_eq, n_in)
    p = QPProblem.allocate(n, n_eq, n_in, variables={"x": slice(0, n)})
    for name in ("H", "g", "A", "b", "C", "l", "u", "lb", "ub"):
        getattr(p, name)[...] = getattr(src, name)
    return p


def test_allocate_makes_zero_views_of_shared_buffers_with_the_problem_shapes():
    p = QPProblem.allocate(5, 2, 3, variables={"x": slice(0, 5)})
    assert (p.n, p.n_eq, p.n_in) == (5, 2, 3) and p.variables == {"x": slice(0, 5)}
    shapes = {k: getattr(p, k).shape for k in ("H", "g", "A", "b", "C", "l", "u", "lb", "ub")}
    assert shapes == {"H": (5, 5), "g": (5,), "A": (2, 5), "b": (2,), "C": (3, 5), "l": (3,), "u": (3,),
                      "lb": (5,), "ub": (5,)}  # fmt: skip
    for name in ("H", "g", "A", "b", "C", "l", "u", "lb", "ub"):
        arr = getattr(p, name)
        assert arr.flags.c_contiguous and not arr.flags.owndata and np.all(arr == 0.0)
    base = p.H.base
    assert all(getattr(p, k).base is base for k in ("g", "A", "b", "C"))  # one buffer for the finite fields
    assert p.l.base is p.lb.base and p.u.base is p.ub.base  # one of the lower bounds, one of the upper
    assert len({id(base), id(p.l.base), id(p.u.base)}) == 3
    p.validate()  # zeros: finite, l <= u
    assert p.copy().validate() is None
    with pytest.raises(QPError, match="sizes"):
        QPProblem.allocate(0, 1, 1)


def test_stacked_gives_the_rows_and_bounds_of_an_allocated_problem_as_views_in_the_solvers_order():
    """``[C; A]``, ``[lb; l]``, ``[ub; u]`` as views of the problem's own buffers (a solver reads them
    in place); ``None`` for a copy or once an array is replaced (its arrays then lie apart)."""
    p = allocated_problem(6, 2, 3)
    rows, lower, upper = p.stacked()
    np.testing.assert_array_equal(rows, np.vstack([p.C, p.A]))
    np.testing.assert_array_equal(lower, np.concatenate([p.lb, p.l]))
    np.testing.assert_array_equal(upper, np.concatenate([p.ub, p.u]))
    assert rows.shape == (5, 6) and rows.flags.c_contiguous
    for view, fields in ((rows, ("C", "A")), (lower, ("lb", "l")), (upper, ("ub", "u"))):
        assert all(np.shares_memory(view, getattr(p, k)) for k in fields)
    p.C[1, 2] = 7.0
    p.l[0] = -3.0
    assert rows[1, 2] == 7.0 and lower[6] == -3.0  # live views
    assert p.copy().stacked() is None
    p.C = p.C.copy()
    assert p.stacked() is None
    assert random_problem(1).stacked() is None


@pytest.mark.parametrize(
    ("field", "index", "value"),
    [("H", (1, 2), np.inf), ("g", (0,), np.nan), ("A", (1, 0), np.nan), ("b", (1,), -np.inf), ("C", (2, 5), np.nan)],
)
def test_allocated_problem_names_a_non_finite_entry_like_any_problem(field, index, value):
    p = allocated_problem()
    p.validate()
    getattr(p, field)[index] = value
    with pytest.raises(QPError, match=f"QP field {field} contains NaN or inf: check the state estimate") as info:
        p.validate()
    assert info.value.problem is p


@pytest.mark.parametrize("field", ["l", "u", "lb", "ub"])
def test_allocated_problem_names_a_nan_bound_and_a_crossed_pair(field):
    p = allocated_problem()
    getattr(p, field)[1] = np.nan
    with pytest.raises(QPError, match=f"QP bound {field} contains NaN"):
        p.validate()
    p = allocated_problem()
    p.l[0], p.u[0] = -np.inf, np.inf  # infinite bounds are fine
    p.validate()
    p.lb[2], p.ub[2] = 1.0, 0.5
    with pytest.raises(QPError, match="lower bound above its upper bound"):
        p.validate()


def test_allocated_problem_with_a_replaced_array_is_validated_in_full():
    p = allocated_problem()
    p.g = np.full(p.n, np.nan)  # no longer the allocated view: the general path checks it
    with pytest.raises(QPError, match="g contains NaN"):
        p.validate()
    p = allocated_problem()
    p.b = np.zeros(5)
    with pytest.raises(QPError, match="b has shape"):
        p.validate()
    p = allocated_problem()
    p.ub = p.lb - 1.0
    with pytest.raises(QPError, match="lower bound above"):
        p.validate()


@pytest.mark.parametrize("copier", ["deepcopy", "pickle"])
def test_a_deep_copy_of_an_allocated_problem_still_names_a_non_finite_entry(copier):
    """Its arrays are copied apart from its buffers: a NaN in the copy is still found."""
    p = allocated_problem()
    q = copy.deepcopy(p) if copier == "deepcopy" else pickle.loads(pickle.dumps(p))
    q.validate()
    q.H[0, 0] = np.nan
    with pytest.raises(QPError, match="QP field H contains NaN or inf"):
        q.validate()
    q.H[0, 0] = 1.0
    q.u[0] = q.l[0] - 1.0
    with pytest.raises(QPError, match="lower bound above its upper bound"):
        q.validate()
    p.validate()  # the original is untouched
