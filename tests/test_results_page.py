"""``examples/results_page.py``: the generated blocks of docs/RESULTS.md and the commands that write them."""

from __future__ import annotations

import importlib.util
import json
import pathlib
import platform
import shutil
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: A command that prints a fixed Markdown table, standing in for a measurement.
FIXED_TABLE = "| a | b |\n|---|---|\n| 1.5 | 2 |\n"


@pytest.fixture(scope="module")
def results_page():
    spec = importlib.util.spec_from_file_location("results_page", ROOT / "examples" / "results_page.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["results_page"] = module  # dataclasses resolve their module by name
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def page(tmp_path):
    copy = tmp_path / "RESULTS.md"
    shutil.copyfile(ROOT / "docs" / "RESULTS.md", copy)
    return copy


def _fake(results_page, monkeypatch, entry_id: str, argv: tuple[str, ...], kind: str = "markdown"):
    """The manifest with ``entry_id``'s command replaced."""
    manifest = tuple(results_page.Entry(e.id, argv, kind, 1) if e.id == entry_id else e for e in results_page.MANIFEST)
    monkeypatch.setattr(results_page, "MANIFEST", manifest)
    return results_page.entries()[entry_id]


def _outside(text: str, entry_id: str) -> tuple[str, str]:
    """The page's text before the block's opening marker and from its closing marker on."""
    start = text.index(f"<!-- results: {entry_id} -->\n")
    end = text.index(f"<!-- /results: {entry_id} -->")
    return text[:start], text[end:]


def test_the_results_page_matches_the_manifest(results_page, capsys):
    assert results_page.main(["--check"]) == 0
    assert "every one matches the manifest" in capsys.readouterr().out
    text = (ROOT / "docs" / "RESULTS.md").read_text()
    for entry in results_page.MANIFEST:  # the command line sits right after each opening marker
        assert f"<!-- results: {entry.id} -->\n{results_page.command_line(entry)}\n" in text


def test_only_rewrites_its_block_and_nothing_else(results_page, monkeypatch, page):
    entry = _fake(results_page, monkeypatch, "bench-mpc", ("python", "-c", f"print({FIXED_TABLE!r}, end='')"))
    before = page.read_text()
    assert results_page.main(["--only", "bench-mpc", "--page", str(page)]) == 0
    after = page.read_text()
    assert _outside(after, "bench-mpc") == _outside(before, "bench-mpc")  # byte for byte
    start = after.index("<!-- results: bench-mpc -->\n") + len("<!-- results: bench-mpc -->\n")
    inner = after[start : after.index("<!-- /results: bench-mpc -->")].split("\n")
    assert inner[0] == "Command: `python -c " + results_page.shlex.quote(f"print({FIXED_TABLE!r}, end='')") + "`"
    assert inner[0] == results_page.command_line(entry)
    assert inner[1].startswith("Measured ") and f"Python {platform.python_version()}" in inner[1]
    assert "\n".join(inner[2:]) == "\n" + FIXED_TABLE
    assert results_page.main(["--check", "--page", str(page)]) == 0  # the rewritten page is consistent


def test_a_text_command_is_shown_as_a_code_block(results_page, monkeypatch, page):
    _fake(results_page, monkeypatch, "bench-codegen", ("python", "-c", "print('what  median_us\\nx  1.25')"), "text")
    assert results_page.main(["--only", "bench-codegen", "--page", str(page)]) == 0
    text = page.read_text()
    assert "\n\n```text\nwhat  median_us\nx  1.25\n```\n<!-- /results: bench-codegen -->" in text
    assert results_page.main(["--check", "--page", str(page)]) == 0


def test_compare_json_becomes_the_librarys_columns_as_markdown(results_page):
    from amlip_qp.experiments.compare_table import TABLE_COLUMNS

    row = {
        "robot": "rabbit",
        "tracker": "qp",
        "planner": "one-step",
        "fell": False,
        "velocity_error_rms": 0.0431,
        "max_sagittal_impulse_Ns": 60.0,
        "sagittal_impulse_at_upper_bound": True,
        "max_lateral_impulse_Ns": None,
        "tick_time_median_us": 274.4,
    }
    table = results_page.compare_markdown(json.loads(json.dumps({"rows": [row]}))).split("\n")
    assert table[0] == "| " + " | ".join(h for _, h, _ in TABLE_COLUMNS) + " |"
    cells = dict(zip([h for _, h, _ in TABLE_COLUMNS], table[2].strip("| ").split(" | ")))
    assert cells["tracker"] == "qp / one-step" and cells["fell"] == "no"
    assert cells["v err m/s"] == "0.043" and cells["tick med us"] == "274"
    assert cells["push x Ns"] == ">=60.0" and cells["push y Ns"] == "-" and cells["foot err m"] == "-"


def test_check_reports_a_block_whose_command_drifted(results_page, page, capsys):
    text = page.read_text()
    page.write_text(text.replace("Command: `amlip-qp bench mpc`", "Command: `amlip-qp bench mpc --duration 2`"))
    assert results_page.main(["--check", "--page", str(page)]) == 1
    assert capsys.readouterr().out.startswith("bench-mpc: the block does not start with")


def test_check_reports_a_table_outside_the_blocks(results_page, page, capsys):
    """A hand-written table, one line or several, is reported once by its first line; inside a block it is not."""
    text = page.read_text()
    lines = text.split("\n")
    assert results_page.check(page) == []
    hand = "| run | result |\n|---|---|\n| by hand | walked |"
    page.write_text(
        text.replace("<!-- results: bench-mpc -->", f"{hand}\n\n| one line |\n<!-- results: bench-mpc -->", 1)
    )
    at = lines.index("<!-- results: bench-mpc -->") + 1
    assert results_page.main(["--check", "--page", str(page)]) == 1
    out = capsys.readouterr().out.splitlines()
    assert [o.split(":")[0] for o in out] == [f"line {at}", f"line {at + 4}"]
    assert all("a table outside the generated blocks" in o for o in out)


def test_check_reports_a_table_indented_under_a_list_item(results_page, page, capsys):
    text = page.read_text()
    at = text.split("\n").index("<!-- results: bench-mpc -->") + 1
    table = "- a list item with a table:\n\n  | run | result |\n  |---|---|\n  | by hand | walked |\n"
    page.write_text(text.replace("<!-- results: bench-mpc -->", f"{table}<!-- results: bench-mpc -->", 1))
    assert results_page.main(["--check", "--page", str(page)]) == 1
    assert capsys.readouterr().out.splitlines()[0].startswith(f"line {at + 2}: a table outside the generated blocks")


def test_check_reports_blocks_missing_from_either_side(results_page, monkeypatch, page, capsys):
    manifest = tuple(e for e in results_page.MANIFEST if e.id != "bench-mpc")
    monkeypatch.setattr(results_page, "MANIFEST", (*manifest, results_page.Entry("extra", ("true",), "text", 1)))
    assert results_page.main(["--check", "--page", str(page)]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out == [
        "bench-mpc: block in the page but not in the manifest",
        "extra: in the manifest but no block in the page",
    ]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--only", "no-such-block"], "unknown block id no-such-block"),
        (["--only", "bench-mpc", "--page", "/nonexistent/RESULTS.md"], "no results page at /nonexistent/RESULTS.md"),
    ],
)
def test_bad_input_exits_2_with_one_line(results_page, argv, message, capsys):
    assert results_page.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


def test_unpaired_markers_are_bad_input(results_page, page, capsys):
    page.write_text(page.read_text().replace("<!-- /results: bench-mpc -->\n", "", 1))
    assert results_page.main(["--only", "bench-codegen", "--page", str(page)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "opens inside block 'bench-mpc'" in err


def test_a_failing_command_leaves_its_block_as_it_was(results_page, monkeypatch, page, capsys):
    _fake(results_page, monkeypatch, "bench-mpc", ("python", "-c", "import sys; sys.exit('no solver')"))
    before = page.read_text()
    assert results_page.main(["--only", "bench-mpc", "--page", str(page)]) == 1
    assert page.read_text() == before
    assert "exited 1: no solver" in capsys.readouterr().err


def test_a_malformed_marker_is_bad_input(results_page, page, capsys):
    page.write_text(page.read_text().replace("<!-- results: bench-mpc -->", "<!-- results: Bench_MPC -->", 1))
    assert results_page.main(["--check", "--page", str(page)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "malformed marker '<!-- results: Bench_MPC -->'" in err
