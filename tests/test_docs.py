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
- ``docs/NEW_ROBOT.md`` names every key a robot profile may have.
- Shipped files speak to users (:data:`SHIPPED`): no issue numbers, no
  "session N" / "stop N" / "pass N" history and no commit hashes; in the tests,
  their names and docstrings.
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
#: The shipped files whose whole text must be free of process words (the tests: names and docstrings).
SHIPPED = (
    "README.md",
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
#: "session 3", "stop 2", "pass 4", and "the fifth pass" / "the previous stop".
PROCESS_WORDS = re.compile(
    r"\b(?:issues?[ -]?#?\d+|issue's|(?:session|stop|pass)\s+#?\d+\b"
    r"|(?:first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|last|previous|next)\s+(?:pass|stop|session)\b)",
    re.I,
)
#: A commit-hash-looking token: 7 to 40 hex digits with a letter and a digit, standing alone. Not a
#: hex constant (``0x...``), not part of a longer token (a 64-digit sha256, a path, an identifier),
#: not a float's mantissa (``4.96654564e-07``, ``1234567e-3``).
COMMIT_HASH = re.compile(r"(?<![\w.#-])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}(?![\w.-])")


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


def test_the_readme_links_the_guides():
    links = set(LINK.findall((ROOT / "README.md").read_text()))
    assert [page for page in README_LINKS if page not in links] == []


def test_shipped_files_carry_no_process_words():
    pages = sorted({p for pattern in SHIPPED for p in ROOT.glob(pattern) if p.is_file()})
    assert len(pages) > 100  # the package's modules are read, not skipped
    found = {str(p.relative_to(ROOT)): process_words(p.read_text()) for p in pages}
    for path in sorted(ROOT.glob("tests/*.py")):
        found[str(path.relative_to(ROOT))] = process_words(_test_names_and_docstrings(path))
    assert {page: words for page, words in found.items() if words} == {}


def test_the_process_word_check_reports_history_and_spares_numbers():
    """Each kind of history is reported; hex constants, hashes of files, floats and words are not."""
    history = (
        "as measured in issue 14; issue #13's terrain; the issue-11 baseline; the issue's goal; "
        "session 3; stop 2 found; pass 4; after the fifth pass; the previous stop; at 3f125b1; (82a46cd)"
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
        "3f125b1",
        "82a46cd",
    ]
    legit = (
        "mask 0x1f2e3d4c; sha256 e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855; "
        "inertia 4.96654564e-07 and 1234567e-3; 1500000 calls; a deadbeat step; cells/baebed2166a5_x.json; "
        "tests pass; the swing foot's stop; a Ray session"
    )
    assert process_words(legit) == []


#: A key added to a profile table to make the reader list the table's keys in its refusal.
PROBE = "zz_probe"
#: The tables whose keys are names the profile chooses (joints, plants): not probed.
FREE_TABLES = ("model.stand.joints", "plants")


def _keys_listed(message: str) -> list[str]:
    """The keys an "unknown key" refusal lists: ``(known: a, b)``, ``(known here: a, b)`` or ``a table of a, b``."""
    m = re.search(r"\(known(?: here)?: ([^)]*)\)", message) or re.search(r"must be a table of (.*)$", message)
    return [k.strip() for k in m.group(1).split(",")] if m else []


def profile_keys(tmp_path: Path) -> dict[str, set[str]]:
    """Table (``""`` for the top level, ``"model.stand"``, ``"trackers.qp"`` ...) -> every key the
    profile reader accepts in it, as the reader itself lists them: a probe key added to each table of
    each bundled profile is refused with the list of the table's keys (the tracker tables when the
    tracker's configuration is built)."""
    from amlip_qp.estimation.invariant_ekf import noise_from_table
    from amlip_qp.exceptions import InputError
    from amlip_qp.paths import MODELS_DIR
    from amlip_qp.profiles import bundled_names, read_profile
    from amlip_qp.sim.scenarios.scenario_tables import profile_scenarios

    found: dict[str, set[str]] = {}
    for name in bundled_names():
        text = (MODELS_DIR / f"{name}.toml").read_text()
        text = re.sub(r'"([^"]+\.xml)"', lambda m: f'"{(MODELS_DIR / m.group(1)).resolve()}"', text)
        tables = [t for t in re.findall(r"^\[([\w.]+)\]$", text, re.M) if t not in FREE_TABLES]
        probes = {"": f"{PROBE} = 1\n{text}", "trackers": f"{text}\n[trackers.{PROBE}]\n"}
        for table in tables:
            probes[table] = text.replace(f"[{table}]\n", f"[{table}]\n{PROBE} = 1\n", 1)
        for table, probed in probes.items():
            path = tmp_path / f"{name}-{table or 'top'}.toml"
            path.write_text(probed)
            try:
                profile = read_profile(path)
                if table.split(".")[0] in ("scenarios", "settings", "mismatches"):
                    profile_scenarios(profile)  # these tables are checked when the scenarios are built
                elif table == "estimator":
                    noise_from_table(profile.estimator)
                else:
                    tracker = table.split(".")[1] if table.startswith("trackers.") else None
                    assert tracker is not None, f"{table}: the probe key was accepted"
                    profile.tracker_config(tracker)
                raise AssertionError(f"{table}: the probe key was accepted")
            except InputError as exc:
                keys = _keys_listed(str(exc))
                assert keys, f"{table}: no key list in {exc}"
                table = re.sub(r"^(scenarios|settings)\..*", r"\1.KEY", table)  # one entry per kind
                found.setdefault(table, set()).update(keys)
    return found


def test_the_new_robot_guide_names_every_profile_key(tmp_path):
    keys = profile_keys(tmp_path)
    tables = {"", "model", "model.stand", "roles", "feet", "imu", "gait", "bounds", "verified", "shaping", "compare"}
    tables |= {"trackers", "trackers.qp", "trackers.pbc", "trackers.pbc.spring_model_linkage"}
    tables |= {"scenarios.KEY", "settings.KEY", "mismatches", "estimator"}
    assert set(keys) == tables  # each table was probed, in some bundled profile (none has [unsupported])
    assert sum(len(k) for k in keys.values()) > 90
    assert {"step_time_s", "servos", "passive_in_stance", "pos_m", "quat_wxyz"} <= set().union(*keys.values())
    text = (ROOT / "docs" / "NEW_ROBOT.md").read_text()
    missing = [
        f"[{table}] {key}" if table else key
        for table, names in sorted(keys.items())
        for key in sorted(names)
        if f"`{key}`" not in text and f"[{table + '.' if table else ''}{key}]" not in text
    ]
    missing += [f"[{table}]" for table in sorted(keys) if table and f"[{table}]" not in text]
    assert missing == []
