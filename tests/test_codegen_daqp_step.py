"""The small QP's compiled step: the same solutions and the same failures as its Python path."""

import numpy as np
import pytest

from amlip_qp.codegen import daqp_step
from amlip_qp.codegen.runtime import CodegenFallbackWarning
from amlip_qp.exceptions import InputError, QPError
from amlip_qp.qp.small_qp import SmallQPSolver
from codegen_cases import needs_cc


@pytest.fixture(scope="module")
def step():
    loaded = daqp_step.load_daqp_step()
    assert loaded is not None, "a C compiler is needed for the compiled step (the kernels' too)"
    return loaded


def _stacked_sequence(n, m, count, seed):
    """Stacked QPs ``(H, g, C, lower, upper)`` drifting from call to call, with bounds beyond DAQP's
    "no bound" (clamped), and now and then a row that contradicts its bounds or a NaN entry."""
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((n, n))
    H0, C0 = M @ M.T + n * np.eye(n), rng.standard_normal((m, n))
    for k in range(count):
        H = H0 + 0.1 * np.diag(rng.random(n))
        g = 3.0 * rng.standard_normal(n)
        C = C0 + 0.01 * rng.standard_normal(C0.shape)
        lower = np.concatenate([-0.5 * np.ones(n), -rng.random(m) - 0.1])
        upper = np.concatenate([0.5 * np.ones(n), rng.random(m) + 0.1])
        lower[n + 2], upper[n + 3] = -np.inf, 1e40
        if k % 40 == 11:
            upper[n + 4] = lower[n + 4] - 1.0
        if k % 40 == 23:
            C[5, 1] = np.nan
        yield np.concatenate([H.ravel(), g, C.ravel(), lower, upper])


def _outcome(solver, data):
    try:
        return solver.solve_stacked(data).tobytes()
    except QPError as exc:
        return str(exc)


def test_compiled_step_solutions_and_failures_equal_the_python_path(step):
    n, m, soft = 13, 24, (0, 1, 6, 7)
    fast = SmallQPSolver(n, m, soft_rows=soft, fast_step=step)
    plain = SmallQPSolver(n, m, soft_rows=soft)
    used = 0
    for data in _stacked_sequence(n, m, 400, seed=5):
        used += fast.fast_path
        assert _outcome(fast, data) == _outcome(plain, data)
    assert fast.failures == plain.failures and 0 < fast.failures < 100
    assert used > 300  # after each failure, one Python solve sets the model up again, then the step


def test_a_nan_row_reported_solved_fails_on_the_compiled_step(step):
    """As on the Python path: DAQP takes a NaN row in a hot-started update and exits "solved"."""
    H, G = np.diag([2.0, 4.0]), np.array([-2.0, -4.0])
    s = SmallQPSolver(2, 2, soft_rows=(1,), fast_step=step)
    lower, upper = [-1e9, -1e9, -10.0, -10.0], [1e9, 1e9, 10.0, 10.0]
    for _ in range(2):
        x = s.solve_stacked(np.concatenate([H.ravel(), G, np.eye(2).ravel(), lower, upper]))
        np.testing.assert_allclose(x, [1.0, 1.0], atol=1e-12)
    assert s.fast_path
    with pytest.raises(QPError, match="exit flag 1"):
        s.solve_stacked(np.concatenate([H.ravel(), G, [np.nan, 0.0, 0.0, 1.0], lower, upper]))
    assert s.failures == 1 and not s.fast_path


def test_a_stacked_problem_of_the_wrong_size_is_refused(step):
    good = np.concatenate([np.eye(2).ravel(), [-1.0, -1.0], [1.0, 1.0], [-5.0, -5.0, -5.0], [5.0, 5.0, 5.0]])
    s = SmallQPSolver(2, 1, fast_step=step)
    with pytest.raises(InputError, match="1-D array of 14 entries"):
        s.solve_stacked(good[:-1])  # the first solve, on the Python path
    s.solve_stacked(good)
    assert s.fast_path
    with pytest.raises(InputError, match="C-contiguous float64 array of 14 entries"):
        s.solve_stacked(good[:-1])


def test_without_a_compiler_the_python_path_runs_with_one_warning(monkeypatch, tmp_path):
    monkeypatch.setenv("AMLIP_QP_CC", "none")
    try:
        with pytest.warns(CodegenFallbackWarning, match="Python path"):
            assert daqp_step.load_daqp_step(cache_dir=tmp_path, refresh=True) is None
    finally:
        monkeypatch.undo()
        assert daqp_step.load_daqp_step(refresh=True) is not None


@needs_cc
def test_the_mpc_planner_on_the_fused_step_walks_the_python_paths_walk_bit_for_bit():
    """``make_mpc_planner``'s solver runs the QP kernel, DAQP and the check in one compiled call; a
    planner on the same kernels solving through the Python path steps the same, to the bit."""
    from alip_point_mass import OUTPUTS, REACH_M, G, H, M, T, Walk
    from amlip_qp.alip import step_mpc
    from amlip_qp.alip.mpc_planner import MPCPlanner
    from amlip_qp.codegen import load_kernels
    from amlip_qp.control.mpc import make_mpc_planner
    from amlip_qp.messages import Command

    command = Command(step_time_s=T, com_height_m=H, clearance_m=0.1, vx_mps=0.5, step_width_m=0.25)
    fused = make_mpc_planner(OUTPUTS, M, g=G)
    k = load_kernels()
    python_path = SmallQPSolver(step_mpc.N_VAR, step_mpc.N_ROWS, step_mpc.SOFT_ROWS)
    plain = MPCPlanner(OUTPUTS, M, python_path, g=G, plan_fn=k.alip_plan, reference_fn=k.swing_reference,
                       mpc_fn=k.alip_mpc_qp)  # fmt: skip
    walks = [Walk(p, command, reach_m=REACH_M).run(2.4, push=(0.95, np.array([2.6, 0.0]))) for p in (fused, plain)]
    assert fused.solve_fn.fast_path and not python_path.fast_path
    assert len(walks[0].steps) == len(walks[1].steps) >= 9
    for a, b in zip(walks[0].steps, walks[1].steps, strict=True):
        assert all(np.array_equal(u, v) for u, v in zip(a, b, strict=True))
    assert min(t1 - t0 for t0, t1, *_ in walks[0].steps) < T - 0.05  # the push shortened a step


def test_the_trackers_compiled_solve_equals_its_python_path_bit_for_bit(step):
    """DAQPSolver with the compiled call (the QP tracker's) against the Python path, on 80 QPs of the
    QP tracker walking cassie-1mps written one after the other into one allocated problem (as the
    tracker's builder does), with a NaN entry and a contradicting row among them: the same solutions,
    and the same failures."""
    from amlip_qp.experiments.bench_qp import record_walk
    from amlip_qp.qp import DAQPSolver, QPProblem

    problems, _, fell = record_walk(n_ticks=80, scenario="cassie-1mps", t_skip_s=0.6)
    assert not fell
    p0 = problems[0]
    target = QPProblem.allocate(p0.n, p0.n_eq, p0.n_in)
    fast, plain = DAQPSolver(fast_step=step), DAQPSolver()
    failed = []
    for k, p in enumerate(problems):
        for name in ("H", "g", "A", "b", "C", "l", "u", "lb", "ub"):
            getattr(target, name)[...] = getattr(p, name)
        if k == 30:
            target.C[2, 3] = np.nan
        if k == 50:
            target.u[4] = target.l[4] - 1.0
        outcomes = []
        for solver in (fast, plain):
            try:
                outcomes.append(solver.solve(target).x.tobytes())
            except QPError as exc:
                outcomes.append(str(exc))
        assert outcomes[0] == outcomes[1], f"problem {k}"
        if isinstance(outcomes[0], str):
            failed.append(k)
    assert 50 in failed and len(failed) < 10  # the contradicting row (the tracker validates against NaN first)
    assert fast.n_compiled >= 80 - 2 * len(failed) - 1 and plain.n_compiled == 0


def _defect(p, kind):
    """Write one defect of ``kind`` into the allocated problem ``p`` (or a valid extreme: an infinite
    bound, a large finite entry)."""
    if kind == "nan H":
        p.H[3, 5] = np.nan
    elif kind == "inf g":
        p.g[7] = np.inf
    elif kind == "nan C":
        p.C[2, 3] = np.nan
    elif kind == "-inf A":
        p.A[1, 0] = -np.inf
    elif kind == "nan b":
        p.b[-1] = np.nan
    elif kind == "crossed l, u":
        p.u[4] = p.l[4] - 1.0
    elif kind == "crossed lb, ub":
        p.lb[-1] = p.ub[-1] + 1e-12  # a swing force pinned at zero: 1e-12 above it
    elif kind == "nan l":
        p.l[0] = np.nan
    elif kind == "nan ub":
        p.ub[-1] = np.nan
    elif kind == "infinite bounds":  # valid
        p.l[1], p.u[2], p.lb[3], p.ub[4] = -np.inf, np.inf, -np.inf, np.inf
    elif kind == "large H":  # valid: finite, though the entries' sum overflows
        p.H[0, 1] = p.H[1, 0] = 1e308
        p.H[2, 3] = p.H[3, 2] = 1e308


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")  # validate's sum, "large H"
def test_the_trackers_compiled_check_refuses_exactly_what_validate_refuses(step):
    """``DAQPSolver.solve(problem, check=True)`` validates the problem inside the compiled call: on
    the QP tracker's recorded problems written into one allocated problem, each with one defect (a
    NaN or infinite entry of each matrix and vector, crossed or NaN bounds) or a valid extreme
    (infinite bounds, entries whose sum overflows), it raises :class:`InvalidQPError` with
    ``QPProblem.validate``'s message exactly when ``validate`` raises, as the Python path does, and
    otherwise gives the Python path's solution bit for bit."""
    from amlip_qp.exceptions import InvalidQPError
    from amlip_qp.experiments.bench_qp import record_walk
    from amlip_qp.qp import DAQPSolver, QPProblem

    problems, _, fell = record_walk(n_ticks=60, scenario="cassie-1mps", t_skip_s=0.6)
    assert not fell
    p0 = problems[0]
    target = QPProblem.allocate(p0.n, p0.n_eq, p0.n_in)
    kinds = [None, "nan H", None, "inf g", "nan C", None, "-inf A", "nan b", None, "crossed l, u",
             "crossed lb, ub", None, "nan l", "nan ub", None, "infinite bounds", None, "large H"]  # fmt: skip
    fast, plain = DAQPSolver(fast_step=step), DAQPSolver()
    invalid = 0
    for k, p in enumerate(problems):
        for name in ("H", "g", "A", "b", "C", "l", "u", "lb", "ub"):
            getattr(target, name)[...] = getattr(p, name)
        kind = kinds[k % len(kinds)] if k >= 2 else None  # the first two: set-up and binding
        _defect(target, kind)
        try:
            target.copy().validate()
            expected = None
        except InvalidQPError as exc:
            expected = str(exc)
        outcomes = []
        for solver in (fast, plain):
            compiled_before = solver.n_compiled
            try:
                outcomes.append(solver.solve(target, check=True).x.tobytes())
            except InvalidQPError as exc:
                outcomes.append(f"invalid: {exc}")
                assert solver is plain or solver.n_compiled == compiled_before + 1  # checked in the call
            except QPError as exc:
                outcomes.append(f"failed: {exc}")
        assert outcomes[0] == outcomes[1], f"problem {k} ({kind})"
        assert (expected is None) == (not isinstance(outcomes[0], str) or outcomes[0].startswith("failed"))
        if expected is not None:
            assert outcomes[0] == f"invalid: {expected}"
            invalid += 1
    valid_kinds = (None, "infinite bounds", "large H")
    assert invalid == sum(kinds[k % len(kinds)] not in valid_kinds for k in range(2, len(problems))) > 2 * 9
    assert fast.n_compiled >= 50 and plain.n_compiled == 0


def test_an_invalid_problem_leaves_the_compiled_solver_hot(step):
    """An invalid problem raises before DAQP is called: the next valid problem is solved by the same
    hot-started workspace (no new set-up) with the solution of a solver that never saw the invalid one."""
    from amlip_qp.exceptions import InvalidQPError
    from amlip_qp.experiments.bench_qp import record_walk
    from amlip_qp.qp import DAQPSolver, QPProblem

    problems, _, _ = record_walk(n_ticks=6, scenario="cassie-1mps", t_skip_s=0.6)
    p0 = problems[0]
    target = QPProblem.allocate(p0.n, p0.n_eq, p0.n_in)
    solvers = DAQPSolver(fast_step=step), DAQPSolver(fast_step=step)
    for k, p in enumerate(problems):
        for name in ("H", "g", "A", "b", "C", "l", "u", "lb", "ub"):
            getattr(target, name)[...] = getattr(p, name)
        x = [s.solve(target, check=True).x.tobytes() for s in solvers]
        assert x[0] == x[1]
        if k == 3:
            target.H[0, 0] = np.nan
            with pytest.raises(InvalidQPError, match="QP field H contains NaN"):
                solvers[0].solve(target, check=True)
    assert solvers[0].n_init == solvers[1].n_init == 1
    assert solvers[0].n_compiled == solvers[1].n_compiled + 1 == len(problems) - 1 + 1


def test_the_invalid_problem_flag_is_the_c_sources():
    """``INVALID_PROBLEM`` is the value ``daqp_step.c`` returns for a problem its check refuses, and no
    DAQP exit flag (DAQP's are -6..2)."""
    import re
    from importlib import resources

    source = resources.files("amlip_qp.codegen").joinpath("daqp_step.c").read_text()
    found = re.search(r"#define AMLIP_DAQP_INVALID \((-?\d+)\)", source)
    assert found is not None and int(found.group(1)) == daqp_step.INVALID_PROBLEM
    assert daqp_step.INVALID_PROBLEM < -6
