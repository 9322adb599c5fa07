"""The documentation names code, tests and files that exist.

- ``docs/EQUATIONS.md`` names each function as ``amlip_qp.module:attr[.attr]``
  (imported and resolved) and each test as ``tests/<file>.py::<test>`` (the
  file defines that function).
- The guides (:data:`GUIDES`) name modules in backticks as ``amlip_qp/...py``
  (or a folder, a glob, ``{a,b}`` alternatives) or ``amlip_qp.x.y`` (a module,
  or an attribute of one), subpackage paths relative to ``amlip_qp/``
  (``control/wbc/``), and files of the repository (``tests/...``,
  ``docs/...``, ``examples/...``, ``models/...``); each must exist.
- Their relative Markdown links resolve.
- The ALIP notes are cited where they are, ``docs/ALIP_NOTES.md``, not at the
  shared folder they were copied from.
- The README links the guides a user reads next.

``docs/NEW_ROBOT.md``'s list of profile keys is checked in ``tests/test_docs_profile_keys.py``,
the shipped files' freedom from development history in ``tests/test_docs_process_words.py``.
"""

from __future__ import annotations

import ast
import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EQUATIONS = ROOT / "docs" / "EQUATIONS.md"
#: The pages whose module and file references are checked.
GUIDES = (
    "docs/ARCHITECTURE.md",
    "docs/TUNING.md",
    "docs/RESULTS.md",
    "docs/LIMITATIONS.md",
    "docs/COMMANDS.md",
    "docs/EQUATIONS.md",
    "docs/ALIP_SLOPES.md",
    "docs/ALIP_MPC.md",
    "docs/SUMMARY_SCHEMA.md",
    "docs/NEW_ROBOT.md",
    "CONTRIBUTING.md",
    "amlip_qp/models/README.md",
    "amlip_qp/codegen/generated/README.md",
    "models/README.md",
    "examples/README.md",
    "README.md",
)
#: Top-level folders of the repository whose paths the guides name.
REPO_FOLDERS = ("amlip_qp", "tests", "docs", "examples", "models", ".ci")
#: Subpackages that the guides name relative to ``amlip_qp/`` (``control/wbc/``, ``qp/problem.py``).
PACKAGE_FOLDERS = ("alip", "codegen", "control", "experiments", "qp", "robots", "sim")

FUNCTION_REF = re.compile(r"`(amlip_qp(?:\.\w+)+):([\w.]+)`")
TEST_REF = re.compile(r"(tests/\w+\.py)::(\w+)")
DOTTED = re.compile(r"amlip_qp(?:\.\w+)+(?::\w+(?:\.\w+)*)?")
PATH_CHARS = r"/[\w./*{},-]*"  # a path after its first folder: names, globs, {a,b} alternatives
PATH = re.compile("(?:" + "|".join(re.escape(f) for f in REPO_FOLDERS) + ")" + PATH_CHARS)
PACKAGE_PATH = re.compile("(?:" + "|".join(PACKAGE_FOLDERS) + ")" + PATH_CHARS)
LINK = re.compile(r"\]\(([^)\s]+)\)")
#: The pages the README links, so that a reader finds the measurements, the limits and the contracts.
README_LINKS = (
    "docs/RESULTS.md",
    "docs/LIMITATIONS.md",
    "docs/TUNING.md",
    "docs/ARCHITECTURE.md",
    "docs/EQUATIONS.md",
    "docs/ALIP_NOTES.md",
    "docs/COMMANDS.md",
    "docs/NEW_ROBOT.md",
    "CONTRIBUTING.md",
)


def _backticked(text: str) -> list[str]:
    """The inline code spans of a Markdown text."""
    return re.findall(r"`([^`\n]+)`", text)


def _resolve(dotted: str) -> None:
    """Import ``amlip_qp.x.y[:attr]``: the module (for ``x.y``, its longest importable prefix), then the attributes.

    Raises ImportError or AttributeError for a name that does not exist.
    """
    module, _, attrs = dotted.partition(":")
    parts = module.split(".")
    cut = len(parts)
    while True:
        name = ".".join(parts[:cut])
        try:
            obj = importlib.import_module(name)
            break
        except ModuleNotFoundError as exc:
            # `module:attr` names the module exactly; a missing dependency of an existing module is an error too
            if attrs or cut == 1 or exc.name != name:
                raise
            cut -= 1
    for attr in parts[cut:] + (attrs.split(".") if attrs else []):
        obj = getattr(obj, attr)


def _expand(name: str) -> list[str]:
    """Brace alternatives, as the shell reads them: ``a.{c,h}`` -> ``a.c``, ``a.h``."""
    m = re.search(r"\{([^{}]*)\}", name)
    if m is None:
        return [name]
    return [e for alt in m.group(1).split(",") for e in _expand(name[: m.start()] + alt + name[m.end() :])]


def missing_functions(text: str) -> list[str]:
    """The ``amlip_qp.module:attr`` references of ``text`` that do not resolve."""
    missing = []
    for mod, attr in sorted(set(FUNCTION_REF.findall(text))):
        try:
            _resolve(f"{mod}:{attr}")
        except (ImportError, AttributeError) as exc:
            missing.append(f"{mod}:{attr} ({exc})")
    return missing


def missing_tests(text: str, root: Path = ROOT) -> list[str]:
    """The ``tests/<file>.py::<test>`` references of ``text`` whose file does not define the test."""
    defined: dict[str, set[str]] = {}
    missing = []
    for path, name in sorted(set(TEST_REF.findall(text))):
        if path not in defined:
            f = root / path
            tree = ast.parse(f.read_text()) if f.is_file() else ast.Module(body=[], type_ignores=[])
            defined[path] = {n.name for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
        if name not in defined[path]:
            missing.append(f"{path}::{name}")
    return missing


def missing_modules_and_files(text: str, root: Path = ROOT) -> list[str]:
    """The backticked ``amlip_qp.x.y``, repository and subpackage paths of ``text`` that do not exist."""
    missing = []
    for span in sorted(set(_backticked(text))):
        dotted = DOTTED.match(span)
        path = PATH.match(span) or PACKAGE_PATH.match(span)
        base = root if PATH.match(span) else root / "amlip_qp"
        if dotted:
            try:
                _resolve(dotted.group(0))
            except (ImportError, AttributeError) as exc:
                missing.append(f"{dotted.group(0)} ({exc})")
        elif path:
            for name in _expand(path.group(0).split("::")[0]):
                found = any(base.glob(name.rstrip("/"))) if "*" in name else (base / name).exists()
                if not found:
                    missing.append(name)
    return missing


def broken_links(text: str, page: Path) -> list[str]:
    """The relative Markdown links of ``text`` (a page at ``page``) that point to no file or folder."""
    broken = []
    for target in LINK.findall(text):
        if "://" in target or target.startswith(("#", "mailto:")):
            continue
        if not (page.parent / target.split("#")[0]).exists():
            broken.append(target)
    return broken


def test_every_function_of_the_equation_map_resolves():
    text = EQUATIONS.read_text()
    assert len(FUNCTION_REF.findall(text)) > 50  # the map is read, not skipped
    assert missing_functions(text) == []


def test_every_test_of_the_equation_map_exists():
    text = EQUATIONS.read_text()
    assert len(TEST_REF.findall(text)) > 50
    assert missing_tests(text) == []


def test_every_amlip_qp_span_of_the_equation_map_is_a_checked_reference():
    """A reference written another way (``amlip_qp.x.f()``, a space) would escape the checks above."""
    spans = [s for s in _backticked(EQUATIONS.read_text()) if s.startswith("amlip_qp")]
    loose = [s for s in spans if not (DOTTED.fullmatch(s) or PATH.fullmatch(s))]
    assert loose == []


@pytest.mark.parametrize("page", GUIDES)
def test_modules_and_files_named_in_the_guides_exist(page):
    assert missing_modules_and_files((ROOT / page).read_text()) == []


@pytest.mark.parametrize("page", GUIDES + ("docs/ALIP_NOTES.md",))
def test_relative_links_resolve(page):
    path = ROOT / page
    assert broken_links(path.read_text(), path) == []


def test_the_alip_notes_are_cited_in_docs():
    """Only the notes' own header may name the shared folder they were copied from."""
    patterns = ("*.md", "docs/*.md", "amlip_qp/**/*.py", "amlip_qp/**/*.xml", "amlip_qp/**/*.md")
    patterns += ("examples/**/*.py", "examples/**/*.md", "models/**/*.py", "models/**/*.md")
    pages = [p for pattern in patterns for p in ROOT.glob(pattern)]
    citing = [
        str(p.relative_to(ROOT))
        for p in pages
        if p.is_file() and p != ROOT / "docs" / "ALIP_NOTES.md" and "shared/ALIP_NOTES" in p.read_text()
    ]
    assert citing == []
    assert "docs/ALIP_NOTES.md" in (ROOT / "amlip_qp" / "alip" / "formulas.py").read_text()


def test_the_checks_report_stale_references(tmp_path):
    """References from before the control package's reorganisation are reported; current ones are not."""
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_a.py").write_text("def test_here():\n    pass\n")
    text = (
        "`amlip_qp.control.estimator:Estimator.estimate`, `amlip_qp.control.walking.estimator:Estimator.nope`, "
        "`amlip_qp.control.walking.estimator:Estimator.estimate`, `amlip_qp.alip.heading:next_heading`\n"
        "`tests/test_a.py::test_here`, `tests/test_a.py::test_gone`, `tests/test_b.py::test_here`\n"
    )
    assert [m.split(" ")[0] for m in missing_functions(text)] == [
        "amlip_qp.alip.heading:next_heading",
        "amlip_qp.control.estimator:Estimator.estimate",
        "amlip_qp.control.walking.estimator:Estimator.nope",
    ]
    assert missing_tests(text, tmp_path) == ["tests/test_a.py::test_gone", "tests/test_b.py::test_here"]
    (tmp_path / "amlip_qp" / "control" / "wbc").mkdir(parents=True)
    (tmp_path / "amlip_qp" / "control" / "wbc" / "builder.py").write_text("")
    guide = (
        "`amlip_qp/control/qp_formulation.py`, `amlip_qp/control/wbc/builder.py`, `amlip_qp/control/wbc/`, "
        "`amlip_qp.control.controller`, `amlip_qp.control.walking.controller`, `amlip_qp.qp.bench`, "
        "`amlip_qp.profiles.get_profile`, `amlip_qp/models/*.xml`, `tests/test_a.py`, `docs/NONE.md`, "
        "`control/wbc/builder.py`, `control/controller.py`, `amlip_qp/control/wbc/{builder,costs}.py`"
    )
    assert [m.split(" ")[0] for m in missing_modules_and_files(guide, tmp_path)] == [
        "amlip_qp.control.controller",
        "amlip_qp.qp.bench",
        "amlip_qp/control/qp_formulation.py",
        "amlip_qp/control/wbc/costs.py",
        "amlip_qp/models/*.xml",
        "control/controller.py",
        "docs/NONE.md",
    ]
    (tmp_path / "docs").mkdir()
    page = tmp_path / "docs" / "X.md"
    links = "[notes](../shared/ALIP_NOTES.md), [b](../amlip_qp/control/wbc/builder.py#L1), [w](https://x.org/a)"
    assert broken_links(links, page) == ["../shared/ALIP_NOTES.md"]


def test_the_readme_links_the_guides():
    links = set(LINK.findall((ROOT / "README.md").read_text()))
    assert [page for page in README_LINKS if page not in links] == []
