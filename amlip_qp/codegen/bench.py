"""Time the planner kernels along three paths.

Paths:

- ``c-fast``: the generated C through :class:`amlip_qp.codegen.kernels.Kernels`
  (``casadi.external`` + ``Function.buffer()`` on preallocated arrays).
- ``casadi-function``: the SX ``casadi.Function`` called from Python on a
  numpy array, result converted back with ``.full()`` (what a controller
  would do without the fast path).
- ``numpy``: the reference :func:`amlip_qp.alip.kernels.alip_plan` /
  :func:`~amlip_qp.alip.kernels.swing_reference`.

Every sample is timed on its own with ``time.perf_counter_ns`` after a warm-up,
with the garbage collector left on (a controller runs with it on), on one
representative Cassie mid-step input. Reported, in microseconds:

- ``per_kernel[kernel][path]``: one call of that kernel per sample;
- ``per_tick[path]``: one ``alip_plan`` plus one ``swing_reference`` call per
  sample (the per-tick pair of the controller);
- ``paths[path]``: the per-tick pair divided by 2, i.e. time per kernel call
  in the per-tick pair; this is the headline figure.

Each entry has ``median_us`` and ``p99_us``.
"""

from __future__ import annotations

import platform
import time
from collections.abc import Callable

import numpy as np

from amlip_qp.alip import kernels
from amlip_qp.codegen import generate, symbolic
from amlip_qp.codegen.kernels import Kernels

PATHS = ("c-fast", "casadi-function", "numpy")
#: The kernels timed here: the per-tick pair (the step-timing MPC's QP kernel is timed with its
#: solve by ``amlip-qp bench mpc``, :mod:`amlip_qp.control.mpc.bench`).
TIMED = ("alip_plan", "swing_reference")

#: Representative Cassie mid-step inputs (layouts in :mod:`amlip_qp.alip.kernels`).
ALIP_PLAN_INPUT = np.array([-0.05, 0.08, -3.0, 8.0, 0.2, 0.0, 0.5, 0.0, 0.1, 1.0, 33.0, 0.9, 0.35, 0.2, 9.81, 0.0])
SWING_REFERENCE_INPUT = np.array([0.4, 0.35, 0.9, 0.1, 0.02, -0.01, -0.2, 0.25, 0.15, 0.2, 0.05, 0.0, 0.0, 0.0, 0.0])


def _stats(samples_ns: np.ndarray, divide: int = 1) -> dict[str, float]:
    us = samples_ns / (1000.0 * divide)
    return {"median_us": float(np.median(us)), "p99_us": float(np.percentile(us, 99))}


def _time_calls(call: Callable[[], object], calls: int, warmup: int) -> np.ndarray:
    """Time ``calls`` individual invocations of ``call`` (ns each), after ``warmup`` untimed ones."""
    for _ in range(warmup):
        call()
    out = np.empty(calls, dtype=np.int64)
    clock = time.perf_counter_ns
    for i in range(calls):
        t0 = clock()
        call()
        out[i] = clock() - t0
    return out


def _callables(fast: Kernels) -> dict[str, dict[str, Callable[[], object]]]:
    """``{path: {kernel: zero-argument callable}}`` on the representative inputs."""
    u_plan, u_swing = ALIP_PLAN_INPUT.copy(), SWING_REFERENCE_INPUT.copy()
    f_plan, f_swing = symbolic.function("alip_plan"), symbolic.function("swing_reference")
    fast_plan, fast_swing = fast.alip_plan, fast.swing_reference
    return {
        "c-fast": {"alip_plan": lambda: fast_plan(u_plan), "swing_reference": lambda: fast_swing(u_swing)},
        "casadi-function": {
            "alip_plan": lambda: f_plan(u_plan).full(),
            "swing_reference": lambda: f_swing(u_swing).full(),
        },
        "numpy": {
            "alip_plan": lambda: kernels.alip_plan(u_plan),
            "swing_reference": lambda: kernels.swing_reference(u_swing),
        },
    }


def run_benchmark(calls: int = 20000, warmup: int | None = None, fast: Kernels | None = None) -> dict:
    """Run the benchmark; return the JSON-ready result (schema in the module doc)."""
    fast = Kernels() if fast is None else fast
    warmup = min(2000, max(10, calls // 10)) if warmup is None else warmup
    per_kernel: dict[str, dict] = {name: {} for name in TIMED}
    per_tick: dict[str, dict] = {}
    paths: dict[str, dict] = {}
    for path, funcs in _callables(fast).items():
        for name in TIMED:
            per_kernel[name][path] = _stats(_time_calls(funcs[name], calls, warmup))
        plan, swing = funcs["alip_plan"], funcs["swing_reference"]

        def tick(plan=plan, swing=swing):
            plan()
            swing()

        pair = _time_calls(tick, calls, warmup)
        per_tick[path] = _stats(pair)
        paths[path] = _stats(pair, divide=2)
    ref = paths["casadi-function"]["median_us"]
    return {
        "paths": paths,
        "per_tick": per_tick,
        "per_kernel": per_kernel,
        "speedup_vs_casadi_function": {p: ref / paths[p]["median_us"] for p in PATHS},
        "c_fast_backend": fast.backend,
        "calls": calls,
        "warmup": warmup,
        "casadi_version": generate.CASADI_VERSION,
        "numpy_version": np.__version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
    }


def format_table(result: dict) -> str:
    """A readable table of :func:`run_benchmark`'s result."""
    rows = [("per call (tick pair / 2)", result["paths"]), ("per tick (both kernels)", result["per_tick"])]
    rows += [(name, result["per_kernel"][name]) for name in TIMED]
    lines = [
        f"amlip-qp bench codegen: {result['calls']} timed calls per entry after {result['warmup']} warm-up "
        f"(perf_counter_ns per sample, GC on; c-fast backend: {result['c_fast_backend']})",
        f"{'what':<26}{'path':<18}{'median_us':>11}{'p99_us':>11}",
    ]
    for label, table in rows:
        for path in PATHS:
            s = table[path]
            lines.append(f"{label:<26}{path:<18}{s['median_us']:>11.3f}{s['p99_us']:>11.3f}")
    speed = result["speedup_vs_casadi_function"]
    lines.append(
        "speedup vs casadi-function (per-call median): "
        + ", ".join(f"{p} {speed[p]:.1f}x" for p in PATHS if p != "casadi-function")
    )
    return "\n".join(lines)
