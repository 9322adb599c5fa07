"""The bounds of ``amlip-qp``'s numeric options that no other layer checks: each a number, its unit and why.

The options' value types (:mod:`~amlip_qp.cli.parsing`) refuse a value
outside these bounds while the command line is read, before any work, in one
line naming the option and the bound. Bounds that belong to a robot (speeds,
the duration of a walk, pushes: ``amlip_qp.profiles.CommandBounds``), to the
plant (the plant modifiers: ``amlip_qp.sim.world.plant_modifiers``), to the terrain
(``amlip_qp.sim.world.terrain``) or to a sweep spec (``amlip_qp.sweep.spec``) are
checked there, also before any work. The ones repeated here from a heavier
module (:data:`MAX_BISECTION_ITERATIONS`, :data:`MAX_VIDEO_FPS`) are held
equal to theirs by the tests, so ``--help`` needs no heavy import. The walk
options' own bounds (``MAX_SEED``, ``MAX_ACCEL_LIMIT_MPS2``) are the library's
(:mod:`amlip_qp.sim.scenarios.options`, a light module), taken from there.
"""

from __future__ import annotations

from amlip_qp.profiles import CommandBounds
from amlip_qp.sim.scenarios.options import MAX_ACCEL_LIMIT_MPS2, MAX_SEED

__all__ = [
    "MAX_ACCEL_LIMIT_MPS2",
    "MAX_BENCH_CALLS",
    "MAX_BENCH_CELLS",
    "MAX_BENCH_REPEATS",
    "MAX_BENCH_TICKS",
    "MAX_BISECTION_ITERATIONS",
    "MAX_DURATION_S",
    "MAX_SEED",
    "MAX_VIDEO_FPS",
    "MAX_WORKERS",
    "MIN_DURATION_S",
]

#: Shortest simulated time of a walk, s: one control tick of the closed loops, 0.5 ms (2 kHz; the same
#: as ``amlip_qp.sim.loop.run_types.CONTROL_DT_S``).
MIN_DURATION_S = 0.0005

#: Longest simulated time of one walk of a benchmark (``bench ekf``, ``bench harness``, ``bench sweep``)
#: and of a sweep cell (``sweep --duration``), s: the robots' ``CommandBounds.duration_max_s`` (600 s),
#: which keeps the preallocated per-tick log of a walk under 0.7 GB.
MAX_DURATION_S: float = CommandBounds.duration_max_s

#: Most worker processes of ``compare --jobs`` and ``sweep --workers``: 64. Each worker holds its own
#: robot, plant and per-tick log, about 0.17 GB for a 1 s Cassie walk (peak resident memory of
#: ``amlip-qp walk --duration 1``, measured), so 64 workers take about 11 GB; a larger machine is a
#: cluster: ``sweep --ray``.
MAX_WORKERS = 64

#: Most bisection iterations (``compare --push-iterations``, a sweep's ``--bisect`` / ``[bisect]``): 20.
#: Each iteration halves the interval (20 leave 1e-6 of it, 57 uN s of Cassie's 60 N s push search)
#: and is one more walk of several seconds per cell and push direction. The same as
#: ``amlip_qp.experiments.robustness.MAX_BISECTION_ITERATIONS``.
MAX_BISECTION_ITERATIONS = 20

#: Largest ``walk --video-fps``, frames per s: 240. The video plays in real time, and 240 Hz is the
#: refresh rate of the fastest common displays: more frames are never shown, yet each is rendered and
#: encoded, up to one a control tick (a 0.5 s walk at 1e9 frames/s rendered 1,000 frames in 97 s).
#: A ``.gif`` allows at most 100 (its frame delays are whole hundredths of a second). The same as
#: ``amlip_qp.sim.reports.video.MAX_VIDEO_FPS``.
MAX_VIDEO_FPS = 240.0

#: Most timed calls of ``bench codegen --calls``: 1,000,000. One call of every kernel on its three
#: paths takes about 0.42 ms (2,000 calls in 0.84 s, measured), so the bound is about 7 min.
MAX_BENCH_CALLS = 1_000_000

#: Most recorded QPs of ``bench qp --ticks``: 20,000 (10 s of walking at the 2 kHz control rate).
#: Each recorded problem is kept in memory, about 20 kB (the Cassie QP's arrays, measured), so the
#: bound is about 0.4 GB before the replays.
MAX_BENCH_TICKS = 20_000

#: Most repeats of ``bench harness --repeats`` and ``bench sweep --repeats``: 20. A repeat is a full
#: round of walks (every tracker and log mode; or a sweep on 1 and on 2 workers); the median of 20
#: is as steady as this machine's timing gets.
MAX_BENCH_REPEATS = 20

#: Most cells of ``bench sweep --cells``: 1,000 (each a walk of ``--duration`` s, run once on 1
#: worker and once on 2 per repeat); a sweep's own bound is ``amlip_qp.sweep.spec.MAX_CELLS``.
MAX_BENCH_CELLS = 1_000
