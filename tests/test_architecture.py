"""The layer contract of docs/ARCHITECTURE.md, checked on the imports of every module.

Every package and every top-level module of amlip_qp has a rule: the amlip_qp
modules it may import (dotted prefixes) and the modules it must never import
(third-party or amlip_qp prefixes), directly or lazily inside a function.
A new package or top-level module without a rule fails the coverage test.
"""

import ast
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "amlip_qp"


@dataclass(frozen=True)
class Rule:
    """``may``: amlip_qp module prefixes it may import; ``never``: prefixes it must not import."""

    may: tuple[str, ...]
    never: tuple[str, ...] = ()


#: Third-party packages that only some layers may use.
HEAVY = ("mujoco", "pinocchio", "casadi", "proxsuite", "qpsolvers", "scipy", "matplotlib", "imageio", "tqdm")
#: What every control subpackage may use below it.
CONTROL_BASE = (
    "amlip_qp.alip",
    "amlip_qp.codegen",
    "amlip_qp.robots",
    "amlip_qp.exceptions",
    "amlip_qp.messages",
    "amlip_qp.profiles",
)
#: The control subpackages (jobs).
CONTROL_JOBS = ("amlip_qp.control.walking", "amlip_qp.control.pbc", "amlip_qp.control.wbc", "amlip_qp.control.mpc")

#: The subpackages of ``amlip_qp.sim``, one per job, lowest first: each may import those before it, never after.
SIM_JOBS = (
    "amlip_qp.sim.world",
    "amlip_qp.sim.sensing",
    "amlip_qp.sim.loop",
    "amlip_qp.sim.scenarios",
    "amlip_qp.sim.reports",
)
#: What sits above the library: never imported by it.
ABOVE_THE_LIBRARY = ("amlip_qp.experiments", "amlip_qp.sweep", "amlip_qp.cli", "amlip_qp.__main__")


def _sim_job(job: str, below: tuple[str, ...], never: tuple[str, ...] = ()) -> Rule:
    """The rule of the sim job ``job``: itself, the jobs before it in :data:`SIM_JOBS` and ``below``."""
    lower = SIM_JOBS[: SIM_JOBS.index(job) + 1]
    return Rule(
        lower + below, never + SIM_JOBS[SIM_JOBS.index(job) + 1 :] + ABOVE_THE_LIBRARY + ("amlip_qp.output_paths",)
    )


#: unit (a package, or a top-level module) -> its rule (docs/ARCHITECTURE.md, "Layers").
RULES: dict[str, Rule] = {
    # the package's own __init__: re-exports the exceptions, and lazily the robot, the controller,
    # its trackers and messages and the MuJoCo loop (so `import amlip_qp` stays light)
    "amlip_qp": Rule(
        (
            "amlip_qp.exceptions",
            "amlip_qp.robots",
            "amlip_qp.messages",
            "amlip_qp.control.walking",
            "amlip_qp.control.wbc.tracker",
            "amlip_qp.control.pbc.tracker",
            "amlip_qp.sim.loop.mujoco_loop",
        ),
        HEAVY + ("numpy",),
    ),
    "amlip_qp.exceptions": Rule((), HEAVY + ("numpy",)),
    # the closed loop's messages: below every part that exchanges them (numpy only)
    "amlip_qp.messages": Rule(("amlip_qp.exceptions",), HEAVY),
    "amlip_qp.paths": Rule((), HEAVY + ("numpy",)),
    "amlip_qp.output_paths": Rule(("amlip_qp.exceptions",), HEAVY + ("numpy",)),
    # the option values' checks, shared by the command line's types and the walk options (light)
    "amlip_qp.option_values": Rule(("amlip_qp.exceptions", "amlip_qp.profiles"), HEAVY + ("numpy",)),
    # the robot profiles: plain data read from TOML files among the package's models
    "amlip_qp.profiles": Rule(("amlip_qp.profiles", "amlip_qp.exceptions", "amlip_qp.paths"), HEAVY + ("numpy",)),
    # ``python -m amlip_qp``: the command line, nothing more
    "amlip_qp.__main__": Rule(("amlip_qp.cli",), HEAVY + ("numpy",)),
    # the command line stays light: handlers are imported by name when a subcommand runs
    # (view's keys for its --help: a leaf module of plain data; the walk options and their value checks: light)
    "amlip_qp.cli": Rule(
        (
            "amlip_qp.cli",
            "amlip_qp.exceptions",
            "amlip_qp.profiles",
            "amlip_qp.option_values",
            "amlip_qp.sim.scenarios.options",
            "amlip_qp.sim.loop.live_keys",
            "amlip_qp.sim.reports.gl",
        ),
        HEAVY + ("numpy",),
    ),
    # pure math: numpy (CasADi only when handed CasADi symbols)
    # profiles only for the CommandShaping parameters (a leaf module of plain dataclasses)
    "amlip_qp.alip": Rule(
        ("amlip_qp.alip", "amlip_qp.exceptions", "amlip_qp.messages", "amlip_qp.profiles"),
        ("mujoco", "pinocchio", "proxsuite", "qpsolvers", "scipy"),
    ),
    "amlip_qp.codegen": Rule(
        (
            "amlip_qp.alip",
            "amlip_qp.codegen",
            "amlip_qp.exceptions",
            "amlip_qp.output_paths",
            "amlip_qp.paths",
            "amlip_qp.profiles",
        ),
        ("mujoco", "pinocchio", "proxsuite", "qpsolvers"),
    ),
    # robots may import the pure alip package (output names, side flip, heading rotation)
    "amlip_qp.robots": Rule(
        ("amlip_qp.alip", "amlip_qp.robots", "amlip_qp.exceptions", "amlip_qp.paths", "amlip_qp.profiles"),
        ("casadi", "proxsuite", "qpsolvers"),
    ),
    "amlip_qp.qp": Rule(("amlip_qp.qp", "amlip_qp.exceptions"), ("mujoco", "pinocchio", "casadi")),
    # the control layer's own modules (the Tracker interface): never MuJoCo, never a job's package
    "amlip_qp.control": Rule(CONTROL_BASE + ("amlip_qp.control",), ("mujoco", "amlip_qp.qp") + CONTROL_JOBS),
    # the walking loop runs any tracker: it imports none, nor the QP layer (the step-timing MPC's
    # planner, which solves its own small QP, it builds through control.mpc)
    "amlip_qp.control.walking": Rule(
        CONTROL_BASE
        + ("amlip_qp.control.tracker", "amlip_qp.control.walking", "amlip_qp.estimation", "amlip_qp.control.mpc"),
        ("mujoco", "proxsuite", "qpsolvers", "amlip_qp.qp"),
    ),
    # the step-timing MPC planner on its runtime: the generated C and a small DAQP; its point-mass bench
    "amlip_qp.control.mpc": Rule(
        CONTROL_BASE + ("amlip_qp.qp", "amlip_qp.control.mpc"),
        ("mujoco", "pinocchio", "proxsuite", "amlip_qp.sim", "amlip_qp.control.walking"),
    ),
    # the base-state estimators: numpy, Pinocchio and the generated C of the codegen runtime; never MuJoCo
    "amlip_qp.estimation": Rule(
        (
            "amlip_qp.estimation",
            "amlip_qp.robots",
            "amlip_qp.exceptions",
            "amlip_qp.codegen",
            "amlip_qp.messages",
            "amlip_qp.profiles",
        ),
        ("mujoco", "proxsuite", "qpsolvers", "scipy", "amlip_qp.control", "amlip_qp.sim"),
    ),
    # the paper's tracker: no QP
    "amlip_qp.control.pbc": Rule(
        CONTROL_BASE
        + ("amlip_qp.control.tracker", "amlip_qp.control.pelvis_yaw", "amlip_qp.control.passive_symbolic")
        + ("amlip_qp.control.pbc",),
        ("mujoco", "proxsuite", "qpsolvers"),
    ),
    # the whole-body QP: may use the QP layer
    "amlip_qp.control.wbc": Rule(
        CONTROL_BASE
        + ("amlip_qp.qp", "amlip_qp.control.tracker", "amlip_qp.control.pelvis_yaw", "amlip_qp.control.wbc")
        + ("amlip_qp.control.passive_symbolic",),
        ("mujoco",),
    ),
    # the MuJoCo side, one subpackage per job (SIM_JOBS, lowest first): each imports only jobs below it
    "amlip_qp.sim": Rule((), HEAVY + ("numpy",)),
    "amlip_qp.sim.world": _sim_job(
        "amlip_qp.sim.world", ("amlip_qp.exceptions", "amlip_qp.profiles", "amlip_qp.robots", "amlip_qp.codegen")
    ),
    # the measurement (the messages' Measurement and ImuReading); never the controller
    "amlip_qp.sim.sensing": _sim_job(
        "amlip_qp.sim.sensing",
        ("amlip_qp.exceptions", "amlip_qp.profiles", "amlip_qp.messages"),
        ("amlip_qp.control",),
    ),
    # the closed loop runs the controller
    "amlip_qp.sim.loop": _sim_job(
        "amlip_qp.sim.loop",
        (
            "amlip_qp.exceptions",
            "amlip_qp.profiles",
            "amlip_qp.messages",
            "amlip_qp.alip",
            "amlip_qp.robots",
            "amlip_qp.control",
        ),
    ),
    # a scenario made a closed loop: the robot, a tracker, the controller, its estimator
    "amlip_qp.sim.scenarios": _sim_job(
        "amlip_qp.sim.scenarios",
        (
            "amlip_qp.exceptions",
            "amlip_qp.option_values",
            "amlip_qp.profiles",
            "amlip_qp.messages",
            "amlip_qp.alip",
            "amlip_qp.robots",
            "amlip_qp.control",
            "amlip_qp.estimation",
        ),
    ),
    # a finished run's summary, figures and video: plain data and the terrain's shape, never the controller
    "amlip_qp.sim.reports": _sim_job(
        "amlip_qp.sim.reports",
        ("amlip_qp.exceptions", "amlip_qp.alip"),
        ("amlip_qp.control", "amlip_qp.sim.scenarios"),
    ),
    # the commands' experiments sit on top of the library (and never import the sweep that runs some of them)
    "amlip_qp.experiments": Rule(("amlip_qp",), ("amlip_qp.sweep",)),
    # the sweep runs walks: the walk options and the harness, the profiles; a cell's options are typed
    # (sim.scenarios.options), never a command line parsed by the CLI's parser
    "amlip_qp.sweep": Rule(
        (
            "amlip_qp.sweep",
            "amlip_qp.sim",
            "amlip_qp.experiments",
            "amlip_qp.exceptions",
            "amlip_qp.output_paths",
            "amlip_qp.profiles",
        ),
        ("amlip_qp.control", "amlip_qp.qp", "amlip_qp.codegen", "amlip_qp.cli", "mujoco", "pinocchio"),
    ),
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PKG.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _units() -> dict[str, list[Path]]:
    """Every package (with its own modules, not its subpackages') and every top-level module."""
    units: dict[str, list[Path]] = {}
    for path in sorted(PKG.rglob("*.py")):
        if path.parent == PKG and path.name != "__init__.py":
            unit = _module_name(path)  # a top-level module is its own unit
        else:
            unit = _module_name(path.parent / "__init__.py")
        units.setdefault(unit, []).append(path)
    return units


def _imports(path: Path) -> set[str]:
    """Absolute names of every module ``path`` imports, at top level or inside functions."""
    package = _module_name(path.parent / "__init__.py")
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: resolve against this file's package
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1] + ([node.module] if node.module else []))
                names.update([base] if node.module else [f"{base}.{alias.name}" for alias in node.names])
            elif node.module:
                names.add(node.module)
    return names


def _matches(name: str, prefixes: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def _offenders(unit: str, files: list[Path]) -> list[str]:
    rule = RULES[unit]
    out = []
    for f in files:
        for name in sorted(_imports(f)):
            internal = name == "amlip_qp" or name.startswith("amlip_qp.")
            if (internal and not _matches(name, rule.may)) or _matches(name, rule.never):
                out.append(f"{f.relative_to(PKG.parent)} imports {name}")
    return out


def test_every_package_and_top_level_module_has_a_rule():
    units = _units()
    assert {"amlip_qp.alip", "amlip_qp.control", "amlip_qp.control.walking", "amlip_qp.control.pbc"} <= set(units)
    missing = sorted(set(units) - set(RULES))
    assert not missing, f"add a rule to RULES and a row to docs/ARCHITECTURE.md for: {missing}"


@pytest.mark.parametrize("unit", sorted(_units()))
def test_layers_import_only_what_the_contract_allows(unit):
    offenders = _offenders(unit, _units()[unit])
    assert not offenders, f"{unit} breaks the layer contract (docs/ARCHITECTURE.md): {offenders}"


def test_nothing_imports_the_sweep_but_itself():
    """The sweep is a leaf: the CLI runs its handler by name; no other module imports it."""
    offenders = [
        f"{f.relative_to(PKG.parent)} imports {name}"
        for unit, files in _units().items()
        if not _matches(unit, ("amlip_qp.sweep",))
        for f in files
        for name in _imports(f)
        if _matches(name, ("amlip_qp.sweep",))
    ]
    assert not offenders


def test_nothing_in_the_library_imports_the_experiments_or_the_command_line():
    """The experiments, the sweep and the command line sit above the library: no library module imports them."""
    offenders = [
        f"{f.relative_to(PKG.parent)} imports {name}"
        for unit, files in _units().items()
        if not _matches(unit, ABOVE_THE_LIBRARY)
        for f in files
        for name in _imports(f)
        if _matches(name, ABOVE_THE_LIBRARY)
    ]
    assert not offenders


def test_the_check_catches_violations(tmp_path, monkeypatch):
    pkg = tmp_path / "amlip_qp"
    (pkg / "control" / "walking").mkdir(parents=True)
    bad = pkg / "control" / "walking" / "m.py"
    bad.write_text(
        "from amlip_qp.control.pbc.tracker import PBCTracker\n"
        "from . import gait\n"
        "def f():\n    import mujoco\n    from amlip_qp.sim.loop.harness import Simulation\n"
    )
    monkeypatch.setattr(sys.modules[__name__], "PKG", pkg)
    found = _imports(bad)
    assert {
        "mujoco",
        "amlip_qp.sim.loop.harness",
        "amlip_qp.control.pbc.tracker",
        "amlip_qp.control.walking.gait",
    } <= found
    offenders = _offenders("amlip_qp.control.walking", [bad])
    assert len(offenders) == 3 and not any("gait" in o for o in offenders)


def test_the_command_line_imports_nothing_heavy():
    """``amlip-qp --help`` stays fast: importing the CLI loads no numpy, MuJoCo, Pinocchio or CasADi."""
    code = (
        "import sys, amlip_qp.cli; "
        "print(','.join(m for m in ('numpy', 'mujoco', 'pinocchio', 'casadi', 'scipy') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=PKG.parent)
    assert out.stdout.strip() == ""


def test_the_top_level_exports_are_lazy_and_from_the_allowed_modules():
    """``import amlip_qp`` loads nothing heavy; each name of ``__all__`` then comes from a module its rule allows."""
    code = (
        "import sys, amlip_qp; "
        "print(','.join(m for m in ('numpy', 'mujoco', 'pinocchio', 'casadi') if m in sys.modules)); "
        "print(' '.join(f'{n}:{getattr(amlip_qp, n).__module__}' for n in amlip_qp.__all__ if n != '__version__'))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=PKG.parent)
    heavy, exports = out.stdout.splitlines()
    assert heavy == ""
    modules = dict(item.split(":") for item in exports.split())
    assert {"load_robot", "Robot", "WalkingController", "QPTracker", "PBCTracker", "Command", "Measurement"} <= set(
        modules
    )
    assert modules["MujocoLoop"] == "amlip_qp.sim.loop.mujoco_loop"
    assert all(_matches(m, RULES["amlip_qp"].may) for m in modules.values()), modules
