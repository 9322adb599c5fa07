"""What the bad-input tests of ``amlip-qp`` share: running the CLI in this process, the files they
point it at, and the check that a refusal is one line, exit status 2 and nothing written."""

from __future__ import annotations

import struct
import zlib

from amlip_qp import cli
from amlip_qp.paths import MODELS_DIR

#: A plant that lacks everything Cassie's controller needs.
RABBIT_XML = str(MODELS_DIR / "rabbit.xml")


def header_only_png(path, width, height):
    """A PNG signature and an IHDR chunk of ``width`` x ``height`` 8-bit gray pixels, without image data."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    chunk = struct.pack(">I", len(ihdr)) + b"IHDR" + ihdr + struct.pack(">I", zlib.crc32(b"IHDR" + ihdr))
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk)
    return path


def run_main(argv, capsys):
    try:
        code = cli.main(argv)
    except SystemExit as exc:  # argparse errors
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def profile_without_pbc(tmp_path):
    """H1's profile, its model by absolute path, with an ``[unsupported]`` reason for the PBC (written
    beside ``tmp_path``, which the test checks for files written)."""
    text = (MODELS_DIR / "h1.toml").read_text()
    text = text.replace('file = "unitree_h1/h1.xml"', f'file = "{MODELS_DIR / "unitree_h1" / "h1.xml"}"')
    path = tmp_path.parent / f"{tmp_path.name}_no_pbc.toml"
    path.write_text(text + '\n[unsupported]\npbc = "a test reason"\n')
    return path


def assert_refused(argv, needle, tmp_path, capsys):
    """``argv`` (``{tmp}``, ``{file}``, ``{bigpng}``, ``{no_pbc}`` filled in) exits 2 with one line on
    stderr holding ``needle``, no traceback, nothing on stdout and nothing written."""
    a_file = tmp_path / "a_file.txt"
    a_file.write_text("not a folder\n")
    big_png = header_only_png(tmp_path / "big.png", 12000, 12000)
    before = sorted(p.name for p in tmp_path.iterdir())
    no_pbc = profile_without_pbc(tmp_path)
    argv = [a.format(tmp=tmp_path, file=a_file, bigpng=big_png, no_pbc=no_pbc) for a in argv]
    code, out, err = run_main(argv, capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("amlip-qp"), err
    assert "Traceback" not in err and "np.float64" not in err and out == ""
    assert needle in lines[0]
