"""Bad input to ``amlip-qp bench`` and ``codegen``: exit status 2, one line on stderr, no traceback, and nothing
simulated.

Every case runs through :func:`amlip_qp.cli.main` in this process with the simulation builders
replaced by a function that fails the test if called (the ``no_simulation`` fixture of
``conftest.py``), so a check that comes too late (after the simulation) shows as a failure, not as
a slow test.
"""

from __future__ import annotations

import pytest

from cli_bad_input_support import assert_refused

#: (argv, a piece of the error line). ``{tmp}`` is a fresh folder, ``{file}`` a file in it, ``{bigpng}``
#: a PNG whose header says 12000 x 12000 pixels and that has no pixel data (so it cannot be decoded:
#: the refusal comes from the header alone), ``{no_pbc}`` H1's profile with the PBC unsupported.
BAD_INPUTS = [
    # malformed values
    (["bench", "mpc", "--duration", "0"], "--duration"),
    (["bench", "mpc", "--json", "/proc/x"], "--json /proc/x: cannot write"),
    (["bench", "mpc", "--duration", "0.01"], "bench mpc needs --duration of at least 0.05 s"),
    # plant modifiers: nonsensical values
    (["bench", "ekf", "--scenario", "cassie-1mps"], "needs a scenario with the EKF estimator"),
    (["bench", "ekf", "--scenario", "nowhere"], "unknown scenario 'nowhere'"),
    (["bench", "ekf", "--duration", "0"], "--duration"),
    # compare and the benchmarks
    (["bench", "codegen", "--json", "/proc/x.json"], "--json /proc/x.json: cannot write"),
    (["bench", "qp", "--json", "/proc/x.json"], "--json /proc/x.json: cannot write"),
    (["bench", "codegen", "--calls", "1000000000000"], "--calls: expected a number of calls in [1, 1000000]"),
    (["bench", "qp", "--ticks", "1000000000"], "--ticks: expected a number of ticks in [1, 20000], got 1000000000"),
    (["bench", "ekf", "--duration", "1e9"], "--duration: expected a number in [0.0005, 600] s, got '1e9'"),
    (["bench", "harness", "--duration", "inf"], "--duration: expected a finite number, got 'inf'"),
    (["bench", "harness", "--repeats", "1000"], "--repeats: expected a number of repeats in [1, 20], got 1000"),
    (["bench", "sweep", "--cells", "1000000"], "--cells: expected a number of cells in [1, 1000], got 1000000"),
    (["bench", "sweep", "--duration", "1e-9"], "--duration: expected a number in [0.0005, 600] s, got '1e-9'"),
    # codegen's output folder
    (["codegen", "--out", "/proc/x"], "--out /proc/x: cannot create the folder (No such file or directory)"),
    (["codegen", "--out", "/sys/kernel"], "--out /sys/kernel: cannot write there (Permission denied)"),
    (["codegen", "--out", "{file}"], "is a file, not a folder; give a folder path"),
]


@pytest.mark.parametrize("argv, needle", BAD_INPUTS, ids=[" ".join(a) for a, _ in BAD_INPUTS])
def test_bad_input_exits_2_with_one_line_and_simulates_nothing(argv, needle, tmp_path, capsys, no_simulation):
    assert_refused(argv, needle, tmp_path, capsys)
