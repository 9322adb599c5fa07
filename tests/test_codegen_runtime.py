"""The compiled kernels equal the numpy reference; caching, fallback and errors."""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
import threading
import warnings

import numpy as np
import pytest

from amlip_qp.alip import kernels
from amlip_qp.codegen import generate, runtime, symbolic
from amlip_qp.codegen.runtime import CodegenFallbackWarning, CodegenStaleWarning, FastFunction, Kernels
from amlip_qp.exceptions import CodegenError, CompilerUnavailableError, InputError
from amlip_qp.paths import PACKAGE_DIR


def needs_cc(test):
    """The test compiles generated C. The README requires a C compiler, so
    without one the test fails, naming the fix (it is never skipped)."""

    @functools.wraps(test)
    def run(*args, **kwargs):
        if shutil.which("cc") is None and shutil.which("gcc") is None:
            pytest.fail("no C compiler on the PATH: install one (e.g. apt-get install gcc), as the README requires")
        return test(*args, **kwargs)

    return run


N = 1500  # random samples per robot and kernel

# Physical ranges: (m kg, H m, T s, W m, z_cl m, lateral motion?)
ROBOTS = {
    "cassie": dict(m=(31.0, 35.0), H=(0.6, 1.0), T=(0.25, 0.45), W=(0.0, 0.35), z_cl=(0.05, 0.2), lateral=True),
    "rabbit": dict(m=(32.0, 32.0), H=(0.6, 0.8), T=(0.3, 0.5), W=(0.0, 0.0), z_cl=(0.05, 0.2), lateral=False),
}


def sample_alip_plan(rng, robot, n):
    r = ROBOTS[robot]
    lat = 1.0 if r["lateral"] else 0.0
    m, H, T = rng.uniform(*r["m"], n), rng.uniform(*r["H"], n), rng.uniform(*r["T"], n)
    vx, vy = rng.uniform(-1, 3, n), lat * rng.uniform(-1, 1, n)
    t_rem = rng.uniform(0, 1, n) * T
    t_rem[:20], t_rem[20:40] = 0.0, T[20:40]  # both ends of the step
    u = np.column_stack([
        rng.uniform(-0.3, 0.3, n), lat * rng.uniform(-0.2, 0.2, n),  # p_st
        -m * H * lat * rng.uniform(-1, 1, n), m * H * rng.uniform(-1, 3, n),  # L_x, L_y
        t_rem, rng.uniform(-0.3, 0.3, n), vx, vy,
        rng.uniform(-np.pi, np.pi, n), rng.choice([-1.0, 1.0], n),
        m, H, T, rng.uniform(*r["W"], n), np.full(n, 9.81),
    ])  # fmt: skip
    return u


def sample_swing_reference(rng, robot, n):
    r = ROBOTS[robot]
    lat = 1.0 if r["lateral"] else 0.0
    s = rng.uniform(0, 1, n)
    s[:20], s[20:40] = 0.0, 1.0
    return np.column_stack([
        s, rng.uniform(*r["T"], n), rng.uniform(*r["H"], n), rng.uniform(*r["z_cl"], n),
        lat * rng.uniform(-0.5, 0.5, n), lat * rng.uniform(-0.5, 0.5, n),
        rng.uniform(-0.4, 0.4, n), lat * rng.uniform(-0.3, 0.3, n),
        rng.uniform(-0.4, 0.4, n), lat * rng.uniform(-0.3, 0.3, n), lat * rng.uniform(-0.6, 0.6, n),
    ])  # fmt: skip


SAMPLERS = {
    "alip_plan": (sample_alip_plan, kernels.alip_plan),
    "swing_reference": (sample_swing_reference, kernels.swing_reference),
}
SEEDS = {("cassie", "alip_plan"): 11, ("cassie", "swing_reference"): 12,
         ("rabbit", "alip_plan"): 21, ("rabbit", "swing_reference"): 22}  # fmt: skip


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("amlip_cache")


@pytest.fixture(scope="module")
def fast(cache_dir):
    return Kernels(cache_dir=cache_dir)


def assert_matches_reference(fn: FastFunction, robot: str, seed: int):
    sample, reference = SAMPLERS[fn.name]
    rng = np.random.default_rng(seed)
    for u in sample(rng, robot, N):
        y = fn(u).copy()
        ref = reference(u)
        err = np.abs(y - ref) / np.maximum(1.0, np.abs(ref))
        assert err.max() <= 1e-12, (fn.name, robot, u, y, ref)


@needs_cc
@pytest.mark.parametrize("robot", sorted(ROBOTS))
@pytest.mark.parametrize("name", ["alip_plan", "swing_reference"])
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
    u = [0.0, 0.0, 0.0, 10.0, 0.1, 0.0, 1.0, 0.0, 0.0, 1.0, 33.0, 0.9, 0.35, 0.2, 9.81]
    np.testing.assert_allclose(fast.alip_plan(u), kernels.alip_plan(np.array(u)), rtol=1e-12, atol=1e-12)
    v = np.array([0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(fast.swing_reference(v), kernels.swing_reference(v.astype(float)), atol=1e-12)


@needs_cc
@pytest.mark.parametrize(
    "bad", [np.zeros(14), np.zeros(16), np.zeros((15, 1)), np.zeros((1, 15)), 3.0, "abc", [[1, 2]]]
)
def test_wrong_shape_raises_input_error(fast, bad):
    with pytest.raises(InputError, match=r"alip_plan|15"):
        fast.alip_plan(bad)


@needs_cc
def test_wrong_shape_message_says_what_to_pass(fast):
    with pytest.raises(InputError, match=r"expects a 1-D array of 11 inputs .*shape \(3,\).*shape \(11,\)"):
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


def test_cache_root_honours_env(tmp_path, monkeypatch):
    monkeypatch.setenv(runtime.CACHE_ENV, str(tmp_path / "c"))
    assert runtime.cache_root() == tmp_path / "c"
    monkeypatch.delenv(runtime.CACHE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert runtime.cache_root() == tmp_path / "xdg" / "amlip_qp"


def test_cache_key_changes_with_source_compiler_and_flags():
    src = generate.generate_files()[generate.SOURCE_FILE]
    key = runtime.cache_key(src, ["cc"])
    assert len(key) == 64 and key == runtime.cache_key(src, ["cc"])
    assert runtime.cache_key(src + b"/* changed */\n", ["cc"]) != key
    assert runtime.cache_key(src, ["gcc"]) != key
    assert runtime.cache_key(src, ["cc"], ("-O3",)) != key


@needs_cc
def test_changed_source_builds_a_new_library(cache_dir, fast):
    src = generate.generate_files()[generate.SOURCE_FILE]
    compiler = runtime.find_compiler()
    lib = runtime.build_library(src, compiler, cache_dir)
    assert lib == fast.library_path
    assert runtime.build_library(src, compiler, cache_dir) == lib  # cached
    other = runtime.build_library(src + b"/* changed */\n", compiler, cache_dir)
    assert other != lib and other.parent.name == runtime.cache_key(src + b"/* changed */\n", compiler)
    assert other.is_file() and (other.parent / generate.SOURCE_FILE).read_bytes().endswith(b"/* changed */\n")


@needs_cc
def test_parallel_builds_do_not_collide(tmp_path):
    src = generate.generate_files()[generate.SOURCE_FILE]
    compiler = runtime.find_compiler()
    results, errors = [], []

    def build():
        try:
            results.append(runtime.build_library(src, compiler, tmp_path))
        except Exception as exc:
            errors.append(exc)

    threads = [threading.Thread(target=build) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and len(set(results)) == 1
    folder = results[0].parent
    assert sorted(p.name for p in folder.iterdir()) == [generate.SOURCE_FILE, runtime.LIBRARY_FILE]
    lib, functions = runtime.compile_and_load(src, ["alip_plan"], cache_dir=tmp_path)
    assert lib == results[0] and functions["alip_plan"].nnz_out(0) == 8


@needs_cc
def test_compile_error_raises_codegen_error_with_compiler_message(tmp_path):
    with pytest.raises(CodegenError, match=r"(?s)compiling .* failed .*error"):
        runtime.build_library(b"int broken(void) { return }\n", runtime.find_compiler(), tmp_path)
    leftovers = [p.name for d in tmp_path.iterdir() for p in d.iterdir()]
    assert leftovers == [generate.SOURCE_FILE]


@needs_cc
def test_missing_committed_sources_generate_into_the_cache(tmp_path, cache_dir, fast):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        k = Kernels(cache_dir=cache_dir, committed_dir=tmp_path / "absent")
    assert k.backend == "c" and k.library_path == fast.library_path


@needs_cc
def test_stale_committed_sources_warn_and_use_fresh(tmp_path, cache_dir, fast):
    generate.write_files(tmp_path)
    src = tmp_path / generate.SOURCE_FILE
    src.write_bytes(src.read_bytes() + b"/* stale */\n")
    with pytest.warns(CodegenStaleWarning, match="amlip_kernels.c"):
        k = Kernels(cache_dir=cache_dir, committed_dir=tmp_path)
    assert k.library_path == fast.library_path


@needs_cc
def test_non_numeric_object_array_raises_input_error(fast):
    with pytest.raises(InputError, match="real numbers"):
        fast.alip_plan(np.array(["x"] * 15, dtype=object))


def test_cache_key_changes_with_the_cpu_architecture(monkeypatch):
    src = b"int f(void) { return 1; }"
    key = runtime.cache_key(src, ["cc"])
    monkeypatch.setattr(runtime.platform, "machine", lambda: "some-other-arch")
    assert runtime.cache_key(src, ["cc"]) != key


LOAD_KERNELS = "from amlip_qp.codegen import load_kernels; print(load_kernels().backend)"


@needs_cc
def test_first_run_says_once_on_stderr_that_it_compiles(tmp_path):
    env = dict(os.environ, AMLIP_QP_CACHE_DIR=str(tmp_path / "cache"))
    env["PYTHONPATH"] = os.pathsep.join([str(PACKAGE_DIR.parent), os.environ.get("PYTHONPATH", "")])
    env.pop(runtime.COMPILER_ENV, None)
    runs = [subprocess.run([sys.executable, "-c", LOAD_KERNELS], capture_output=True, text=True, env=env, timeout=300)
            for _ in range(2)]  # fmt: skip
    cold, warm = runs
    assert cold.returncode == warm.returncode == 0 and cold.stdout == warm.stdout == "c\n", cold.stderr
    (line,) = cold.stderr.splitlines()
    assert line.startswith("amlip_qp: compiling generated C once into ")
    assert line.endswith(f"{os.sep}cache (up to about {runtime.COLD_COMPILE_S} s; later runs reuse it)")
    assert warm.stderr == ""


@needs_cc
def test_compile_and_load_announces_once_per_process_and_cache(tmp_path, capsys):
    src = generate.generate_files()[generate.SOURCE_FILE]
    runtime.compile_and_load(src, symbolic.KERNEL_NAMES, cache_dir=tmp_path)
    assert capsys.readouterr().err.count("compiling generated C once") == 1
    # A second library into the same cache (as a walk compiles three) and a warm load stay silent.
    lib, functions = runtime.compile_and_load(src + b"/* another */\n", ["swing_reference"], cache_dir=tmp_path)
    runtime.compile_and_load(src, symbolic.KERNEL_NAMES, cache_dir=tmp_path)
    assert capsys.readouterr().err == ""
    assert lib.is_file() and functions["swing_reference"].nnz_out(0) == 27


def test_compile_and_load_without_compiler_is_a_typed_error(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(runtime.COMPILER_ENV, "none")
    with pytest.raises(CompilerUnavailableError, match="AMLIP_QP_CC=none"):
        runtime.compile_and_load(b"int f(void) { return 1; }\n", ["f"], cache_dir=tmp_path)
    assert capsys.readouterr().err == "" and not any(tmp_path.iterdir())


@needs_cc
def test_compile_and_load_names_a_missing_function(tmp_path):
    source = generate.generate_files()[generate.SOURCE_FILE]
    with pytest.raises(
        CodegenError, match=r"cannot load no_such_kernel from .*no_such_kernel.*delete .* to rebuild"
    ) as info:
        runtime.compile_and_load(source, ["no_such_kernel"], cache_dir=tmp_path)
    assert "\n" not in str(info.value)
