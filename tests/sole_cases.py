"""Four-point-foot variants of the bundled humanoids: each bundled profile with its two-point
sole line replaced by the four corners of its Menagerie foot's collision geoms.

H1's foot: a toe bar from y = -0.03 to 0.03 m at x = 0.14 m and a heel capsule at x = -0.035 m,
their lowest points 0.070 m below the ankle (a rectangle of half width 0.03 m). G1's: four
spheres at x = 0.12 m (y = +-0.03 m) and x = -0.05 m (y = +-0.025 m), 0.035 m below the ankle.
"""

from pathlib import Path

from amlip_qp.paths import MODELS_DIR

#: Per robot: its bundled two-point line, and the four-point sole that replaces it.
SOLES = {
    "h1": (
        "force_points_m = [[0.14, 0.0, -0.07], [-0.035, 0.0, -0.07]]",
        "sole_rectangle_m = { x_front = 0.14, x_back = -0.035, half_width = 0.03, z = -0.07 }",
    ),
    "g1": (
        "force_points_m = [[0.12, 0.0, -0.035], [-0.05, 0.0, -0.035]]",
        "force_points_m = [[0.12, 0.03, -0.035], [0.12, -0.03, -0.035], [-0.05, 0.025, -0.035], "
        "[-0.05, -0.025, -0.035]]",
    ),
}


def sole_profile(name: str, folder: Path) -> Path:
    """Write the four-point variant of bundled robot ``name``'s profile into ``folder``; its path."""
    line, sole = SOLES[name]
    text = (MODELS_DIR / f"{name}.toml").read_text()
    assert line in text, f"{name}.toml no longer has the line {line!r}"
    text = text.replace(line, sole).replace('file = "unitree_', f'file = "{MODELS_DIR}/unitree_')
    path = Path(folder) / f"{name}_sole.toml"
    path.write_text(text)
    return path
