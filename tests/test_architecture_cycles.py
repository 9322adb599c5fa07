"""No import cycles among amlip_qp's modules: data flows one way, even through lazy imports and
imports for typing only (docs/ARCHITECTURE.md, "Layers")."""

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[1] / "amlip_qp"


def _module_name(path: Path, pkg: Path) -> str:
    parts = path.relative_to(pkg.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _module_graph(pkg: Path = PKG) -> dict[str, set[str]]:
    """Module -> the amlip_qp modules it imports: top level, inside functions and under ``TYPE_CHECKING``.

    ``from package import name`` counts as importing the module ``package.name`` when there is one,
    else ``package`` itself.
    """
    modules = {_module_name(p, pkg): p for p in pkg.rglob("*.py")}
    graph = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        edges = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                edges.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                parts = package.split(".")
                base = (
                    ".".join(parts[: len(parts) - node.level + 1] + ([node.module] if node.module else []))
                    if node.level
                    else node.module or ""
                )
                edges.update(f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names)
        graph[name] = {e for e in edges if e in modules and e != name}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import cycles of ``graph``: its strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_module_import_cycle():
    """Data flow one way: no two modules import each other, even lazily or for typing only."""
    assert _cycles(_module_graph()) == []


def test_the_cycle_check_finds_a_cycle(tmp_path):
    pkg = tmp_path / "amlip_qp"
    (pkg / "sim").mkdir(parents=True)
    (pkg / "sim" / "__init__.py").write_text("")
    (pkg / "sim" / "a.py").write_text("from amlip_qp.sim import b\n")
    (pkg / "sim" / "b.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from amlip_qp.sim.c import C\n"
    )
    (pkg / "sim" / "c.py").write_text("def f():\n    from .a import g\n")
    (pkg / "sim" / "d.py").write_text("from amlip_qp.sim import a\n")
    assert _cycles(_module_graph(pkg)) == [["amlip_qp.sim.a", "amlip_qp.sim.b", "amlip_qp.sim.c"]]
