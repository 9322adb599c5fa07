"""A sweep cell: a frozen mapping parameter -> value, its stable id and its seed.

The id is a hash of everything that decides the cell's outcome (every
parameter, swept or fixed, and the bisection), so a finished cell in an output
folder is recognised whatever the order, backend or number of workers. The
seed is the cell's ``seed`` parameter when it has one, otherwise derived from
the same hash: each cell has its own seed, the same on every run.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from amlip_qp.exceptions import InputError

#: Hex digits of the cell id (48 bits: a collision in a million cells has odds below 1e-3).
ID_HEX_DIGITS = 12


def canonical_json(value: Any) -> str:
    """``value`` as compact JSON with sorted keys (floats as their shortest round-trip text)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False)


@dataclass(frozen=True)
class Cell(Mapping[str, Any]):
    """One point of a sweep: ``swept`` and ``fixed`` parameters (name -> value, in spec order).

    Attributes:
        index: Position in the sweep (the table's row order).
        swept: The swept parameters' values, ``((name, value), ...)``.
        fixed: The parameters held in every cell, ``((name, value), ...)``.
        bisect: The bisection, ``None`` or ``(parameter, low, high, iterations)``.
    """

    index: int
    swept: tuple[tuple[str, Any], ...]
    fixed: tuple[tuple[str, Any], ...] = ()
    bisect: tuple[str, float, float, int] | None = None

    # Mapping: every parameter (swept values win over fixed ones, which the spec forbids anyway)
    def __getitem__(self, name: str) -> Any:
        return self.params[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self.params)

    def __len__(self) -> int:
        return len(self.params)

    @property
    def params(self) -> dict[str, Any]:
        """All parameters of the walk: fixed, then swept."""
        return {**dict(self.fixed), **dict(self.swept)}

    def _identity(self) -> str:
        return canonical_json({"parameters": self.params, "bisect": list(self.bisect) if self.bisect else None})

    @property
    def id(self) -> str:
        """Stable id: a hash of the parameters and the bisection (not of the index)."""
        return hashlib.sha256(self._identity().encode()).hexdigest()[:ID_HEX_DIGITS]

    @property
    def seed(self) -> int:
        """The walk's seed: the ``seed`` parameter if set, else a 31-bit hash of the cell."""
        params = self.params
        if "seed" in params:
            seed = params["seed"]
            if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
                raise InputError(f"seed must be a non-negative integer, got {seed!r}")
            return seed
        return int(hashlib.sha256(("seed:" + self._identity()).encode()).hexdigest()[:8], 16) & 0x7FFFFFFF

    def task(self) -> dict[str, Any]:
        """The plain-data task of :func:`amlip_qp.sweep.run_cell.run_cell` (picklable, JSON-able)."""
        bis = None
        if self.bisect is not None:
            name, low, high, iterations = self.bisect
            bis = {"parameter": name, "low": low, "high": high, "iterations": iterations}
        return {"index": self.index, "id": self.id, "seed": self.seed, "params": self.params, "bisect": bis}
