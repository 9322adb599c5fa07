"""Bad input to ``amlip-qp compare``: exit status 2, one line on stderr, no traceback, and nothing
simulated.

Every case runs through :func:`amlip_qp.cli.main` in this process with the simulation builders
replaced by a function that fails the test if called (the ``no_simulation`` fixture of
``conftest.py``), so a check that comes too late (after the simulation) shows as a failure, not as
a slow test.
"""

from __future__ import annotations

import pytest

from cli_bad_input_support import RABBIT_XML, assert_refused

#: (argv, a piece of the error line). ``{tmp}`` is a fresh folder, ``{file}`` a file in it, ``{bigpng}``
#: a PNG whose header says 12000 x 12000 pixels and that has no pixel data (so it cannot be decoded:
#: the refusal comes from the header alone), ``{no_pbc}`` H1's profile with the PBC unsupported.
BAD_INPUTS = [
    # the plant, the sensors and the estimator
    (["compare", "--jobs", "1", "--plant", "moon"], "unknown plant 'moon' for cassie"),
    (["compare", "--robots", "cassie", "--jobs", "1", "--plant", RABBIT_XML], "it lacks body 'cassie-pelvis'"),
    (["compare", "--sensors", "perfect"], "argument --sensors: invalid choice"),
    (["compare", "--estimator", "kalman"], "argument --estimator: invalid choice"),
    (["compare", "--jobs", "1", "--noise", "--sensors", "robot"], "--sensors robot has its own"),
    # plant modifiers: nonsensical values
    (["compare", "--jobs", "1", "--friction", "-0.5"], "--friction) must be a coefficient in [1e-05, 10]"),
    (["compare", "--jobs", "1", "--payload", "5@9,0,0"], "must be 3 numbers within 1 m of the base body"),
    # seeds, worker counts, iterations
    (["compare", "--jobs", "1000"], "argument --jobs: expected a number of worker processes in [1, 64], got 1000"),
    (["compare", "--jobs", "0"], "argument --jobs: expected a number of worker processes in [1, 64], got 0"),
    (
        ["compare", "--push-iterations", "1000000000"],
        "argument --push-iterations: expected a number of iterations in [0, 20], got 1000000000",
    ),
    (["compare", "--jobs", "1", "--terrain", "stairs:0:0.3"], "RISE_M must be a number in (0, 1], got 0"),
    # compare and the benchmarks
    (["compare", "--jobs", "1", "--json", "/proc/x.json"], "--json /proc/x.json: cannot write"),
    (["compare", "--jobs", "1", "--plot", "/proc/x.png"], "--plot /proc/x.png: cannot write"),
    (["compare", "--jobs", "1", "--json", "{tmp}/missing/x.json"], "does not exist"),
    (["compare", "--jobs", "1", "--plot", "{tmp}/cmp"], "figure file must end in"),
    (["compare", "--jobs", "1", "--plot", "{file}/cmp.png"], "is a file, not a folder"),
    (["compare", "--robots", "cassie,atlas"], "argument --robots: unknown robot 'atlas'"),
    (["compare", "--robots", ","], "expected a comma-separated list of robots"),
    (["compare", "--planners", "one-step,two-step"], "--planners: expected a comma-separated list from one-step, mpc"),
    (["compare", "--planners", ","], "--planners: expected a comma-separated list from one-step, mpc, got ','"),
    (["compare", "--jobs", "1", "--scenario", "moonwalk"], "unknown scenario"),
]


@pytest.mark.parametrize("argv, needle", BAD_INPUTS, ids=[" ".join(a) for a, _ in BAD_INPUTS])
def test_bad_input_exits_2_with_one_line_and_simulates_nothing(argv, needle, tmp_path, capsys, no_simulation):
    assert_refused(argv, needle, tmp_path, capsys)
