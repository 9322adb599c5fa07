"""amlip_qp.output_paths: unwritable outputs are refused before any work; failed writes become one InputError."""

import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.output_paths import check_output_folder, check_output_path, writing


def test_check_output_path_keeps_files_and_creates_folders_only_when_asked(tmp_path):
    existing = tmp_path / "kept.json"
    existing.write_text("old\n")
    check_output_path("--json", str(existing))
    assert existing.read_text() == "old\n"  # opened for appending, not truncated
    new = tmp_path / "new.json"
    check_output_path("--json", str(new))
    assert not new.exists()  # the probe file is removed again
    nested = tmp_path / "a" / "b" / "fig.png"
    with pytest.raises(InputError, match="does not exist"):
        check_output_path("--plot", str(nested))
    check_output_path("--plot", str(nested), create_folder=True)
    assert nested.parent.is_dir() and not nested.exists()
    check_output_path("--json", None)
    check_output_path("--json", "-")


def _file(path):
    path.write_text("")
    return path


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda tmp: tmp, "is a folder"),
        (lambda tmp: tmp / "missing" / "x.json", "does not exist"),
        (lambda tmp: _file(tmp / "f") / "x.json", "is a file, not a folder"),
    ],
)
def test_bad_paths_name_the_option_and_the_fix(tmp_path, make, message):
    path = str(make(tmp_path))
    with pytest.raises(InputError, match=message) as info:
        check_output_path("--json", path)
    assert str(info.value).startswith(f"--json {path}:")


def test_a_path_under_proc_is_refused():
    with pytest.raises(InputError, match="cannot write there"):
        check_output_path("--video", "/proc/x.mp4")


def test_check_output_folder_creates_a_missing_folder_and_leaves_an_existing_one_as_it_was(tmp_path):
    existing = tmp_path / "gen"
    existing.mkdir()
    (existing / "kept.c").write_text("int x;\n")
    check_output_folder("--out", str(existing))
    assert [p.name for p in existing.iterdir()] == ["kept.c"]  # the probe file is removed again
    nested = tmp_path / "a" / "b"
    check_output_folder("--out", str(nested))
    assert nested.is_dir() and list(nested.iterdir()) == []


@pytest.mark.parametrize(
    "path, message",
    [
        ("/proc/x", "--out /proc/x: cannot create the folder (No such file or directory); give a writable folder"),
        ("/sys/kernel", "--out /sys/kernel: cannot write there (Permission denied); give a writable folder"),
        ("{file}", "--out {file}: is a file, not a folder; give a folder path"),
        ("{file}/sub", "--out {file}/sub: cannot create the folder (Not a directory); give a writable folder"),
    ],
)
def test_check_output_folder_refuses_in_one_line(path, message, tmp_path):
    a_file = _file(tmp_path / "f")
    with pytest.raises(InputError) as info:
        check_output_folder("--out", path.format(file=a_file))
    assert str(info.value) == message.format(file=a_file)


def test_writing_turns_an_oserror_into_an_input_error():
    with pytest.raises(InputError, match=r"--log /full/x.npz: writing failed \(No space left on device\)"):
        with writing("--log", "/full/x.npz"):
            raise OSError(28, "No space left on device")
    with writing("--log", "/ok.npz"):  # no error, no effect
        pass


def test_emit_report_prints_the_table_and_writes_the_json_where_asked(tmp_path, capsys):
    import json

    from amlip_qp.output_paths import emit_report

    report = {"ratio": 0.05, "ticks": 10}
    emit_report("TABLE", report, None)
    out, err = capsys.readouterr()
    assert out == "TABLE\n" and err == ""
    emit_report("TABLE", report, "-")
    out, err = capsys.readouterr()
    assert json.loads(out) == report and err == "TABLE\n"
    path = tmp_path / "r.json"
    emit_report("TABLE", report, str(path))
    out, _ = capsys.readouterr()
    assert json.loads(path.read_text()) == report and out == f"TABLE\nwrote {path}\n"
