"""Tests of amlip_qp.codegen.kernels: the planner kernels compiled and called through FastFunction, and the fallback."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from amlip_qp.alip import kernels
from amlip_qp.codegen import generate, runtime
from amlip_qp.codegen.kernels import Kernels
from amlip_qp.codegen.runtime import CodegenFallbackWarning, CodegenStaleWarning
from amlip_qp.exceptions import InputError
from codegen_cases import ROBOTS, SEEDS, assert_matches_reference, needs_cc, sample_alip_plan, sample_swing_reference


@pytest.fixture(scope="module")
def fast(shared_cache_dir):
    return Kernels(cache_dir=shared_cache_dir)


@needs_cc
@pytest.mark.parametrize("robot", sorted(ROBOTS))
@pytest.mark.parametrize("name", ["alip_plan", "swing_reference", "alip_mpc_qp"])
def test_compiled_c_equals_numpy_reference(fast, robot, name):
    assert fast.backend == "c" and fast[name].backend == "c"
    assert fast.library_path is not None and fast.library_path.is_file()
    assert_matches_reference(fast[name], robot, seed=SEEDS[robot, name])


@needs_cc
def test_output_is_a_shared_read_only_array(fast):
    u = sample_alip_plan(np.random.default_rng(1), "cassie", 2)
    y0 = fast.alip_plan(u[0])
    first = y0.copy()
    y1 = fast.alip_plan(u[1])
    assert y1 is y0 and y0.shape == (8,) and not y0.flags.writeable
    assert not np.array_equal(first, y1)
    with pytest.raises(ValueError):
        y0[0] = 1.0


@needs_cc
def test_accepts_sequences_and_integer_arrays(fast):
    u = [0.0, 0.0, 0.0, 10.0, 0.1, 0.0, 1.0, 0.0, 0.0, 1.0, 33.0, 0.9, 0.35, 0.2, 9.81, 0.0]
    np.testing.assert_allclose(fast.alip_plan(u), kernels.alip_plan(np.array(u)), rtol=1e-12, atol=1e-12)
    v = np.array([0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(fast.swing_reference(v), kernels.swing_reference(v.astype(float)), atol=1e-12)


@needs_cc
@pytest.mark.parametrize(
    "bad", [np.zeros(15), np.zeros(17), np.zeros((16, 1)), np.zeros((1, 16)), 3.0, "abc", [[1, 2]]]
)
def test_wrong_shape_raises_input_error(fast, bad):
    with pytest.raises(InputError, match=r"alip_plan|16"):
        fast.alip_plan(bad)


@needs_cc
def test_wrong_shape_message_says_what_to_pass(fast):
    with pytest.raises(InputError, match=r"expects a 1-D array of 15 inputs .*shape \(3,\).*shape \(15,\)"):
        fast.swing_reference(np.zeros(3))


def test_fallback_without_compiler_warns_once_and_is_right(tmp_path, monkeypatch):
    monkeypatch.setenv(runtime.COMPILER_ENV, "none")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        k = Kernels(cache_dir=tmp_path / "cache", committed_dir=tmp_path)
        assert_matches_reference(k.alip_plan, "cassie", seed=3)
        assert_matches_reference(k.swing_reference, "rabbit", seed=4)
    assert len(caught) == 1
    assert issubclass(caught[0].category, CodegenFallbackWarning)
    assert "no C compiler" in str(caught[0].message) and "AMLIP_QP_CC=none" in str(caught[0].message)
    assert k.backend == "casadi" and k.alip_plan.backend == "casadi" and k.library_path is None
    assert not (tmp_path / "cache").exists()


def test_fallback_when_compiler_lookup_finds_nothing(tmp_path, monkeypatch):
    def no_compiler():
        raise runtime._NoCompiler("neither 'cc' nor 'gcc' is on the PATH")

    monkeypatch.setattr(runtime, "find_compiler", no_compiler)
    with pytest.warns(CodegenFallbackWarning, match="neither 'cc' nor 'gcc'") as caught:
        k = Kernels(cache_dir=tmp_path / "cache", committed_dir=tmp_path)
    assert len(caught) == 1
    u = sample_swing_reference(np.random.default_rng(5), "cassie", 1)[0]
    np.testing.assert_allclose(k.swing_reference(u), kernels.swing_reference(u), rtol=1e-12, atol=1e-12)


def test_named_compiler_missing_falls_back(tmp_path, monkeypatch):
    monkeypatch.setenv(runtime.COMPILER_ENV, "/nonexistent/amlip-cc")
    with pytest.warns(CodegenFallbackWarning, match="amlip-cc"):
        assert Kernels(cache_dir=tmp_path, committed_dir=tmp_path).backend == "casadi"


def test_two_fallback_instances_have_independent_buffers(tmp_path, monkeypatch):
    monkeypatch.setenv(runtime.COMPILER_ENV, "none")
    with pytest.warns(CodegenFallbackWarning):
        a, b = Kernels(committed_dir=tmp_path), Kernels(committed_dir=tmp_path)
    u = sample_alip_plan(np.random.default_rng(6), "cassie", 2)
    ya = a.alip_plan(u[0])
    b.alip_plan(u[1])
    np.testing.assert_allclose(ya, kernels.alip_plan(u[0]), rtol=1e-12, atol=1e-12)


@needs_cc
def test_missing_committed_sources_generate_into_the_cache(tmp_path, shared_cache_dir, fast):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        k = Kernels(cache_dir=shared_cache_dir, committed_dir=tmp_path / "absent")
    assert k.backend == "c" and k.library_path == fast.library_path


@needs_cc
def test_stale_committed_sources_warn_and_use_fresh(tmp_path, shared_cache_dir, fast):
    generate.write_files(tmp_path)
    src = tmp_path / generate.SOURCE_FILE
    src.write_bytes(src.read_bytes() + b"/* stale */\n")
    with pytest.warns(CodegenStaleWarning, match="amlip_kernels.c"):
        k = Kernels(cache_dir=shared_cache_dir, committed_dir=tmp_path)
    assert k.library_path == fast.library_path


@needs_cc
def test_non_numeric_object_array_raises_input_error(fast):
    with pytest.raises(InputError, match="real numbers"):
        fast.alip_plan(np.array(["x"] * 15, dtype=object))
