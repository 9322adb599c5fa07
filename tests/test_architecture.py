"""The layer contract of docs/ARCHITECTURE.md, checked on the imports of every module."""

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "amlip_qp"

#: package -> top-level modules it must never import (directly or lazily).
FORBIDDEN = {
    "alip": ("mujoco", "pinocchio", "proxsuite", "qpsolvers", "amlip_qp.robots", "amlip_qp.control", "amlip_qp.sim"),
    "codegen": ("mujoco", "pinocchio", "amlip_qp.robots", "amlip_qp.control", "amlip_qp.sim"),
    "robots": ("casadi", "proxsuite", "amlip_qp.control", "amlip_qp.sim", "amlip_qp.codegen"),
    "control": ("mujoco", "amlip_qp.sim"),
}


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_layers_import_only_what_the_contract_allows(package):
    files = sorted((PKG / package).glob("*.py"))
    assert files, f"no modules found in amlip_qp/{package}"
    offenders = []
    for f in files:
        for name in _imports(f):
            for bad in FORBIDDEN[package]:
                if name == bad or name.startswith(bad + "."):
                    offenders.append(f"{f.name} imports {name}")
    assert not offenders, f"amlip_qp/{package} breaks the layer contract: {offenders}"


def test_the_check_catches_a_violation(tmp_path):
    bad = tmp_path / "m.py"
    bad.write_text("def f():\n    import mujoco\n    from amlip_qp.sim.harness import Simulation\n")
    assert {"mujoco", "amlip_qp.sim.harness"} <= _imports(bad)
