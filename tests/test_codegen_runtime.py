"""Tests of amlip_qp.codegen.runtime: the library source, compiling into the cache, loading, errors."""

from __future__ import annotations

import os
import subprocess
import sys
import threading

import pytest

from amlip_qp.codegen import generate, runtime, symbolic
from amlip_qp.exceptions import CodegenError, CompilerUnavailableError
from amlip_qp.paths import PACKAGE_DIR
from codegen_cases import needs_cc


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
def test_changed_source_builds_a_new_library(shared_cache_dir):
    src = generate.generate_files()[generate.SOURCE_FILE]
    compiler = runtime.find_compiler()
    lib = runtime.build_library(src, compiler, shared_cache_dir)
    assert lib == runtime.compile_and_load(src, symbolic.KERNEL_NAMES, cache_dir=shared_cache_dir)[0]
    assert runtime.build_library(src, compiler, shared_cache_dir) == lib  # cached
    other = runtime.build_library(src + b"/* changed */\n", compiler, shared_cache_dir)
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
    assert lib.is_file() and functions["swing_reference"].nnz_out(0) == 30


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
