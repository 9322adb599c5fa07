"""The sweep spec: a TOML file and/or ``--grid NAME=V1,V2``; grid or random sampling into cells.

A spec file::

    [sweep]
    sampling = "grid"            # or "random" (then: samples = N, sampling_seed = 0)
    metrics = ["survived", "mean_vx_mps"]   # default: amlip_qp.sweep.run_cell.DEFAULT_METRICS

    [fixed]                      # walk options and push parameters held in every cell
    robot = "cassie"
    vx = 1.0
    duration = 6.0

    [parameters]                 # the swept ones: a list, or a range
    tracker = ["pbc", "qp"]
    push_direction_deg = { start = 0, stop = 315, num = 8 }   # inclusive; or step = 45
    push_phase = { start = 0.0, stop = 0.8, num = 5 }

    [bisect]                     # optional: per cell, the largest value of one parameter survived
    parameter = "push_impulse_Ns"
    low = 0.0
    high = 60.0
    iterations = 5

Grid cells are the product of the parameters, the first one varying slowest.
Random sampling draws each parameter per sample (a list: one of its values; a
range with ``num`` or ``step``: one of its points; ``{start, stop}``: uniform)
with ``numpy.random.default_rng(sampling_seed)``; duplicate cells are dropped.

A sweep has at most :data:`MAX_CELLS` cells (the product of the grid's sizes,
or the random samples), counted from the sizes before anything is expanded,
and a bisection at most :data:`MAX_BISECTION_ITERATIONS` iterations.
"""

from __future__ import annotations

import itertools
import math
import sys
from dataclasses import dataclass, field
from typing import Any

from amlip_qp.exceptions import InputError
from amlip_qp.experiments.robustness import MAX_BISECTION_ITERATIONS
from amlip_qp.sweep.cells import Cell

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10: the same parser as a package (a dependency there)
    import tomli as tomllib

#: Significant digits that range points are rounded to (0.6000000000000001 -> 0.6).
RANGE_DIGITS = 12
#: Most cells of a sweep: 100,000. Before anything runs every cell's walk options are checked and
#: made a scenario, 1.2 ms a cell (10,000 Cassie cells in 12 s, measured on 2 busy cores), so about
#: 2 min at the bound; then each cell is a walk of seconds (about 3 days for 100,000 cells of 6 s
#: on 2 cores, hours on a Ray cluster), and one record file in ``cells/``. A larger sweep is several
#: sweeps, or random sampling.
MAX_CELLS = 100_000
_SECTIONS = ("sweep", "fixed", "parameters", "bisect")
_SWEEP_KEYS = ("sampling", "samples", "sampling_seed", "metrics")
_BISECT_KEYS = ("parameter", "low", "high", "iterations")
_RANGE_KEYS = ("start", "stop", "num", "step")


@dataclass(frozen=True)
class Range:
    """A numeric range: ``num`` points or a ``step`` from ``start`` to ``stop`` inclusive, or (random) uniform."""

    start: float
    stop: float
    num: int | None = None
    step: float | None = None

    def count(self) -> float:
        """How many points :meth:`points` gives, without listing them (a float: a huge range may be ``inf``)."""
        if self.num is not None:
            return float(self.num)
        if self.step is not None:
            spans = (self.stop - self.start) / self.step
            return math.floor(spans + 1e-9) + 1.0 if math.isfinite(spans) else math.inf
        return 1.0

    def points(self) -> list[float | int]:
        """The range's points (ints when start and step are ints), rounded to :data:`RANGE_DIGITS` digits."""
        if self.num is not None:
            if self.num == 1:
                return [self.start]
            values = [self.start + i * (self.stop - self.start) / (self.num - 1) for i in range(self.num)]
        elif self.step is not None:
            n = int(math.floor((self.stop - self.start) / self.step + 1e-9)) + 1
            if isinstance(self.start, int) and isinstance(self.step, int):
                return [self.start + i * self.step for i in range(n)]
            values = [self.start + i * self.step for i in range(n)]
        else:
            raise InputError(f"a range from {self.start:g} to {self.stop:g} needs num or step on a grid")
        return [float(f"{v:.{RANGE_DIGITS}g}") for v in values]


@dataclass(frozen=True)
class Bisect:
    """The bisection of one parameter per cell (:func:`amlip_qp.experiments.robustness.largest_surviving`)."""

    parameter: str
    low: float
    high: float
    iterations: int


@dataclass(frozen=True)
class SweepSpec:
    """A parsed spec (before the parameters are checked against ``walk``).

    Attributes:
        parameters: Swept name -> list of values or :class:`Range`, in spec order.
        fixed: Name -> value held in every cell.
        sampling: ``"grid"`` or ``"random"``.
        samples: Number of random samples.
        sampling_seed: Seed of the random sampling.
        metrics: The metric columns (``None``: the defaults, or the bisection's).
        bisect: The bisection, or ``None``.
    """

    parameters: dict[str, list[Any] | Range] = field(default_factory=dict)
    fixed: dict[str, Any] = field(default_factory=dict)
    sampling: str = "grid"
    samples: int | None = None
    sampling_seed: int = 0
    metrics: tuple[str, ...] | None = None
    bisect: Bisect | None = None

    def plain(self) -> dict[str, Any]:
        """The spec as plain JSON data (``spec.json`` of the output folder)."""
        params = {k: (v if isinstance(v, list) else {**v.__dict__}) for k, v in self.parameters.items()}
        return {
            "parameters": params,
            "fixed": self.fixed,
            "sampling": self.sampling,
            "samples": self.samples,
            "sampling_seed": self.sampling_seed,
            "metrics": list(self.metrics) if self.metrics is not None else None,
            "bisect": None if self.bisect is None else {**self.bisect.__dict__},
        }


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _value(name: str, v: Any) -> Any:
    if isinstance(v, bool) or isinstance(v, str) or _is_number(v):
        return v
    raise InputError(f"parameter {name!r}: a value must be a string, a finite number or a boolean, got {v!r}")


def _range(name: str, table: dict) -> Range:
    extra = sorted(set(table) - set(_RANGE_KEYS))
    if extra or "start" not in table or "stop" not in table:
        raise InputError(f"parameter {name!r}: a range is {{start, stop, num}} or {{start, stop, step}}, got {table}")
    start, stop, num, step = table["start"], table["stop"], table.get("num"), table.get("step")
    if not (_is_number(start) and _is_number(stop)) or stop < start:
        raise InputError(f"parameter {name!r}: a range needs numbers start <= stop, got {start!r}, {stop!r}")
    if num is not None and step is not None:
        raise InputError(f"parameter {name!r}: give num or step, not both")
    if num is not None and (isinstance(num, bool) or not isinstance(num, int) or num < 1):
        raise InputError(f"parameter {name!r}: num must be a positive integer, got {num!r}")
    if step is not None and not (_is_number(step) and step > 0):
        raise InputError(f"parameter {name!r}: step must be a positive number, got {step!r}")
    return Range(start, stop, num, step)


def _swept(name: str, v: Any) -> list[Any] | Range:
    if isinstance(v, dict):
        return _range(name, v)
    if not isinstance(v, list):
        v = [v]
    if not v:
        raise InputError(f"parameter {name!r} has an empty list: the grid would be empty")
    return [_value(name, x) for x in v]


def from_toml_text(text: str, source: str) -> dict[str, Any]:
    """The TOML document ``text``; a malformed one raises :class:`InputError` naming ``source`` and the line."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: malformed TOML: {exc}") from None


def load_spec_file(path: str) -> dict[str, Any]:
    """Read the TOML spec at ``path`` (an unreadable file or malformed TOML: :class:`InputError`)."""
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the sweep spec {path}: {getattr(exc, 'strerror', None) or exc}") from None
    return from_toml_text(text, path)


def parse_spec(doc: dict[str, Any]) -> SweepSpec:
    """A :class:`SweepSpec` from a TOML document's tables (structure checked; names are checked later)."""
    unknown = sorted(set(doc) - set(_SECTIONS))
    if unknown:
        raise InputError(f"unknown section [{unknown[0]}] in the sweep spec; known: {', '.join(_SECTIONS)}")
    for section in _SECTIONS:
        if section in doc and not isinstance(doc[section], dict):
            raise InputError(f"[{section}] must be a table")
    sw = doc.get("sweep", {})
    bad = sorted(set(sw) - set(_SWEEP_KEYS))
    if bad:
        raise InputError(f"unknown key {bad[0]!r} in [sweep]; known: {', '.join(_SWEEP_KEYS)}")
    metrics = sw.get("metrics")
    if metrics is not None and (not isinstance(metrics, list) or not all(isinstance(m, str) for m in metrics)):
        raise InputError(f"[sweep] metrics must be a list of names, got {metrics!r}")
    bisect = None
    if "bisect" in doc:
        b = doc["bisect"]
        if sorted(b) != sorted(_BISECT_KEYS):
            raise InputError(f"[bisect] needs exactly {', '.join(_BISECT_KEYS)}, got {', '.join(b) or 'nothing'}")
        it = b["iterations"]
        if not (isinstance(b["parameter"], str) and _is_number(b["low"]) and _is_number(b["high"])):
            raise InputError("[bisect] needs a parameter name and numbers low < high")
        if b["low"] >= b["high"] or isinstance(it, bool) or not isinstance(it, int) or it < 0:
            raise InputError(f"[bisect] needs low < high and iterations >= 0, got {b['low']}, {b['high']}, {it!r}")
        if it > MAX_BISECTION_ITERATIONS:
            raise InputError(
                f"[bisect] iterations must be at most {MAX_BISECTION_ITERATIONS} (each halves the interval and is "
                f"one more walk per cell), got {it}"
            )
        bisect = Bisect(b["parameter"], float(b["low"]), float(b["high"]), it)
    spec = SweepSpec(
        parameters={k: _swept(k, v) for k, v in doc.get("parameters", {}).items()},
        fixed={k: _value(k, v) for k, v in doc.get("fixed", {}).items()},
        sampling=sw.get("sampling", "grid"),
        samples=sw.get("samples"),
        sampling_seed=sw.get("sampling_seed", 0),
        metrics=None if metrics is None else tuple(metrics),
        bisect=bisect,
    )
    check_structure(spec)
    return spec


def check_structure(spec: SweepSpec) -> None:
    """Sampling, sample count, and parameters named twice or missing."""
    if spec.sampling not in ("grid", "random"):
        raise InputError(f"[sweep] sampling must be 'grid' or 'random', got {spec.sampling!r}")
    if spec.sampling == "random":
        n = spec.samples
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise InputError(f"random sampling needs [sweep] samples, a positive integer, got {n!r}")
    elif spec.samples is not None:
        raise InputError("[sweep] samples is for sampling = 'random'")
    seed = spec.sampling_seed
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"[sweep] sampling_seed must be a non-negative integer, got {seed!r}")
    if not spec.parameters:
        raise InputError("empty grid: nothing is swept; give [parameters] in the spec or --grid NAME=V1,V2")
    both = sorted(set(spec.parameters) & set(spec.fixed))
    if spec.bisect is not None:
        both += [spec.bisect.parameter] if spec.bisect.parameter in {**spec.parameters, **spec.fixed} else []
    if both:
        raise InputError(f"parameter {both[0]!r} is given twice (swept, fixed or bisected): give it once")
    if spec.bisect is not None and spec.metrics is not None:
        raise InputError("a bisection cell reports max_<parameter>; leave [sweep] metrics out with [bisect]")
    count = cell_count(spec)
    if count > MAX_CELLS:
        sizes = " x ".join(f"{_count(v):g}" for v in spec.parameters.values())
        what = f"{count:g} random samples" if spec.sampling == "random" else f"{count:g} cells ({sizes})"
        raise InputError(
            f"the sweep has {what}; at most {MAX_CELLS} cells are run (each is checked, then walked, for "
            "seconds): split it or sample it (sampling = 'random')"
        )


def _count(v: list[Any] | Range) -> float:
    return v.count() if isinstance(v, Range) else float(len(v))


def cell_count(spec: SweepSpec) -> float:
    """The number of cells before duplicates are dropped: the product of the grid's sizes, or the samples.

    Nothing is expanded, so a spec of 1e9 cells is counted at once (a float: ``inf`` past 1e308).
    """
    if spec.sampling == "random":
        return float(spec.samples or 0)
    return math.prod(_count(v) for v in spec.parameters.values())


def parse_cli_value(text: str) -> Any:
    """A ``--grid`` or ``--set`` value: an int, a float, ``true``/``false``, else the text."""
    low = text.strip().lower()
    if low in ("true", "false"):
        return low == "true"
    for kind in (int, float):
        try:
            value = kind(text)
        except ValueError:
            continue
        if _is_number(value):
            return value
    return text.strip()


def parse_assignment(text: str, option: str) -> tuple[str, str]:
    """``NAME=VALUE`` -> ``(name, value text)``; :class:`InputError` otherwise."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip() or not value.strip():
        raise InputError(f"{option} expects NAME=VALUE, got {text!r}")
    return name.strip(), value


def cells_of(spec: SweepSpec) -> list[Cell]:
    """The spec's cells in order (grid product, or random samples without duplicates)."""
    names = list(spec.parameters)
    fixed = tuple(spec.fixed.items())
    bis = (
        None
        if spec.bisect is None
        else (spec.bisect.parameter, spec.bisect.low, spec.bisect.high, spec.bisect.iterations)
    )
    if spec.sampling == "grid":
        axes = [v.points() if isinstance(v, Range) else v for v in spec.parameters.values()]
        combos = list(itertools.product(*axes))
    else:
        import numpy as np

        rng = np.random.default_rng(spec.sampling_seed)
        combos = []
        for _ in range(spec.samples or 0):
            row = []
            for v in spec.parameters.values():
                if isinstance(v, Range) and v.num is None and v.step is None:
                    row.append(float(f"{rng.uniform(v.start, v.stop):.{RANGE_DIGITS}g}"))
                else:
                    choices = v.points() if isinstance(v, Range) else v
                    row.append(choices[int(rng.integers(len(choices)))])
            combos.append(tuple(row))
    cells: list[Cell] = []
    seen: set[str] = set()
    for combo in combos:
        cell = Cell(len(cells), tuple(zip(names, combo)), fixed, bis)
        if cell.id not in seen:
            seen.add(cell.id)
            cells.append(cell)
    return cells
