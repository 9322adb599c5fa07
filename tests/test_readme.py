"""The README's library example runs as written and gives sensible numbers."""

import re
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_example_runs(capsys):
    text = README.read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "the README lost its python example"
    namespace: dict = {}
    exec(compile(blocks[0], "README.md", "exec"), namespace)
    out, kin = namespace["out"], namespace["kin"]
    r_st = kin.contact_position("left")
    # The target is the predicted CoM at T- minus the desired swing-to-CoM offset.
    np.testing.assert_allclose(out.swing_target_world_m[:2], r_st[:2] + out.p_hat_m - out.p_sw_des_world_m, atol=1e-12)
    # The right foot steps to the right of the left stance foot, by a width
    # of the order of the commanded 0.25 m.
    assert 0.1 < r_st[1] - out.swing_target_world_m[1] < 0.45
    assert np.isfinite(out.h_d).all()
    printed = capsys.readouterr().out
    assert "swing foot target" in printed
    assert "np.float64" not in printed, "the example should print plain floats"
