"""Shipped files speak to users (:data:`SHIPPED` and the tests): no issue numbers, no "session N" /
"stop N" / "pass N" / "helper N" history, no commit named as a point of history and no commit
hashes."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The shipped files whose whole text must be free of process words (so must the tests' but this one's
#: own examples: its names and docstrings).
SHIPPED = (
    "README.md",
    "pyproject.toml",
    ".ci/*",
    "CHANGELOG.md",
    "CONTRIBUTING.md",
    "docs/*.md",
    "amlip_qp/**/*.py",
    "amlip_qp/**/*.md",
    "examples/**/*.py",
    "examples/**/*.toml",
    "examples/**/*.md",
    "models/**/*.py",
    "models/**/*.md",
)
#: Work history in prose: an issue number ("issue 12", "issue #13", "issue-11"), "the issue's",
#: "session 3", "stop 2", "pass 4", "helper 2", "the fifth pass" / "the previous stop", and a commit
#: named as a point of history ("the reference commit", "baseline commit", "commit 12").
PROCESS_WORDS = re.compile(
    r"\b(?:issues?[ -]?#?\d+|issue's|(?:session|stop|pass|helper)[ -]#?\d+\b"
    r"|(?:first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|last|previous|next)\s+(?:pass|stop|session)\b"
    r"|(?:reference|baseline|parent|earlier|previous)\s+commits?\b|commit\s+#?\d+\b)",
    re.I,
)
#: A commit-hash-looking token: 7 to 40 hex digits with a letter and a digit, standing alone. Not a
#: hex constant (``0x...``), not part of a longer token (a 64-digit sha256, a path, an identifier),
#: not a float's mantissa (``4.96654564e-07``, ``1234567e-3``).
COMMIT_HASH = re.compile(r"(?<![\w.#-])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}(?![\w.-])")


def process_words(text: str) -> list[str]:
    """The issue numbers, history words and commit-hash-looking tokens of ``text``."""
    found = [m.group(0) for m in PROCESS_WORDS.finditer(text)]
    return found + [t for t in COMMIT_HASH.findall(text) if not re.fullmatch(r"\d+e", t)]


def _test_names_and_docstrings(path: Path) -> str:
    """A test file's function and class names and its docstrings, one a line."""
    tree = ast.parse(path.read_text())
    parts = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            parts.append(node.name)
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            parts.append(ast.get_docstring(node) or "")
    return "\n".join(parts)


def test_shipped_files_carry_no_process_words():
    pages = sorted({p for pattern in SHIPPED for p in ROOT.glob(pattern) if p.is_file()})
    assert len(pages) > 100  # the package's modules are read, not skipped
    found = {str(p.relative_to(ROOT)): process_words(p.read_text()) for p in pages}
    for path in sorted(ROOT.glob("tests/*.py")):  # this file's own examples aside: its names and docstrings
        text = _test_names_and_docstrings(path) if path.name == Path(__file__).name else path.read_text()
        found[str(path.relative_to(ROOT))] = process_words(text)
    assert {page: words for page, words in found.items() if words} == {}


def test_the_process_word_check_reports_history_and_spares_numbers():
    """Each kind of history is reported; hex constants, hashes of files, floats and words are not."""
    history = (
        "as measured in issue 14; issue #13's terrain; the issue-11 baseline; the issue's goal; "
        "session 3; stop 2 found; pass 4; after the fifth pass; the previous stop; at 3f125b1; (82a46cd); "
        "helper 2's walks; against the reference commit; the baseline commit's table; commit #12"
    )
    assert process_words(history) == [
        "issue 14",
        "issue #13",
        "issue-11",
        "issue's",
        "session 3",
        "stop 2",
        "pass 4",
        "fifth pass",
        "previous stop",
        "helper 2",
        "reference commit",
        "baseline commit",
        "commit #12",
        "3f125b1",
        "82a46cd",
    ]
    legit = (
        "mask 0x1f2e3d4c; sha256 e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855; "
        "inertia 4.96654564e-07 and 1234567e-3; 1500000 calls; a deadbeat step; cells/baebed2166a5_x.json; "
        "tests pass; the swing foot's stop; a Ray session; the test helpers; commit the regenerated files; "
        "the committed sources"
    )
    assert process_words(legit) == []
