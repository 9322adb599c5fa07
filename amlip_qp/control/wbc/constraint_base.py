"""The shape of every constraint of the whole-body QP: :class:`Constraint`.

A :class:`Constraint` owns a block of the problem: rows of ``A, b``
(``kind="eq"``), rows of ``C, l, u`` (``"in"``) or the box bounds ``lb, ub``
of some variables (``"box"``). It writes its constant entries once
(:meth:`~Constraint.initialize`), its varying entries every tick from the
gathered inputs (:meth:`~Constraint.write`, numpy, the reference), and gives
the same varying entries as CasADi expressions (:meth:`~Constraint.symbolic`)
for the generated build. The constraints themselves are in
:mod:`~amlip_qp.control.wbc.constraints`.
"""

from __future__ import annotations

import abc
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from amlip_qp.control.wbc.inputs import SymbolicInputs, TickInputs
    from amlip_qp.control.wbc.spring_elimination import ReducedDynamics, SymbolicDynamics
    from amlip_qp.qp.problem import QPProblem


class Constraint(abc.ABC):
    """One block of the problem (see the module doc).

    Attributes:
        name: The block's name (``QPProblem.eq_rows`` / ``in_rows``).
        kind: ``"eq"``, ``"in"`` or ``"box"``.
        size: Number of rows; for a box, of the variables it may bound.
        rows: Its rows of ``A, b`` or ``C, l, u`` (set by :meth:`place`), or
            for a box the slice of ``x`` it bounds.
    """

    kind: str = "eq"

    def __init__(self, name: str, rows: slice):
        self.name = name
        self.rows = rows

    @property
    def size(self) -> int:
        return self.rows.stop - self.rows.start

    def place(self, start: int) -> int:
        """Put the rows at ``start``; return the next free row."""
        self.rows = slice(start, start + self.size)
        return self.rows.stop

    def row_blocks(self) -> list[tuple[str, slice]]:
        """The named row blocks for ``QPProblem.eq_rows`` / ``in_rows``."""
        return [(self.name, self.rows)]

    def initialize(self, problem: QPProblem) -> None:  # noqa: B027 (optional hook: a no-op by design)
        """Write the entries that never change (once, on the fresh problem).

        The default writes nothing: a constraint whose entries all vary per tick need not override it.
        """

    @abc.abstractmethod
    def write(self, inputs: TickInputs, dynamics: ReducedDynamics, problem: QPProblem) -> None:
        """Write this tick's varying entries of its block."""

    @abc.abstractmethod
    def symbolic(self, sym: SymbolicInputs, dyn: SymbolicDynamics) -> dict[str, Any]:
        """The varying entries as expressions: ``{"A", "b"}`` (eq), ``{"C", "l",
        "u"}`` (in; ``None`` for an entry that never changes) or ``{"lb", "ub"}``
        (box: n-vectors, zero outside its variables; the problem's box is the sum)."""
