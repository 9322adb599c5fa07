"""Robots are data: no module outside the profiles names a robot in code (docs/ARCHITECTURE.md)."""

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[1] / "amlip_qp"


def _robot_literals(path: Path, names: tuple[str, ...]) -> list[str]:
    """String constants of ``path`` (docstrings aside) that are a robot's name or start with it and a dash."""
    tree = ast.parse(path.read_text())
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return [
        f"{path.relative_to(PKG.parent)}:{node.lineno}: {node.value!r}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
        for name in names
        if node.value == name or node.value.startswith(f"{name}-")
    ]


def test_no_module_outside_the_profiles_names_a_robot():
    """Robots are data: only ``amlip_qp.profiles`` (its defaults) names one in code."""
    names = tuple(p.stem for p in (PKG / "models").glob("*.toml"))
    assert set(names) >= {"cassie", "rabbit", "h1", "g1"}
    found = [
        hit
        for path in sorted(PKG.rglob("*.py"))
        if "profiles" not in path.relative_to(PKG).parts[:1] and "models" not in path.relative_to(PKG).parts[:1]
        for hit in _robot_literals(path, names)
    ]
    assert found == []


def test_the_robot_name_check_finds_a_literal():
    probe = PKG / "_probe_robot_literal.py"
    try:
        probe.write_text('"""A docstring naming cassie is fine."""\nROBOT = "cassie"\nSCENARIO = "h1-1mps"\n')
        hits = _robot_literals(probe, ("cassie", "h1"))
    finally:
        probe.unlink()
    assert [h.split(": ", 1)[1] for h in hits] == ["'cassie'", "'h1-1mps'"]
