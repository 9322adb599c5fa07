"""An inspectable dense QP in ProxQP's form.

.. math::

    \\min_x \\tfrac12 x^T H x + g^T x \\quad \\text{s.t.}\\quad
    A x = b,\\; l \\le C x \\le u,\\; l_{box} \\le x \\le u_{box}

Rows and variables carry names, so a failing problem can be read by a person:
``problem.variables["forces"]`` is the slice of the force variables,
``problem.eq_rows`` and ``problem.in_rows`` list ``(name, slice)`` blocks.

A problem made by :meth:`QPProblem.allocate` keeps its arrays as views of
three contiguous buffers (``H, g, C, A, b``; the lower bounds ``lb, l``; the
upper bounds ``ub, u``), so that :meth:`QPProblem.validate`, once per control
tick, checks finiteness with one reduction and the bound order with one
comparison while the fields are still those views, and a solver that takes
the rows and bounds stacked (DAQP: the box, then ``C``, then ``A``) reads them
as they lie (:meth:`QPProblem.stacked`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from amlip_qp.exceptions import InvalidQPError, QPError

_sum = np.add.reduce
_all = np.logical_and.reduce
_le = np.less_equal


@dataclass
class QPProblem:
    """A dense QP ``min 1/2 x'Hx + g'x  s.t.  Ax = b, l <= Cx <= u, lb <= x <= ub``.

    Attributes:
        H: Cost Hessian, (n, n), symmetric positive semi-definite.
        g: Cost gradient, (n,).
        A: Equality matrix, (n_eq, n).
        b: Equality right-hand side, (n_eq,).
        C: Inequality matrix, (n_in, n).
        l: Inequality lower bounds, (n_in,) (``-inf`` allowed).
        u: Inequality upper bounds, (n_in,) (``+inf`` allowed).
        lb: Box lower bounds on ``x``, (n,).
        ub: Box upper bounds on ``x``, (n,).
        variables: Name -> slice of ``x``.
        eq_rows: ``(name, slice)`` blocks of the equality rows.
        in_rows: ``(name, slice)`` blocks of the inequality rows.
    """

    H: np.ndarray
    g: np.ndarray
    A: np.ndarray
    b: np.ndarray
    C: np.ndarray
    l: np.ndarray
    u: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    variables: dict[str, slice] = field(default_factory=dict)
    eq_rows: list[tuple[str, slice]] = field(default_factory=list)
    in_rows: list[tuple[str, slice]] = field(default_factory=list)
    #: Set by :meth:`allocate`: the buffers and the views the fields were made as.
    _packed: _Packed | None = field(default=None, init=False, repr=False, compare=False)

    @classmethod
    def allocate(
        cls,
        n: int,
        n_eq: int,
        n_in: int,
        variables: dict[str, slice] | None = None,
        eq_rows: list[tuple[str, slice]] | None = None,
        in_rows: list[tuple[str, slice]] | None = None,
    ) -> QPProblem:
        """A problem of zeros (every array, bounds included) whose arrays are views of three
        contiguous buffers (see the module doc): fill it in place, never replace its arrays
        (a replaced array is still validated, by the general path)."""
        if min(n, n_eq, n_in) < 0 or n == 0:
            raise QPError(f"allocate({n}, {n_eq}, {n_in}): sizes must be >= 0 and n > 0")
        sizes = (n * n, n, n_in * n, n_eq * n, n_eq)
        data = np.zeros(sum(sizes))
        H, g, C, A, b = np.split(data, np.cumsum(sizes)[:-1])
        lower, upper = np.zeros(n + n_in), np.zeros(n + n_in)
        problem = cls(
            H.reshape(n, n), g, A.reshape(n_eq, n), b, C.reshape(n_in, n),
            lower[n:], upper[n:], lower[:n], upper[:n],
            variables=dict(variables or {}), eq_rows=list(eq_rows or []), in_rows=list(in_rows or []),
        )  # fmt: skip
        rows = data[n * n + n : n * n + n + (n_in + n_eq) * n].reshape(n_in + n_eq, n)
        problem._packed = _Packed(data, lower, upper, rows, problem)
        return problem

    @property
    def n(self) -> int:
        """Number of variables."""
        return self.H.shape[0]

    @property
    def n_eq(self) -> int:
        """Number of equality rows."""
        return self.A.shape[0]

    @property
    def n_in(self) -> int:
        """Number of two-sided inequality rows (box bounds not counted)."""
        return self.C.shape[0]

    def copy(self) -> QPProblem:
        """A deep copy (for recording problems while the builder reuses buffers)."""
        H, g, A, b, C, l, u, lb, ub = (
            np.array(getattr(self, k), copy=True) for k in ("H", "g", "A", "b", "C", "l", "u", "lb", "ub")
        )
        return QPProblem(
            H,
            g,
            A,
            b,
            C,
            l,
            u,
            lb,
            ub,
            variables=dict(self.variables),
            eq_rows=list(self.eq_rows),
            in_rows=list(self.in_rows),
        )

    def stacked(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """For a problem made by :meth:`allocate` whose arrays are still its views: ``(rows, lower,
        upper)``, views of its buffers (no copies; read only): ``rows`` = ``[C; A]``, shape
        (n_in + n_eq, n); ``lower`` = ``[lb; l]`` and ``upper`` = ``[ub; u]``, shape (n + n_in,).
        ``None`` for any other problem (its arrays lie apart)."""
        packed = self._packed
        H, g, A, b, C, l, u, lb, ub = self.H, self.g, self.A, self.b, self.C, self.l, self.u, self.lb, self.ub
        if packed is None or not packed.holds(H, g, A, b, C, l, u, lb, ub):
            return None
        return packed.rows, packed.lower, packed.upper

    def buffers(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """For a problem made by :meth:`allocate` whose arrays are still its views: its three buffers
        ``(data, lower, upper)`` (no copies; read only): ``data`` holds ``H, g, C, A, b`` flattened in
        that order, ``lower`` = ``[lb; l]`` and ``upper`` = ``[ub; u]``. ``None`` for any other
        problem."""
        packed = self._packed
        H, g, A, b, C, l, u, lb, ub = self.H, self.g, self.A, self.b, self.C, self.l, self.u, self.lb, self.ub
        if packed is None or not packed.holds(H, g, A, b, C, l, u, lb, ub):
            return None
        return packed.data, packed.lower, packed.upper

    def validate(self) -> None:
        """Check shapes and finiteness; raise :class:`~amlip_qp.exceptions.InvalidQPError` (a
        :class:`QPError`) naming the defect."""
        H, g, A, b, C, l, u, lb, ub = self.H, self.g, self.A, self.b, self.C, self.l, self.u, self.lb, self.ub
        packed = self._packed
        if packed is not None and packed.holds(H, g, A, b, C, l, u, lb, ub):
            # The allocated views (shapes fixed at allocation): one sum and one comparison; only if
            # either fails, the general path below names the defect.
            if math.isfinite(_sum(packed.data)) and _all(_le(packed.lower, packed.upper)):
                return
        n, n_eq, n_in = H.shape[0], A.shape[0], C.shape[0]
        got = (H.shape, g.shape, A.shape, b.shape, C.shape, l.shape, u.shape, lb.shape, ub.shape)
        expected = ((n, n), (n,), (n_eq, n), (n_eq,), (n_in, n), (n_in,), (n_in,), (n,), (n,))
        if got != expected:
            for name, shape, want in zip(("H", "g", "A", "b", "C", "l", "u", "lb", "ub"), got, expected):
                if shape != want:
                    raise InvalidQPError(f"QP field {name} has shape {shape}, expected {want}", problem=self)
        # Fast path, once per control tick: NaN and inf propagate through a sum (ufunc
        # reductions without ndarray.sum()'s wrapper; short vectors as Python floats, cheaper still).
        if not math.isfinite(_sum(H, None) + _sum(A, None) + _sum(C, None) + sum(g.tolist()) + sum(b.tolist())):
            for name in ("H", "g", "A", "b", "C"):
                if not np.all(np.isfinite(getattr(self, name))):
                    raise InvalidQPError(
                        f"QP field {name} contains NaN or inf: check the state estimate and gains", problem=self
                    )
        # Bounds may be +-inf, but never NaN; a crossed pair is infeasible by construction.
        if not (_all(l <= u) and _all(lb <= ub)):
            for name in ("l", "u", "lb", "ub"):
                if np.any(np.isnan(getattr(self, name))):
                    raise InvalidQPError(f"QP bound {name} contains NaN", problem=self)
            raise InvalidQPError(
                "QP has a lower bound above its upper bound (infeasible by construction)", problem=self
            )

    def objective(self, x: np.ndarray) -> float:
        """Cost ``1/2 x'Hx + g'x`` at ``x``."""
        return float(0.5 * x @ self.H @ x + self.g @ x)

    def residuals(self, x: np.ndarray) -> dict[str, float]:
        """Largest constraint violations at ``x``: ``eq``, ``in`` and ``box`` (>= 0)."""
        eq = float(np.max(np.abs(self.A @ x - self.b), initial=0.0))
        cx = self.C @ x
        ineq = float(np.max(np.maximum(self.l - cx, cx - self.u), initial=0.0))
        box = float(np.max(np.maximum(self.lb - x, x - self.ub), initial=0.0))
        return {"eq": eq, "in": max(ineq, 0.0), "box": max(box, 0.0)}

    def to_qpsolvers(self):
        """The same problem as a :class:`qpsolvers.Problem` (``G x <= h`` form)."""
        import qpsolvers

        rows_u = np.isfinite(self.u)
        rows_l = np.isfinite(self.l)
        G = np.vstack([self.C[rows_u], -self.C[rows_l]])
        h = np.concatenate([self.u[rows_u], -self.l[rows_l]])
        return qpsolvers.Problem(
            P=self.H,
            q=self.g,
            G=G if G.shape[0] else None,
            h=h if h.shape[0] else None,
            A=self.A if self.n_eq else None,
            b=self.b if self.n_eq else None,
            lb=self.lb,
            ub=self.ub,
        )

    def without_fixed_variables(self) -> tuple[QPProblem, np.ndarray, np.ndarray]:
        """The equivalent problem over the variables whose box is not a single point.

        Variables with ``lb == ub`` (e.g. the swing foot's forces in the air)
        are substituted. Active-set solvers such as quadprog reject the
        degenerate pair of opposite bounds they become; the reduced problem
        has the same optimum.

        Returns:
            ``(reduced, free, x_fixed)``: the reduced problem, the boolean mask
            of the free variables, and the values of the fixed ones.
        """
        fixed = self.lb == self.ub
        free = ~fixed
        x_fixed = self.lb[fixed].copy()
        if not np.any(fixed):
            return self, free, x_fixed
        off_c = self.C[:, fixed] @ x_fixed
        names: dict[str, slice] = {}
        reduced = QPProblem(
            H=self.H[np.ix_(free, free)],
            g=self.g[free] + self.H[np.ix_(free, fixed)] @ x_fixed,
            A=self.A[:, free],
            b=self.b - self.A[:, fixed] @ x_fixed,
            C=self.C[:, free],
            l=self.l - off_c,
            u=self.u - off_c,
            lb=self.lb[free],
            ub=self.ub[free],
            variables=names,
            eq_rows=list(self.eq_rows),
            in_rows=list(self.in_rows),
        )
        return reduced, free, x_fixed

    def leading(self, n: int, n_in: int) -> QPProblem:
        """The problem over the first ``n`` variables and the first ``n_in`` inequality rows (views, no copies).

        It has the same optimum as this problem when the dropped variables are
        fixed at zero (``lb = ub = 0``; e.g. the swing foot's forces in the
        air) and the dropped rows are free (``l = -inf``, ``u = +inf``): the
        dropped variables then add nothing to the cost, the equalities or the
        kept rows. Not checked (once per control tick); the caller knows.
        Variable and row names keep only the blocks wholly inside.

        Raises:
            QPError: ``n`` or ``n_in`` out of range.
        """
        if not (0 < n <= self.n and 0 <= n_in <= self.n_in):
            raise QPError(
                f"leading({n}, {n_in}) of a problem with {self.n} variables and {self.n_in} rows", problem=self
            )
        return QPProblem(
            H=self.H[:n, :n],
            g=self.g[:n],
            A=self.A[:, :n],
            b=self.b,
            C=self.C[:n_in, :n],
            l=self.l[:n_in],
            u=self.u[:n_in],
            lb=self.lb[:n],
            ub=self.ub[:n],
            variables={k: s for k, s in self.variables.items() if s.stop <= n},
            eq_rows=list(self.eq_rows),
            in_rows=[(k, s) for k, s in self.in_rows if s.stop <= n_in],
        )

    def solve_with(self, solver: str, **kwargs) -> np.ndarray:
        """Solve with any installed ``qpsolvers`` backend (cross-checks, benchmarks).

        Fixed variables (``lb == ub``) are substituted first
        (:meth:`without_fixed_variables`); the returned ``x`` has full size.

        Raises:
            QPError: the backend is not installed or found no solution.
        """
        import qpsolvers

        if solver not in qpsolvers.available_solvers:
            raise QPError(
                f"qpsolvers backend {solver!r} is not installed; available: {', '.join(qpsolvers.available_solvers)}",
                problem=self,
            )
        reduced, free, x_fixed = self.without_fixed_variables()
        solution = qpsolvers.solve_problem(reduced.to_qpsolvers(), solver=solver, **kwargs)
        if not solution.found or solution.x is None:
            raise QPError(f"qpsolvers backend {solver!r} found no solution", problem=self, status="not found")
        x = np.empty(self.n)
        x[free] = solution.x
        x[~free] = x_fixed
        return x


class _Packed:
    """The buffers of an :meth:`QPProblem.allocate` problem and its nine views, by identity."""

    __slots__ = ("data", "lower", "upper", "rows", "_views")

    def __init__(self, data: np.ndarray, lower: np.ndarray, upper: np.ndarray, rows: np.ndarray, problem: QPProblem):
        self.data, self.lower, self.upper, self.rows = data, lower, upper, rows
        p = problem
        self._views = (p.H, p.g, p.A, p.b, p.C, p.l, p.u, p.lb, p.ub)

    def holds(self, H, g, A, b, C, l, u, lb, ub) -> bool:
        """Whether these are still the allocated views (not replaced arrays) of these buffers
        (a deep copy or a pickle round trip copies every array apart: the general path then)."""
        v = self._views
        return (
            H is v[0] and g is v[1] and A is v[2] and b is v[3] and C is v[4]
            and l is v[5] and u is v[6] and lb is v[7] and ub is v[8]
            and H.base is self.data and l.base is self.lower and u.base is self.upper
        )  # fmt: skip
