"""A plain clone passes its tests: no test reads a file outside the repository.

Each ``tests/*.py`` file is parsed and every path expression built from
``__file__`` (or from :data:`amlip_qp.paths.PACKAGE_DIR`) is followed through
``.parent``, ``.parents[N]`` and the module-level names it is bound to; a path
that climbs above the repository root (``tests/x.py``'s ``parents[2]``, the
root's ``.parent``, ``/ ".."``) is an escape, and so is ``open("../x")`` or
``Path("../x")``, relative to the working folder. The parameter sheet of the Cassie models is vendored for that reason
(``models/reference/cassie_parameters.json``).
"""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent
REPO = TESTS.parent
#: Levels of a folder above the repository root: ``tests/x.py`` is -2, ``tests/`` -1, the root 0.
START_LEVELS = {"__file__": -2, "PACKAGE_DIR": -1}


def _level(node: ast.expr, names: dict[str, int]) -> int | None:
    """The level above the repository root of a path expression, or ``None`` if it is not traced to the repository."""
    if isinstance(node, ast.Name):
        return START_LEVELS.get(node.id, names.get(node.id))
    if isinstance(node, ast.Call):
        func = node.func
        if isinstance(func, ast.Attribute) and func.attr in ("resolve", "absolute", "expanduser"):
            return _level(func.value, names)
        if isinstance(func, ast.Name | ast.Attribute) and node.args:  # Path(__file__), pathlib.Path(...)
            name = func.id if isinstance(func, ast.Name) else func.attr
            if name in ("Path", "PurePath"):
                return _level(node.args[0], names)
        return None
    if isinstance(node, ast.Attribute) and node.attr == "parent":
        inner = _level(node.value, names)
        return None if inner is None else inner + 1
    if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Attribute) and node.value.attr == "parents":
        inner = _level(node.value.value, names)
        index = node.slice
        if inner is None or not (isinstance(index, ast.Constant) and isinstance(index.value, int)):
            return None
        return inner + index.value + 1
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
        inner = _level(node.left, names)
        if inner is None or inner > 0:  # once outside, a path stays outside
            return inner
        parts = node.right.value.replace("\\", "/").split("/") if _is_text(node.right) else ["x"]
        for part in parts:
            inner += 1 if part == ".." else 0 if part in ("", ".") else -1
            if inner > 0:
                return inner
        return inner
    return None


def _is_text(node: ast.expr) -> bool:
    return isinstance(node, ast.Constant) and isinstance(node.value, str)


def _opens_relative_parent(node: ast.expr) -> bool:
    """``open("../x")``, ``Path("../x")``: a path relative to the working folder that starts above it."""
    if not isinstance(node, ast.Call) or not node.args or not _is_text(node.args[0]):
        return False
    func = node.func
    name = func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else ""
    text = node.args[0].value.replace("\\", "/")  # type: ignore[attr-defined]
    return name in ("open", "Path", "PurePath") and (text == ".." or text.startswith("../"))


def path_escapes(source: str) -> list[str]:
    """The expressions of ``source`` (a test file's text) that point outside the repository."""
    tree = ast.parse(source)
    names: dict[str, int] = {}
    for stmt in tree.body:  # module-level names bound to a traced path (REPO = Path(__file__).parents[1])
        if isinstance(stmt, ast.Assign | ast.AnnAssign) and stmt.value is not None:
            level = _level(stmt.value, names)
            targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]
            for target in targets:
                if isinstance(target, ast.Name) and level is not None:
                    names[target.id] = level
    out: dict[int, str] = {}  # line -> its outermost escaping expression (ast.walk visits outer nodes first)
    for node in ast.walk(tree):
        if not isinstance(node, ast.expr) or node.lineno in out:
            continue
        if _opens_relative_parent(node) or (not isinstance(node, ast.Name) and (_level(node, names) or 0) > 0):
            out[node.lineno] = ast.unparse(node)
    return [f"line {line}: {text}" for line, text in sorted(out.items())]


def test_no_test_reads_outside_the_repository():
    offenders = [f"{f.name} {hit}" for f in sorted(TESTS.glob("*.py")) for hit in path_escapes(f.read_text())]
    assert offenders == []


def test_the_check_catches_the_escapes_it_names():
    old_sheet_paths = (
        'SHEET_PATH = Path(__file__).resolve().parents[2] / "shared" / "reference" / "cassie_parameters.json"\n'
        'REPO = Path(__file__).resolve().parents[1]\nSHEET = REPO.parent / "shared" / "sheet.json"\n'
        'HERE = Path(__file__).parent\nUP = HERE / ".." / ".." / "shared"\n'
        'OUT = PACKAGE_DIR.parent.parent / "x"\nTEXT = open("../shared/notes.md").read()\n'
        'NOTES = REPO / "docs/../../shared/x.md"\n'
    )
    assert [hit.split(":")[0] for hit in path_escapes(old_sheet_paths)] == [
        "line 1",
        "line 3",
        "line 5",
        "line 6",
        "line 7",
        "line 8",
    ]
    inside = (
        'ROOT = Path(__file__).resolve().parents[1]\nA = ROOT / "models" / "reference" / "x.json"\n'
        'B = Path(__file__).parent / "data.txt"\nC = PACKAGE_DIR.parent / "pyproject.toml"\n'
        'D = tmp.parent / "y"\nE = "[notes](../shared/ALIP_NOTES.md)"\n'
    )
    assert path_escapes(inside) == []


def test_the_parameter_sheet_is_in_the_repository():
    sheet = REPO / "models" / "reference" / "cassie_parameters.json"
    assert sheet.is_file() and "Agility Robotics" in sheet.read_text()
    notice = (REPO / "NOTICE").read_text()
    assert "models/reference/cassie_parameters.json" in notice and "Copyright (c) 2022 Agility Robotics" in notice
