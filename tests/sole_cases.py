"""Four-point-foot variants of the bundled humanoids, from ``examples/four_point_feet.py``.

Each bundled profile with its two-point sole line replaced by a four-point sole: H1's rectangle
(its toe bar's ends and heel capsule, 0.070 m below the ankle), G1's four foot spheres (0.035 m
below the ankle). The example and the tests build them with the same function.
"""

import importlib.util
from pathlib import Path

_spec = importlib.util.spec_from_file_location(
    "four_point_feet_example", Path(__file__).resolve().parents[1] / "examples" / "four_point_feet.py"
)
_example = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_example)

#: Per robot: its bundled sole line and the four-point soles that replace it, by name.
SOLES = _example.SOLES
#: ``sole_profile(robot, folder, sole=None)``: the profile with sole ``sole`` (default: the
#: robot's first, H1's rectangle and G1's four spheres) written into ``folder``; its path.
sole_profile = _example.sole_profile
