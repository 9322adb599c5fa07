"""The keys of ``amlip-qp view``: which key does what, and by how much; a key script (light: no numpy, no MuJoCo).

The codes are GLFW's key codes, what MuJoCo's viewer hands its ``key_callback``
(``mujoco.viewer.launch_passive``). The keys are chosen among those the viewer
itself leaves alone in its passive mode: every letter, digits and most
punctuation toggle one of its own visualisation or rendering flags (``,`` the
segmentation rendering, ``D`` the static bodies, ``R`` the reflections), so
none is used here. Backspace is also the viewer's own "Reset" (MuJoCo's
default state, not the stand keyframe); the live loop sees that reset and puts
the robot back at its keyframe (:mod:`amlip_qp.sim.loop.live`).

The command parser (``--help``) and :mod:`amlip_qp.sim.loop.live` read the same table;
:func:`parse_key_script` reads ``view --script``'s key presses at simulated times.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from amlip_qp.exceptions import InputError

#: Step of the forward-speed command per key press, m/s.
VX_STEP_MPS = 0.1
#: Step of the lateral-speed command per key press, m/s.
VY_STEP_MPS = 0.05
#: Step of the turn-rate command per key press, deg/s.
TURN_STEP_DEGPS = 10.0

#: The actions a key can have.
ACTIONS = ("vx+", "vx-", "turn+", "turn-", "vy+", "vy-", "stop", "pause", "reset")


@dataclass(frozen=True)
class KeyBinding:
    """One key of the live view.

    Attributes:
        name: The key's name, as in a key script (case does not matter).
        code: Its GLFW key code.
        action: One of :data:`ACTIONS`.
        help: What it does, for people.
    """

    name: str
    code: int
    action: str
    help: str


BINDINGS: tuple[KeyBinding, ...] = (
    KeyBinding("up", 265, "vx+", f"forward speed +{VX_STEP_MPS:g} m/s"),
    KeyBinding("down", 264, "vx-", f"forward speed -{VX_STEP_MPS:g} m/s"),
    KeyBinding("left", 263, "turn+", f"turn rate +{TURN_STEP_DEGPS:g} deg/s (to the left)"),
    KeyBinding("right", 262, "turn-", f"turn rate -{TURN_STEP_DEGPS:g} deg/s (to the right)"),
    KeyBinding("home", 268, "vy+", f"lateral speed +{VY_STEP_MPS:g} m/s (to the left)"),
    KeyBinding("end", 269, "vy-", f"lateral speed -{VY_STEP_MPS:g} m/s (to the right)"),
    KeyBinding("enter", 257, "stop", "every speed to 0 (walk in place)"),
    KeyBinding("space", 32, "pause", "pause / resume"),
    KeyBinding("backspace", 259, "reset", "back to the stand keyframe and the starting command"),
)

#: Key code -> action.
ACTION_OF_CODE: dict[int, str] = {b.code: b.action for b in BINDINGS}
#: Key name -> key code.
CODE_OF_NAME: dict[str, int] = {b.name: b.code for b in BINDINGS}


def keys_help() -> str:
    """The keys, one per line, as ``--help`` shows them."""
    width = max(len(b.name) for b in BINDINGS)
    lines = [f"  {b.name.capitalize():<{width}}  {b.help}" for b in BINDINGS]
    lines.append(f"  {'mouse':<{width}}  double-click a body to select it, Ctrl + right-drag to push it")
    lines.append(f"  {'F1':<{width}}  MuJoCo's own help (camera, selection); Tab, Shift+Tab: its panels")
    return "\n".join(lines)


def parse_key_script(text: str, source: str = "key script") -> tuple[tuple[float, int], ...]:
    """``(t_s, key code)`` pairs, in time order, from lines ``T KEY`` (simulated s, a key name; ``#`` comments).

    Raises:
        InputError: A line that is not a time >= 0 and one of the keys' names, saying which.
    """
    events = []
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        names = ", ".join(CODE_OF_NAME)
        if len(parts) != 2:
            raise InputError(f"{source} line {number}: expected 'T KEY' (simulated s, one of {names}), got {raw!r}")
        try:
            t_s = float(parts[0])
        except ValueError:
            t_s = math.nan
        if not (math.isfinite(t_s) and t_s >= 0.0):
            raise InputError(f"{source} line {number}: the time must be a number of seconds >= 0, got {parts[0]!r}")
        code = CODE_OF_NAME.get(parts[1].lower())
        if code is None:
            raise InputError(f"{source} line {number}: unknown key {parts[1]!r}; known: {names}")
        events.append((t_s, code))
    return tuple(sorted(events, key=lambda e: e[0]))
