"""DAQP through its C API: the same solutions, bit for bit, as through daqp.Model."""

import numpy as np
import pytest

from amlip_qp.qp import daqp_model as dm
from amlip_qp.qp.small_qp import SmallQPSolver

SENSE_SOFT, SENSE_EQUALITY = 8, 5


def _problem_sequence(n, n_rows, n_eq, count, seed):
    """Problems of one shape whose data drift from call to call (the hot start's use), with a soft
    row, an unbounded side, equalities and now and then a row that contradicts its bounds."""
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((n, n))
    H0, A0 = M @ M.T + n * np.eye(n), rng.standard_normal((n_rows + n_eq, n))
    for k in range(count):
        H = H0 + 0.1 * np.diag(rng.random(n))
        g = 3.0 * rng.standard_normal(n)
        A = A0 + 0.01 * rng.standard_normal(A0.shape)
        lower = np.concatenate([-0.5 * np.ones(n), -rng.random(n_rows) - 0.1, np.zeros(n_eq)])
        upper = np.concatenate([0.5 * np.ones(n), rng.random(n_rows) + 0.1, np.zeros(n_eq)])
        lower[n + 2] = -1e30
        if k % 50 == 7:
            upper[n + 4] = lower[n + 4] - 1.0
        yield H, g, A, upper, lower


def test_the_c_api_loads_for_the_verified_release():
    import importlib.metadata

    version = importlib.metadata.version("daqp")
    status = dm.c_api_status()
    if version in dm.VERIFIED_VERSIONS:
        assert status is None
        assert isinstance(dm.make_model(2, 2, 2), dm.CModel)
    else:
        assert version in status
        assert isinstance(dm.make_model(2, 2, 2), dm.PyModel)


@pytest.mark.parametrize("n, n_rows, n_eq", [(13, 24, 0), (8, 12, 3)])
def test_c_api_solutions_are_daqp_models_bit_for_bit(n, n_rows, n_eq):
    m = n + n_rows + n_eq
    models = [dm.make_model(n, m, n), dm.make_model(n, m, n, use_c_api=False)]
    buffers = [[np.zeros((n, n)), np.zeros(n), np.zeros((n_rows + n_eq, n)), np.zeros(m), np.zeros(m)] for _ in models]
    sense = np.zeros(m, dtype=np.intc)
    sense[n + 1] = SENSE_SOFT
    sense[n + n_rows :] = SENSE_EQUALITY
    flags = set()
    for k, data in enumerate(_problem_sequence(n, n_rows, n_eq, 300, seed=n)):
        results = []
        for model, bufs in zip(models, buffers, strict=True):
            for buf, value in zip(bufs, data, strict=True):
                buf[...] = value
            if k == 0:
                assert model.setup(*bufs, sense.copy()) >= 0
                model.set_settings(200, 1e-6)
            else:
                model.update(*bufs)
            results.append((model.solve(), model.x.tobytes()))
        assert results[0] == results[1], f"problem {k}"
        flags.add(results[0][0])
    assert {1, 2} <= flags  # solved, and solved with the soft row given way


def test_arrays_daqp_cannot_read_in_place_are_refused():
    model = dm.make_model(2, 3, 2)
    if isinstance(model, dm.PyModel):
        pytest.fail(f"the C API did not load: {dm.c_api_status()}")
    H, f, A = np.eye(2), np.zeros(2), np.ones((1, 2))
    with pytest.raises(ValueError, match="C-contiguous float64"):
        model.setup(np.ones((2, 4))[:, ::2], f, A, np.ones(3), -np.ones(3), np.zeros(3, dtype=np.intc))
    with pytest.raises(ValueError, match="int32"):
        model.setup(H, f, A, np.ones(3), -np.ones(3), np.zeros(3, dtype=np.int64))


def test_an_unverified_release_falls_back_with_one_warning(monkeypatch):
    monkeypatch.setattr(dm, "VERIFIED_VERSIONS", ("0.0.0",))
    try:
        with pytest.warns(dm.DAQPModelFallbackWarning, match="daqp.Model"):
            reason = dm.c_api_status(refresh=True)
        assert "0.0.0" in reason
        assert isinstance(dm.make_model(2, 2, 2), dm.PyModel)
    finally:
        monkeypatch.undo()
        dm.c_api_status(refresh=True)


def test_small_qp_solver_paths_agree_bit_for_bit():
    n, n_rows = 6, 8
    solvers = [SmallQPSolver(n, n_rows, soft_rows=(1,)), SmallQPSolver(n, n_rows, soft_rows=(1,), use_c_api=False)]
    stacked = SmallQPSolver(n, n_rows, soft_rows=(1,))
    for H, g, A, upper, lower in _problem_sequence(n, n_rows, 0, 200, seed=3):
        outcomes = []
        for solve in (*solvers, None):
            try:
                if solve is None:
                    x = stacked.solve_stacked(np.concatenate([H.ravel(), g, A.ravel(), lower, upper]))
                else:
                    x = solve(H, g, A, lower, upper)
                outcomes.append(x.tobytes())
            except Exception as exc:  # the failures must agree too
                outcomes.append(type(exc).__name__)
        assert outcomes[0] == outcomes[1] == outcomes[2]
    assert solvers[0].solves == 200 and 0 < solvers[0].failures < 200


def test_a_c_model_refuses_to_be_pickled():
    """Its structures point into this process's memory: a copy elsewhere would solve garbage."""
    import pickle

    model = dm.make_model(2, 2, 2)
    if isinstance(model, dm.PyModel):
        pytest.fail(f"the C API did not load: {dm.c_api_status()}")
    with pytest.raises(TypeError, match="cannot be pickled"):
        pickle.dumps(model)


@pytest.mark.parametrize("use_c_api", [True, False])
def test_a_failed_set_up_leaves_a_model_that_takes_settings_and_nothing_else(use_c_api):
    """DAQP frees its settings when the set-up fails (here: H not positive definite); setting them
    then is a no-op on both models, as daqp.Model's."""
    model = dm.make_model(2, 2, 2, use_c_api=use_c_api)
    H, f, A = -np.eye(2), np.zeros(2), np.zeros((0, 2))
    assert model.setup(H, f, A, np.ones(2), -np.ones(2), np.zeros(2, dtype=np.intc)) < 0
    model.set_settings(100, 1e-6)
    if use_c_api:
        with pytest.raises(RuntimeError, match="setup"):
            model.c_handles()
