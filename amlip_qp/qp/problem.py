"""An inspectable dense QP in ProxQP's form.

.. math::

    \\min_x \\tfrac12 x^T H x + g^T x \\quad \\text{s.t.}\\quad
    A x = b,\\; l \\le C x \\le u,\\; l_{box} \\le x \\le u_{box}

Rows and variables carry names, so a failing problem can be read by a person:
``problem.variables["forces"]`` is the slice of the force variables,
``problem.eq_rows`` and ``problem.in_rows`` list ``(name, slice)`` blocks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from amlip_qp.exceptions import QPError

_sum = np.add.reduce
_all = np.logical_and.reduce


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

    def validate(self) -> None:
        """Check shapes and finiteness; raise :class:`QPError` naming the defect."""
        H, g, A, b, C, l, u, lb, ub = self.H, self.g, self.A, self.b, self.C, self.l, self.u, self.lb, self.ub
        n, n_eq, n_in = H.shape[0], A.shape[0], C.shape[0]
        got = (H.shape, g.shape, A.shape, b.shape, C.shape, l.shape, u.shape, lb.shape, ub.shape)
        expected = ((n, n), (n,), (n_eq, n), (n_eq,), (n_in, n), (n_in,), (n_in,), (n,), (n,))
        if got != expected:
            for name, shape, want in zip(("H", "g", "A", "b", "C", "l", "u", "lb", "ub"), got, expected):
                if shape != want:
                    raise QPError(f"QP field {name} has shape {shape}, expected {want}", problem=self)
        # Fast path, once per control tick: NaN and inf propagate through a sum (ufunc
        # reductions without ndarray.sum()'s wrapper; short vectors as Python floats, cheaper still).
        if not math.isfinite(_sum(H, None) + _sum(A, None) + _sum(C, None) + sum(g.tolist()) + sum(b.tolist())):
            for name in ("H", "g", "A", "b", "C"):
                if not np.all(np.isfinite(getattr(self, name))):
                    raise QPError(
                        f"QP field {name} contains NaN or inf: check the state estimate and gains", problem=self
                    )
        # Bounds may be +-inf, but never NaN; a crossed pair is infeasible by construction.
        if not (_all(l <= u) and _all(lb <= ub)):
            for name in ("l", "u", "lb", "ub"):
                if np.any(np.isnan(getattr(self, name))):
                    raise QPError(f"QP bound {name} contains NaN", problem=self)
            raise QPError("QP has a lower bound above its upper bound (infeasible by construction)", problem=self)

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
