"""The ``--terrain`` specs (sim.world.terrain.parse_terrain): good specs read canonically, bad ones and
unreadable or oversized height maps refused with what to fix."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sim.world.terrain import (
    parse_terrain,
)


@pytest.mark.parametrize(
    "text, kind, canonical, params",
    [
        ("flat", "flat", "flat", ()),
        (" slope:10.0 ", "slope", "slope:10", (10.0,)),
        ("slope:-22.5", "slope", "slope:-22.5", (-22.5,)),
        ("stairs:0.1:0.3", "stairs", "stairs:0.1:0.3:4", (0.1, 0.3, 4.0)),
        ("stairs:0.15:0.25:2", "stairs", "stairs:0.15:0.25:2", (0.15, 0.25, 2.0)),
        ("rough:0.04", "rough", "rough:0.04:0", (0.04, 0.0)),
        ("rough:0.05:7", "rough", "rough:0.05:7", (0.05, 7.0)),
        ("waves:0.3:4", "waves", "waves:0.3:4", (0.3, 4.0, 0.0)),
        ("waves:0.3:4:0", "waves", "waves:0.3:4", (0.3, 4.0, 0.0)),
        ("waves:0.3:4:-0", "waves", "waves:0.3:4", (0.3, 4.0, 0.0)),
        ("waves:0.6:2.25:90", "waves", "waves:0.6:2.25:90", (0.6, 2.25, 90.0)),
        ("waves:0.6:2.25:-30.5", "waves", "waves:0.6:2.25:-30.5", (0.6, 2.25, -30.5)),
    ],
)
def test_parse_good_specs(text, kind, canonical, params):
    spec = parse_terrain(text)
    assert (spec.kind, spec.text, spec.params) == (kind, canonical, params)
    assert parse_terrain(spec.text) == spec  # the canonical text parses to itself


@pytest.mark.parametrize(
    "text, needle",
    [
        ("", "unknown terrain"),
        ("hill", "unknown terrain"),
        ("flat:1", "wrong number of fields for flat"),
        ("slope:45", "less than 45 deg"),
        ("slope:-45", "less than 45 deg"),
        ("slope:inf", "less than 45 deg"),
        ("slope:1:2", "wrong number of fields for slope"),
        ("stairs:0.1", "wrong number of fields for stairs"),
        ("stairs:0:0.3", "RISE_M must be a number in (0, 1]"),
        ("stairs:0.1:-0.3", "RUN_M must be a number in (0, 10]"),
        ("stairs:0.1:0.3:0", "N must be in [1, 50]"),
        ("rough:nan", "AMPLITUDE_M must be a number in (0, 1]"),
        ("rough:0.04:x", "SEED must be a whole number"),
        ("waves:-0.3:4", "HEIGHT_M must be a number in (0, 5]"),
        ("waves:0.3:0.1", "the wavelength must be at least 0.2 m"),
        ("waves:1.5:4", "deg steep at their flanks"),
        ("waves:1.5:4:90", "deg steep at their flanks"),
        ("waves:0.3:4:91", "HEADING_DEG must be in [-90, 90]"),
        ("waves:0.3:4:nan", "HEADING_DEG must be in [-90, 90]"),
        ("waves:0.3:4:east", "HEADING_DEG must be a number of degrees"),
        ("waves:0.3:4:0:1", "wrong number of fields for waves"),
        ("hfield:a.png:1:2", "give hfield:PATH.png"),
        ("hfield:/nonexistent/h.png:10:4:0.5", "height map not found: /nonexistent/h.png"),
        ("hfield:x.png:-10:4:0.5", "SIZE_X_M must be a number in (0, 1000]"),
    ],
)
def test_parse_bad_specs_name_what_to_fix(text, needle):
    with pytest.raises(InputError) as err:
        parse_terrain(text)
    msg = str(err.value)
    assert needle in msg and "\n" not in msg


def test_unreadable_and_tiny_pngs_are_input_errors(tmp_path):
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png")
    with pytest.raises(InputError, match="cannot read the height map"):
        parse_terrain(f"hfield:{bad}:10:4:0.5")
    tiny = tmp_path / "tiny.png"
    iio.imwrite(tiny, np.zeros((1, 5), dtype=np.uint8))
    with pytest.raises(InputError, match="at least 2 x 2 pixels"):
        parse_terrain(f"hfield:{tiny}:10:4:0.5")


def test_a_height_map_above_the_pixel_bound_is_refused_from_its_header(tmp_path, monkeypatch):
    from amlip_qp.sim.world import terrain_grids as G

    at_bound, above = tmp_path / "at.png", tmp_path / "above.png"
    iio.imwrite(at_bound, np.zeros((4096, 4096), dtype=np.uint8))
    iio.imwrite(above, np.zeros((4096, 4097), dtype=np.uint8))
    assert G.image_size(str(above)) == (4097, 4096)
    assert parse_terrain(f"hfield:{at_bound}:20:8:0.1").grid.data.shape == (4096, 4096)

    def no_decoding(*args, **kwargs):
        raise AssertionError("the height map was decoded")

    monkeypatch.setattr(iio, "imread", no_decoding)
    with pytest.raises(InputError) as err:
        parse_terrain(f"hfield:{above}:20:8:0.1")
    assert str(err.value) == (
        f"--terrain 'hfield:{above}:20:8:0.1': height map {above} has 4097 x 4096 pixels; at most 16777216 "
        "pixels (4096 x 4096) are read: downsample it (MuJoCo holds every pixel of a height field in memory)"
    )


def test_other_image_formats_are_sized_by_pillow_and_a_decompression_bomb_is_refused(tmp_path):
    from amlip_qp.sim.world import terrain_grids as G

    small = tmp_path / "small.bmp"
    iio.imwrite(small, np.zeros((3, 7), dtype=np.uint8))
    assert G.image_size(str(small)) == (7, 3)
    bomb = tmp_path / "bomb.bmp"  # the BMP header's width and height (int32 at bytes 18 and 22) say 30000 x 30000
    data = bytearray(small.read_bytes())
    data[18:26] = (30000).to_bytes(4, "little") + (30000).to_bytes(4, "little")
    bomb.write_bytes(bytes(data))
    with pytest.raises(InputError, match="has more pixels than Pillow opens; at most 16777216 pixels"):
        G.read_gray_png(str(bomb))
    (tmp_path / "text.png").write_text("not an image")
    assert G.image_size(str(tmp_path / "text.png")) is None  # unknown: the decoder says what is wrong
