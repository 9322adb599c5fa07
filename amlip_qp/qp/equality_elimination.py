"""A QP's equalities eliminated: the same optimum as a smaller QP with inequalities only.

.. math::

    x = x_0 + Z y, \\qquad A x_0 = b, \\quad A Z = 0, \\quad Z^T Z = I

over the free variables (a fixed variable, ``lb == ub``, is substituted
first), from one complete QR factorisation ``A^T = [Q_1\\; Z] [R; 0]`` (LAPACK
``dgeqrf`` and ``dorgqr``): ``x_0 = Q_1 R^{-T} b``. The problem in ``y`` is

.. math::

    \\min_y \\tfrac12 y^T (Z^T H Z) y + (Z^T (H x_0 + g))^T y \\quad\\text{s.t.}\\quad
    l - C x_0 \\le C Z y \\le u - C x_0

where the rows are the inequality rows that have a finite bound and, below
them, the box rows of the free variables that have one (``Z`` picks their
rows). It has ``n - n_fixed - n_eq`` variables and no equality. On the whole-body QP
tracker's Cassie problems with the swing foot in the air (32 variables, 6 of
them fixed, 15 equalities) that is 11 variables and 29 rows; DAQP solves it
in about half the time it takes on the problem as built
(``amlip-qp bench qp``, runner ``daqp-eliminated``; docs/BENCH_QP.md).

:func:`eliminate_equalities` works in NumPy and LAPACK: a reference, and the
bench's measurement. The elimination costs about what it saves, in Python and
even as generated C, so the tracker does not use it (docs/TUNING.md,
"Controller speed: the equalities eliminated").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import lapack

from amlip_qp.exceptions import QPError
from amlip_qp.qp.problem import QPProblem

#: A pivot of ``R`` below this fraction of the largest is taken as a dependent equality row.
RANK_TOLERANCE = 1e-10


@dataclass(frozen=True)
class EliminatedQP:
    """A problem in ``y`` and the map back to the full ``x`` (module doc).

    Attributes:
        problem: The QP in ``y``: no equality, no box (its box rows are among its inequalities).
        basis: ``Z``, (n_free, n_y), orthonormal columns spanning the null space of the free
            variables' equality matrix.
        particular: ``x_0`` over the free variables, (n_free,): the least-norm solution of the equalities.
        free: Indices of the free variables in ``x``.
        fixed_x: The full ``x`` with the fixed variables at their values and zeros elsewhere.
    """

    problem: QPProblem
    basis: np.ndarray
    particular: np.ndarray
    free: np.ndarray
    fixed_x: np.ndarray

    def recover(self, y: np.ndarray) -> np.ndarray:
        """The full ``x`` of a ``y`` (a new array): ``x_free = x_0 + Z y``, the fixed variables at their values."""
        x = self.fixed_x.copy()
        x[self.free] = self.particular + self.basis @ np.asarray(y, dtype=float)
        return x


def eliminate_equalities(problem: QPProblem) -> EliminatedQP:
    """The problem's equalities and fixed variables eliminated (module doc).

    Raises:
        QPError: The equality rows are dependent over the free variables (rank below their
            number, naming the block; then they may also be inconsistent), or they leave no free
            variable. Rows of full rank always have a solution ``x_0``.
    """
    p = problem
    fixed_mask = p.lb == p.ub
    free = np.flatnonzero(~fixed_mask)
    fixed = np.flatnonzero(fixed_mask)
    fixed_x = np.zeros(p.n)
    fixed_x[fixed] = p.lb[fixed]
    xf = fixed_x[fixed]
    n_free, n_eq = free.size, p.n_eq
    if n_free <= n_eq:
        raise QPError(
            f"eliminate_equalities: {n_eq} equality rows leave none of the {n_free} free variables", problem=p
        )
    A = p.A[:, free]
    b = p.b - p.A[:, fixed] @ xf
    qr, tau, _, info = lapack.dgeqrf(np.asfortranarray(A.T))
    if info != 0:
        raise QPError(f"eliminate_equalities: LAPACK dgeqrf failed (info {info})", problem=p)
    pivots = np.abs(np.diagonal(qr[:n_eq, :n_eq])) if n_eq else np.zeros(0)
    if n_eq and pivots.min() <= RANK_TOLERANCE * max(pivots.max(), 1.0):
        row = int(np.argmin(pivots))
        block = next((name for name, s in p.eq_rows if s.start <= row < s.stop), "unnamed")
        raise QPError(
            f"eliminate_equalities: the equality rows are dependent (row {row}, block {block!r}): "
            "drop the redundant row",
            problem=p,
        )
    R = np.triu(qr[:n_eq, :n_eq])
    full = np.zeros((n_free, n_free), order="F")
    full[:, :n_eq] = qr
    Q, _, info = lapack.dorgqr(full, tau)
    if info != 0:
        raise QPError(f"eliminate_equalities: LAPACK dorgqr failed (info {info})", problem=p)
    Q1, Z = Q[:, :n_eq], np.ascontiguousarray(Q[:, n_eq:])
    x0 = Q1 @ (lapack.dtrtrs(R, b, trans=1)[0] if n_eq else np.zeros(0))

    H = p.H[np.ix_(free, free)]
    g = p.g[free] + p.H[np.ix_(free, fixed)] @ xf
    HZ = H @ Z
    Hy = Z.T @ HZ
    Hy = 0.5 * (Hy + Hy.T)
    gy = Z.T @ (H @ x0 + g)

    shift = p.C[:, fixed] @ xf
    C = p.C[:, free]
    keep_rows = np.flatnonzero(np.isfinite(p.l) | np.isfinite(p.u))
    box = np.flatnonzero(np.isfinite(p.lb[free]) | np.isfinite(p.ub[free]))
    rows_x0 = np.concatenate([C[keep_rows] @ x0, x0[box]])
    lo = np.concatenate([p.l[keep_rows] - shift[keep_rows], p.lb[free][box]]) - rows_x0
    hi = np.concatenate([p.u[keep_rows] - shift[keep_rows], p.ub[free][box]]) - rows_x0
    Cy = np.vstack([C[keep_rows] @ Z, Z[box]])
    n_y, n_rows = Z.shape[1], Cy.shape[0]
    reduced = QPProblem(
        H=Hy,
        g=gy,
        A=np.zeros((0, n_y)),
        b=np.zeros(0),
        C=Cy,
        l=lo,
        u=hi,
        lb=np.full(n_y, -np.inf),
        ub=np.full(n_y, np.inf),
        variables={"y": slice(0, n_y)},
        eq_rows=[],
        in_rows=[("inequalities", slice(0, keep_rows.size)), ("box", slice(keep_rows.size, n_rows))],
    )
    return EliminatedQP(reduced, Z, x0, free, fixed_x)
