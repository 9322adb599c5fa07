"""``examples/raised_starts.py --forward M``: start k moved forward by k * M m instead of raised."""

from __future__ import annotations

import importlib.util
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _raised_starts():
    spec = importlib.util.spec_from_file_location("raised_starts", ROOT / "examples" / "raised_starts.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_start_moved_forward_walks_the_same_gait_further_on():
    """Rabbit on flat ground: the start moved 0.05 m forward walks the first half second like the
    unmoved one (the speed within 1 mm/s) but not bit for bit; the option's bounds are checked."""
    module = _raised_starts()
    runs = [module.walk_from(("rabbit-1mps", "qp", "one-step", 0.5, k, 0.05)) for k in (0, 1)]
    assert runs[0][3] == module.walk_from(("rabbit-1mps", "qp", "one-step", 0.5, 0))[3]  # k = 0: the start itself
    assert not any(fell for _, fell, _, _ in runs)
    assert runs[0][3] != runs[1][3] and abs(runs[0][3] - runs[1][3]) < 1e-3
    with pytest.raises(SystemExit) as info:
        module.main(["--forward", "0.5"])
    assert info.value.code == 2
