"""One table of a robot profile being read: each key taken once and checked, what is left over an unknown key.

:class:`Table` is what :mod:`amlip_qp.profiles.reader` reads a profile's
tables with: every failure is one :class:`~amlip_qp.exceptions.ProfileError`
line naming the file and the key.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from amlip_qp.exceptions import ProfileError


class Table:
    """One TOML table being read: each key is taken once; what is left over is an unknown key."""

    def __init__(self, source: Path, where: str, data: Any):
        self.source, self.where = source, where
        if not isinstance(data, Mapping):
            self.fail(f"must be a table, got {type(data).__name__}")
        self.data = dict(data)
        self.taken: set[str] = set()

    def key_path(self, key: str) -> str:
        return f"{self.where}.{key}" if self.where else key

    def fail(self, message: str, key: str | None = None) -> Any:
        where = self.key_path(key) if key is not None else (self.where or "top level")
        raise ProfileError(f"{self.source}: {where}: {message}")

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = ...) -> Any:
        self.taken.add(key)
        if key not in self.data:
            if default is ...:
                self.fail("is required", key)
            return default
        return self.data[key]

    def table(self, key: str, required: bool = True) -> Table | None:
        value = self.raw(key, ... if required else None)
        return None if value is None else Table(self.source, self.key_path(key), value)

    def string(self, key: str, default: Any = ..., choices: tuple[str, ...] = ()) -> Any:
        value = self.raw(key, default)
        if value is default and default is not ...:
            return value
        if not isinstance(value, str) or not value.strip():
            self.fail(f"must be a non-empty string, got {value!r}", key)
        if choices and value not in choices:
            self.fail(f"must be one of {', '.join(choices)}, got {value!r}", key)
        return value

    def boolean(self, key: str, default: Any = ...) -> Any:
        value = self.raw(key, default)
        if not isinstance(value, bool):
            self.fail(f"must be true or false, got {value!r}", key)
        return value

    def number(
        self,
        key: str,
        default: Any = ...,
        *,
        low: float = -math.inf,
        high: float = math.inf,
        unit: str = "",
        finite: bool = True,
    ) -> Any:
        value = self.raw(key, default)
        if value is default and default is not ...:
            return value
        return check_number(self, key, value, low, high, unit, finite)

    def vector(self, key: str, size: int, default: Any = ..., unit: str = "") -> Any:
        value = self.raw(key, default)
        if value is default and default is not ...:
            return value
        if not isinstance(value, list) or len(value) != size:
            self.fail(f"must be a list of {size} numbers ({unit}), got {value!r}", key)
        return tuple(check_number(self, key, v, -math.inf, math.inf, unit, True) for v in value)

    def rows(self, key: str, size: int, default: Any = ..., unit: str = "") -> Any:
        """A list of rows of ``size`` numbers as a tuple of float tuples (``[]`` gives ``()``)."""
        value = self.raw(key, default)
        if value is default and default is not ...:
            return value
        if not isinstance(value, list) or not all(isinstance(r, list) and len(r) == size for r in value):
            self.fail(f"must be a list of rows of {size} numbers ({unit}), got {value!r}", key)
        return tuple(tuple(check_number(self, key, v, -math.inf, math.inf, unit, True) for v in r) for r in value)

    def done(self) -> None:
        unknown = sorted(set(self.data) - self.taken)
        if unknown:
            known = ", ".join(sorted(self.taken))
            self.fail(f"unknown key {unknown[0]!r} (known here: {known})", None)


def check_number(t: Table, key: str, value: Any, low: float, high: float, unit: str, finite: bool) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        t.fail(f"must be a number{f' ({unit})' if unit else ''}, got {value!r}", key)
    value = float(value)
    if math.isnan(value) or (finite and math.isinf(value)):
        t.fail(f"must be a finite number, got {value!r}", key)
    if not low <= value <= high:
        t.fail(f"{value:g}{f' {unit}' if unit else ''} is outside [{low:g}, {high:g}]", key)
    return value
