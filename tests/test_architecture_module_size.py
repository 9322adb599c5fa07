"""One concept per file: every shipped Python file, the package's, the tests', the examples' and the
model tools', is at most 400 lines (the style guide's "modules under about 400 lines")."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The folders of shipped Python files (the generated C and the data files are no modules).
SHIPPED = (ROOT / "amlip_qp", ROOT / "tests", ROOT / "examples", ROOT / "models")
#: The style guide's bound on a module's length, lines ("modules under about 400 lines; one concept per file").
MAX_MODULE_LINES = 400


def _long_modules(folder: Path, limit: int) -> dict[str, int]:
    """Every Python file under ``folder`` longer than ``limit`` lines: its path from the folder's
    parent -> its line count."""
    counts = {
        p.relative_to(folder.parent).as_posix(): len(p.read_text().splitlines()) for p in sorted(folder.rglob("*.py"))
    }
    return {path: n for path, n in counts.items() if n > limit}


def test_every_shipped_python_file_is_at_most_400_lines():
    """One concept per file keeps each short: a module, test module, example or model tool over the bound
    is split, not allowed."""
    assert all(any(folder.rglob("*.py")) for folder in SHIPPED)
    over = {path: n for folder in SHIPPED for path, n in _long_modules(folder, MAX_MODULE_LINES).items()}
    assert over == {}, f"split these files (lines) into files of one concept each: {over}"


def test_the_length_check_finds_a_long_module(tmp_path):
    pkg = tmp_path / "amlip_qp"
    (pkg / "sim").mkdir(parents=True)
    (pkg / "sim" / "short.py").write_text("x = 1\n" * 400)
    (pkg / "sim" / "long.py").write_text("x = 1\n" * 401)
    (pkg / "codegen" / "generated").mkdir(parents=True)
    (pkg / "codegen" / "generated" / "kernels.c").write_text("int x;\n" * 1000)
    assert _long_modules(pkg, 400) == {"amlip_qp/sim/long.py": 401}
