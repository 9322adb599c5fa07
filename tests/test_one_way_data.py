"""Data flows one way: the controller updates its kinematics, trackers only read it and return what
they computed; no module writes into another's kinematics object or replaces another object's methods."""

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from amlip_qp.control.pbc.tracker import PBCTracker
from amlip_qp.control.tracker import Tracker
from amlip_qp.control.wbc.tracker import QPTracker
from amlip_qp.messages import Command, Measurement
from amlip_qp.robots import load_robot

PKG = Path(__file__).resolve().parents[1] / "amlip_qp"
#: The kinematics' own package: the only code that may write into a kinematics object.
OWNER = PKG / "robots"
#: Names that hold a kinematics object in the library (``kin``, ``self.kin``, ``kinematics``, ``k0``...).
KIN_NAME = re.compile(r"^(kin|kinematics|k0)$|_kin$|^kin_")
#: Methods that would put something into another object.
STORE_METHOD = re.compile(r"^(store|set|put|install|write|swap)")


def _is_kin(node: ast.AST) -> bool:
    if isinstance(node, ast.Name):
        return bool(KIN_NAME.search(node.id))
    return isinstance(node, ast.Attribute) and bool(KIN_NAME.search(node.attr))


def _written_into_kin(target: ast.AST) -> bool:
    """Whether an assignment to ``target`` writes into a kinematics object (an attribute of it, or of
    anything it holds, or an element of its arrays)."""
    while isinstance(target, ast.Subscript):
        target = target.value
    while isinstance(target, ast.Attribute):
        target = target.value
        if _is_kin(target):
            return True
    return False


def backward_writes(source: str) -> list[str]:
    """The lines of ``source`` that write into a kinematics object: an assignment into it (or its
    ``output_map``), ``setattr`` on it, or a call of a store-like method of it."""
    found = []
    for node in ast.walk(ast.parse(source)):
        targets: list[ast.AST] = []
        if isinstance(node, ast.Assign):
            targets = list(node.targets)
        elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
            targets = [node.target]
        for t in targets:
            for leaf in ast.walk(t):  # tuple targets too
                if (isinstance(leaf, (ast.Attribute, ast.Subscript)) and _written_into_kin(leaf)) or (
                    isinstance(leaf, ast.Attribute) and leaf.attr == "output_map"
                ):
                    found.append(f"{node.lineno}: {ast.unparse(node)}")
        if isinstance(node, ast.Call):
            fn = node.func
            if isinstance(fn, ast.Name) and fn.id == "setattr" and node.args and _is_kin(node.args[0]):
                found.append(f"{node.lineno}: {ast.unparse(node)}")
            if isinstance(fn, ast.Attribute) and _is_kin(fn.value) and STORE_METHOD.search(fn.attr):
                found.append(f"{node.lineno}: {ast.unparse(node)}")
    return sorted(set(found))


def test_no_module_writes_into_a_kinematics_object():
    offenders = []
    for path in sorted(PKG.rglob("*.py")):
        if OWNER in path.parents:
            continue
        rel = path.relative_to(PKG.parent).as_posix()
        offenders += [f"{rel}:{line}" for line in backward_writes(path.read_text())]
    assert offenders == [], "writes into a kinematics object:\n" + "\n".join(offenders)


def test_the_write_check_finds_writes():
    snippet = """
def build(self, kin, kinematics, robot):
    kin.store_outputs(stance, heading, (y, J, jdv))
    kinematics.output_map = CompiledOutputMap(robot)
    self.kin.q[0] = 1.0
    self.kin.data.M[:] = 0.0
    setattr(kin, "v", v)
    self.kin = RobotKinematics(robot)
    kin.update(q, v)
    y, J, jdv = kin.outputs(stance, heading)
"""
    found = backward_writes(snippet)
    assert [line.split(":")[0] for line in found] == ["3", "4", "5", "6", "7"], found


def _fingerprint(kin) -> dict:
    """Identity of everything the kinematics holds: its attributes, the entries of its dict caches and
    the parts of its tuple caches."""
    out = {}
    for name, value in vars(kin).items():
        out[name] = id(value)
        if isinstance(value, dict):
            out.update({(name, k): id(v) for k, v in value.items()})
        elif isinstance(value, tuple):
            out.update({(name, i): id(v) for i, v in enumerate(value)})
            for i, v in enumerate(value):
                if isinstance(v, tuple):
                    out.update({(name, i, j): id(w) for j, w in enumerate(v)})
    return out


class _Watched(Tracker):
    """Runs ``inner`` and checks that its compute left the kinematics as it found it: after the read
    the controller makes anyway (the outputs of the target's stance and heading), nothing it held was
    replaced (a cache first filled by a read of the tracker, ``None`` before, may appear), and the state
    ``(q, v)`` is unchanged."""

    def __init__(self, inner: Tracker):
        self.inner, self.name = inner, inner.name
        self.robot = inner.robot
        self.replaced: list = []
        self.results: list = []

    def compute(self, kin, target):
        primed = kin.outputs(target.stance, target.heading_rad)
        before, q, v = _fingerprint(kin), kin.q.copy(), kin.v.copy()
        was_none = {name for name, value in vars(kin).items() if value is None}
        result = self.inner.compute(kin, target)
        after = _fingerprint(kin)
        self.replaced += [k for k, i in before.items() if after.get(k) != i and k not in was_none]
        self.replaced += [k for k in after if k not in before and not isinstance(k, tuple)]
        assert np.array_equal(kin.q, q) and np.array_equal(kin.v, v)
        assert kin.outputs(target.stance, target.heading_rad) is primed
        self.results.append((result, primed))
        return result

    def reset(self):
        self.inner.reset()


def _tick_a_few_times(robot, tracker, ticks=6):
    from amlip_qp.control.walking.controller import WalkingController

    watched = _Watched(tracker)
    controller = WalkingController(robot, watched)
    gait = robot.profile.gait
    command = Command(
        step_time_s=gait.step_time_s, com_height_m=gait.com_height_m, clearance_m=gait.clearance_m, vx_mps=0.5
    )
    rng = np.random.default_rng(3)
    infos = []
    for k in range(ticks):
        v = rng.normal(0.0, 0.05, robot.nv)
        infos.append(controller.step(Measurement(k * controller.dt_s, robot.q_stand.copy(), v), command))
    return watched, infos


@pytest.mark.parametrize(
    "make",
    [
        QPTracker,
        lambda robot: QPTracker(robot, in_place_assembly=False),
        lambda robot: QPTracker(robot, compiled_build=False),
        PBCTracker,
    ],
    ids=["qp in place", "qp gathered", "qp python build", "pbc"],
)
def test_a_tracker_tick_leaves_the_kinematics_as_the_update_made_it(make):
    cassie = load_robot("cassie")
    watched, infos = _tick_a_few_times(cassie, make(cassie))
    assert len(watched.results) == len(infos) == 6
    assert watched.replaced == []


def test_the_controller_reports_the_outputs_the_qp_returns():
    """The in-place QP returns the output map h_0 it evaluated (to rounding the kinematics' own); the
    controller reports those, without asking the kinematics again."""
    cassie = load_robot("cassie")
    tracker = QPTracker(cassie)
    assert tracker.build_backend == "c-in-place"
    watched, infos = _tick_a_few_times(cassie, tracker)
    n, nv = len(cassie.profile.outputs), cassie.nv
    for (result, primed), info in zip(watched.results, infos):
        y, J, jdv = result.outputs
        assert y.shape == (n,) and J.shape == (n, nv) and jdv.shape == (n,)
        assert info.h is y
        for got, want in zip(result.outputs, primed):
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
            assert got is not want


def method_names(sources: list[str]) -> set[str]:
    """The names of the methods (not properties) defined in the classes of ``sources``."""
    return {
        item.name
        for source in sources
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.ClassDef)
        for item in node.body
        if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef))
        and not any("property" in ast.unparse(d) or "setter" in ast.unparse(d) for d in item.decorator_list)
    }


def replaced_methods(source: str, methods: set[str]) -> list[str]:
    """The lines of ``source`` that assign to an attribute named like one of ``methods`` on another
    object (``ctrl.tracker.compute = wrapper``): a module replacing another object's behaviour."""
    found = []
    for node in ast.walk(ast.parse(source)):
        for t in node.targets if isinstance(node, ast.Assign) else []:
            if (
                isinstance(t, ast.Attribute)
                and t.attr in methods
                and not (isinstance(t.value, ast.Name) and t.value.id in ("self", "cls"))
            ):
                found.append(f"{node.lineno}: {ast.unparse(node)}")
    return found


def test_no_module_replaces_another_objects_methods():
    paths = sorted(PKG.rglob("*.py"))
    methods = method_names([p.read_text() for p in paths])
    assert {"update", "compute", "step"} <= methods
    offenders = [
        f"{path.relative_to(PKG.parent).as_posix()}:{line}"
        for path in paths
        for line in replaced_methods(path.read_text(), methods)
    ]
    assert offenders == [], "methods replaced from outside:\n" + "\n".join(offenders)


def test_the_method_check_finds_a_replacement():
    snippet = """
def wrap(ctrl, kin, timed):
    update = kin.update
    kin.update = timed
    ctrl.tracker.compute = timed
    self.step = timed
    ctrl.gain = 2.0
"""
    found = replaced_methods(snippet, {"update", "compute", "step"})
    assert [line.split(":")[0] for line in found] == ["4", "5"]
