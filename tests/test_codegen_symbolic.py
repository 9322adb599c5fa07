"""The SX kernels are dense, correctly sized and equal the numpy reference."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from amlip_qp.alip import kernels
from amlip_qp.codegen import symbolic


@pytest.mark.parametrize(
    "name, n_in, n_out", [("alip_plan", 16, 8), ("swing_reference", 15, 30), ("alip_mpc_qp", 62, 568)]
)
def test_function_signature_is_dense(name, n_in, n_out):
    f = symbolic.function(name)
    assert isinstance(f, ca.Function)
    assert f.name() == name
    assert (f.n_in(), f.n_out()) == (1, 1)
    assert f.name_in() == ["u"] and f.name_out() == ["y"]
    assert f.sparsity_in(0).is_dense() and f.size_in(0) == (n_in, 1)
    assert f.sparsity_out(0).is_dense() and f.size_out(0) == (n_out, 1)
    assert f.nnz_out(0) == n_out


def test_functions_in_library_order_and_cached():
    fs = symbolic.functions()
    assert list(fs) == ["alip_plan", "swing_reference", "alip_mpc_qp"]
    assert fs["alip_plan"] is symbolic.function("alip_plan")


def test_unknown_kernel_is_a_key_error():
    with pytest.raises(KeyError, match="alip_plan"):
        symbolic.spec("nope")


def test_sx_functions_match_numpy_reference():
    rng = np.random.default_rng(7)
    for _ in range(50):
        u = np.array([rng.uniform(-0.3, 0.3), rng.uniform(-0.2, 0.2), rng.uniform(-20, 20), rng.uniform(-30, 90),
                      rng.uniform(0, 0.4), rng.uniform(-0.3, 0.3), rng.uniform(-1, 3), rng.uniform(-0.5, 0.5),
                      rng.uniform(-np.pi, np.pi), rng.choice([-1.0, 1.0]), 33.0, rng.uniform(0.6, 1.0),
                      rng.uniform(0.25, 0.45), rng.uniform(0, 0.35), 9.81, rng.uniform(-0.2, 0.2)])  # fmt: skip
        y = symbolic.function("alip_plan")(u).full().ravel()
        np.testing.assert_allclose(y, kernels.alip_plan(u), rtol=1e-12, atol=1e-12)
        v = np.concatenate([[rng.uniform(0, 1), rng.uniform(0.25, 0.5), rng.uniform(0.6, 1.0), rng.uniform(0.05, 0.2)],
                            rng.uniform(-0.5, 0.5, 7),
                            rng.uniform(-0.15, 0.15, 2), rng.uniform(-0.5, 0.5, 2)])  # fmt: skip
        h = symbolic.function("swing_reference")(v).full().ravel()
        np.testing.assert_allclose(h, kernels.swing_reference(v), rtol=1e-12, atol=1e-12)
