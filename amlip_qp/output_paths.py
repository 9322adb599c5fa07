"""Output paths of the commands: refuse an unwritable one before any work, and turn a failed write into one line.

Used by every command that writes a file (``walk``, ``compare``, ``bench``,
``codegen``); it imports only :mod:`amlip_qp.exceptions`, so every layer's
command handler may use it.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from amlip_qp.exceptions import InputError


def check_output_path(option: str, path: str | None, create_folder: bool = False) -> None:
    """Refuse, before any work, an output ``path`` that cannot be written (``None`` and ``'-'`` pass).

    A new file is created and removed again; an existing regular file is
    opened for appending (its content is kept); other existing files (a
    device, a pipe) must be writable by the user. With ``create_folder`` a
    missing parent folder is created, otherwise it is an error.

    Raises:
        InputError: Naming ``option``, the path and what to do.
    """
    if path is None or path == "-":
        return
    target = Path(path).expanduser()
    if target.is_dir():
        raise InputError(f"{option} {path}: is a folder; give a file name")
    folder = target.parent
    if create_folder and not folder.exists():
        try:
            folder.mkdir(parents=True)
        except OSError as exc:
            raise InputError(
                f"{option} {path}: cannot create the folder {folder} ({exc.strerror or exc}); give a writable path"
            ) from None
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{option} {path}: {folder} is a file, not a folder; give a path in a folder")
    if not folder.is_dir():
        raise InputError(f"{option} {path}: folder {folder} does not exist; create it or give another path")
    try:
        if not target.exists():
            os.close(os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL))
            target.unlink()
        elif target.is_file():
            os.close(os.open(target, os.O_WRONLY | os.O_APPEND))
        elif not os.access(target, os.W_OK):
            raise PermissionError(13, "Permission denied")
    except OSError as exc:
        raise InputError(f"{option} {path}: cannot write there ({exc.strerror or exc}); give a writable path") from None


def check_output_folder(option: str, path: str) -> None:
    """Refuse, before any work, an output folder ``path`` that cannot be written; create it if missing.

    A missing folder is created with its parents; an existing one must be a
    folder in which a file can be created (a probe file is created and removed).

    Raises:
        InputError: Naming ``option``, the path and what to do.
    """
    folder = Path(path).expanduser()
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{option} {path}: is a file, not a folder; give a folder path")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(
            f"{option} {path}: cannot create the folder ({exc.strerror or exc}); give a writable folder"
        ) from None
    try:
        fd, probe = tempfile.mkstemp(prefix=".amlip-qp-probe-", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise InputError(
            f"{option} {path}: cannot write there ({exc.strerror or exc}); give a writable folder"
        ) from None


@contextlib.contextmanager
def writing(option: str, path: str) -> Iterator[None]:
    """Turn an :class:`OSError` raised while writing ``path`` into an :class:`InputError` naming ``option``."""
    try:
        yield
    except OSError as exc:
        raise InputError(f"{option} {path}: writing failed ({exc.strerror or exc}); give a writable path") from exc


def emit_report(table: str, report: dict, target: str | None) -> None:
    """Print a benchmark's ``table`` and write its ``report`` as JSON to ``target`` (``--json``).

    ``target`` ``None``: the table on stdout only; ``"-"``: the table on stderr
    and the JSON on stdout; a path: the table on stdout and the JSON to the
    file (an :class:`~amlip_qp.exceptions.InputError` naming ``--json`` if it
    cannot be written, see :func:`writing`).
    """
    import json
    import sys

    if target == "-":
        sys.stderr.write(table + "\n")
        sys.stdout.write(json.dumps(report, indent=2) + "\n")
        return
    print(table)
    if target:
        with writing("--json", target):
            Path(target).write_text(json.dumps(report, indent=2) + "\n")
        print(f"wrote {target}")
