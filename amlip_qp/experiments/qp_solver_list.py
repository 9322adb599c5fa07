"""The QP solvers ``amlip-qp bench qp`` compares: name, module, pip package, how to run it.

:data:`SOLVERS` lists every pip-installable solver that fits the tracker's
dense problems (about 32 variables, 15 equalities, 26 inequalities and a
box): the tracker's ProxSuite path and the solvers ``qpsolvers`` supports.
A solver whose module does not import is reported as not installed, with the
package that brings it (:func:`available`). The ``bench`` extra of
``pyproject.toml`` installs the open-source ones that install from pip.
eiquadprog-fast, TSID's solver, comes from pip as a C++ library without a
Python binding; the bench compiles a shim for it
(:mod:`amlip_qp.experiments.qp_runner_eiquadprog`) and reports it as not
usable, with the reason, where that cannot be done (e.g. no compiler).
TSID itself is not compared: its ``libtsid`` dependency has no wheel for
this platform and does not build from its source distribution through pip.

Left out: MOSEK (its pip package needs a licence file to solve anything),
COPT (its pip build stopped the process with an illegal instruction on the
development machine's CPU) and the ``qpsolvers`` backends without a package
on PyPI (HPIPM, qpOASES, NPPro) or built on JAX or a GPU (jaxopt, qpax, PDHCG).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass

from amlip_qp.exceptions import InputError
from amlip_qp.experiments import qp_runner_eiquadprog as eiquadprog
from amlip_qp.experiments import qp_runners as dense
from amlip_qp.experiments import qp_runners_sparse as sparse


@dataclass(frozen=True)
class SolverSettings:
    """What the runners are built with.

    Attributes:
        proxqp: The :class:`~amlip_qp.qp.solver.ProxQPSolver` arguments (the tracker's).
        eps_abs: Absolute tolerance handed to the iterative solvers that take one (the tracker's).
        eps_primal_inf: Primal infeasibility threshold of PIQP (the tracker's ProxQP's).
    """

    proxqp: dict
    eps_abs: float
    eps_primal_inf: float


@dataclass(frozen=True)
class SolverSpec:
    """One solver of the bench.

    Attributes:
        name: Name in the report and in ``--solvers``.
        module: The Python module it needs (imported to tell whether it is installed); ``None``
            for a solver without one, told by ``installed``.
        pip: The pip package that installs it.
        make: Builds the runner.
        backend: The ``qpsolvers`` backend name that must be available too (``None``: not through qpsolvers).
        installed: Whether the package is installed, for a solver without a Python module.
        unusable: Why an installed solver cannot run here (e.g. no compiler for its shim), or ``None``.
    """

    name: str
    module: str | None
    pip: str
    make: Callable[[SolverSettings], dense.Runner]
    backend: str | None = None
    installed: Callable[[], bool] | None = None
    unusable: Callable[[], str | None] | None = None


def _qpsolvers(name: str, module: str, pip: str, box_as_rows: bool = False) -> SolverSpec:
    return SolverSpec(name, module, pip, lambda s: sparse.QPSolversRunner(name, box_as_rows), backend=name)


#: Every solver compared, in report order; the first is the reference of the time ratios.
SOLVERS: tuple[SolverSpec, ...] = (
    SolverSpec("proxsuite-warm", "proxsuite", "proxsuite", lambda s: dense.ProxSuiteRunner(True, s.proxqp)),
    SolverSpec("proxsuite-init", "proxsuite", "proxsuite", lambda s: dense.ProxSuiteRunner(False, s.proxqp)),
    SolverSpec("daqp-hot", "daqp", "daqp", lambda s: dense.DAQPRunner(hot=True)),
    SolverSpec("daqp-hot-model", "daqp", "daqp", lambda s: dense.DAQPRunner(hot=True, model=True)),
    SolverSpec("daqp-tracker", "daqp", "daqp", lambda s: dense.DAQPTrackerRunner()),
    SolverSpec("daqp-cold", "daqp", "daqp", lambda s: dense.DAQPRunner(hot=False)),
    SolverSpec("daqp-eliminated", "daqp", "daqp", lambda s: dense.DAQPEliminatedRunner()),
    SolverSpec("piqp", "piqp", "piqp", lambda s: dense.PIQPRunner(s.eps_abs, s.eps_primal_inf)),
    SolverSpec("clarabel", "clarabel", "clarabel", lambda s: sparse.ClarabelRunner()),
    SolverSpec("qpalm", "qpalm", "qpalm", lambda s: sparse.QPALMRunner(s.eps_abs)),
    SolverSpec("quadprog", "quadprog", "quadprog", lambda s: dense.QuadprogRunner()),
    SolverSpec("qpmad", "pyqpmad", "pyqpmad", lambda s: dense.QPMADRunner()),
    SolverSpec(
        "eiquadprog",
        None,
        "eiquadprog",
        lambda s: eiquadprog.EiquadprogRunner(),
        installed=eiquadprog.installed,
        unusable=eiquadprog.unusable,
    ),
    SolverSpec("osqp", "osqp", "osqp", lambda s: sparse.OSQPRunner(s.eps_abs)),
    _qpsolvers("highs", "highspy", "highspy"),
    _qpsolvers("ecos", "ecos", "ecos", box_as_rows=True),  # ECOS takes no infinite bound
    _qpsolvers("cvxopt", "cvxopt", "cvxopt"),
    _qpsolvers("kvxopt", "kvxopt", "kvxopt"),
    _qpsolvers("scs", "scs", "scs"),
    _qpsolvers("sip", "sip_qp_python", "sip-qp-python"),
    _qpsolvers("qtqp", "qtqp", "qtqp"),
    _qpsolvers("qpswift", "qpSWIFT", "qpSWIFT"),
    _qpsolvers("gurobi", "gurobipy", "gurobipy"),
)

#: The solver every time ratio is taken against: the tracker's path.
REFERENCE = "proxsuite-warm"


def select(names: str | None, solvers: tuple[SolverSpec, ...] = SOLVERS) -> tuple[SolverSpec, ...]:
    """The solvers named in the comma-separated ``names`` (``None``: all), the reference always first.

    Raises:
        InputError: an unknown name.
    """
    if names is None:
        return solvers
    by_name = {s.name: s for s in solvers}
    wanted = [n.strip() for n in names.split(",") if n.strip()]
    unknown = [n for n in wanted if n not in by_name]
    if unknown or not wanted:
        what = f"unknown solver {unknown[0]!r}" if unknown else "no solver named"
        raise InputError(f"--solvers: {what}; choose from {', '.join(by_name)}")
    keep = {REFERENCE, *wanted}
    return tuple(s for s in solvers if s.name in keep)


def _installed(spec: SolverSpec) -> bool:
    """Whether ``spec``'s package is installed: its module imports (or its own test says so)."""
    if spec.module is None:
        return spec.installed is not None and spec.installed()
    try:
        importlib.import_module(spec.module)
    except Exception:  # an ImportError, or a broken build failing at import
        return False
    return True


def available(spec: SolverSpec) -> bool:
    """Whether ``spec`` can run: its package is installed (its module imports, and its ``qpsolvers``
    backend is registered), and nothing makes it unusable here."""
    if not _installed(spec):
        return False
    if spec.unusable is not None:
        return spec.unusable() is None
    if spec.backend is None:
        return True
    import qpsolvers

    return spec.backend in qpsolvers.available_solvers


def versions(specs: tuple[SolverSpec, ...] | list[SolverSpec]) -> dict[str, str]:
    """``{pip package: installed version}`` of ``specs`` (each package once)."""
    from importlib.metadata import PackageNotFoundError, version

    out: dict[str, str] = {}
    for spec in specs:
        try:
            out.setdefault(spec.pip, version(spec.pip))
        except PackageNotFoundError:
            out.setdefault(spec.pip, "unknown")
    return out


def missing_line(spec: SolverSpec) -> str:
    """The report's line for a solver that cannot run: not installed (and how to install it), or
    installed but unusable here (and why)."""
    if _installed(spec) and spec.unusable is not None:
        why = spec.unusable()
        if why is not None:
            return f"not usable: {spec.name} ({why})"
    return f"not installed: {spec.name} (pip install {spec.pip})"
