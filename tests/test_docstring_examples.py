"""Every Examples section in the packages' docstrings runs and prints what it shows.

One test per module listed in ``MODULES_WITH_EXAMPLES``, and one that compares that list with the
modules that have examples, both ways: a listed module whose examples were all deleted fails (it
used to turn into a silent skip), and a module that gains examples fails until it is listed.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

PACKAGES = ("models", "lmi", "rmpc", "benchmarks", "toolkit_common", "dev")

#: The modules whose docstrings hold examples (``>>>``), by their import name.
MODULES_WITH_EXAMPLES = (
    "benchmarks.baseline",
    "benchmarks.compare",
    "benchmarks.core.executors",
    "benchmarks.core.family",
    "benchmarks.core.folders",
    "benchmarks.core.jsonable",
    "benchmarks.core.metrics",
    "benchmarks.core.registry",
    "benchmarks.families.controller_options",
    "benchmarks.families.crmpc_options",
    "benchmarks.families.rmpc_forms",
    "benchmarks.core.scenario",
    "benchmarks.core.store",
    "benchmarks.core.schema",
    "benchmarks.core.publish",
    "benchmarks.core.suite",
    "benchmarks.core.sweep_spec",
    "benchmarks.families.flexible.controllers",
    "benchmarks.families.flexible.metrics",
    "benchmarks.families.mrp.family",
    "benchmarks.families.wheel.family",
    "benchmarks.families.wheel.plant",
    "benchmarks.core.progress",
    "benchmarks.reports.citations",
    "benchmarks.reports.measurement",
    "benchmarks.reports.figure_style",
    "benchmarks.reports.sections",
    "benchmarks.reports.tables",
    "benchmarks.suites.faults",
    "benchmarks.suites.faults_claims",
    "benchmarks.suites.flexible",
    "benchmarks.suites.flexible_claims",
    "benchmarks.suites.flexible_f5",
    "benchmarks.suites.flexible_report",
    "benchmarks.suites.methods_store",
    "benchmarks.suites.mrp",
    "benchmarks.suites.mrp_claims",
    "benchmarks.suites.paper",
    "benchmarks.suites.paper_claims",
    "benchmarks.timing.common",
    "benchmarks.timing.config",
    "benchmarks.timing.cpg_attempt",
    "benchmarks.timing.versus",
    "lmi.backends.ipm",
    "lmi.data",
    "lmi.forms.problem",
    "lmi.ipm.blocks",
    "lmi.ipm.kernels.eigen",
    "lmi.ipm.kernels.notice",
    "lmi.ipm.solver",
    "lmi.kothare",
    "lmi.ccore.generate",
    "lmi.ccore.runtime",
    "lmi.observer",
    "lmi.offline",
    "lmi.sdpa",
    "lmi.status",
    "models",
    "models.actuators",
    "models.attitude.euler",
    "models.attitude.euler_inverse",
    "models.attitude.mrp",
    "models.attitude.quaternion",
    "models.attitude.vectors",
    "models.flexible.parameters",
    "models.flexible.satellite",
    "models.flexible.scenario",
    "models.flexible.single_axis",
    "models.linear",
    "models.mrp.satellite",
    "models.mrp.scenarios",
    "models.mrp.spinning_disk",
    "models.mrp.tracking",
    "models.protocols",
    "models.rigid.satellite",
    "models.wheels.array",
    "models.wheels.faults",
    "models.wheels.noise",
    "models.wheels.satellite",
    "models.wheels.scenarios",
    "models.wheels.stage",
    "rmpc.analysis",
    "rmpc.analysis.region",
    "rmpc.controller",
    "rmpc.errors",
    "rmpc.estimators.linear",
    "rmpc.estimators.robust",
    "rmpc.export",
    "rmpc.io.design",
    "rmpc.io.registry",
    "rmpc.laws.flexible.adaptive_pd",
    "rmpc.laws.flexible.adaptive_smc",
    "rmpc.laws.flexible.attitude_pd",
    "rmpc.laws.flexible.csmc",
    "rmpc.laws.flexible.hybrid",
    "rmpc.laws.flexible.input_shaping",
    "rmpc.laws.flexible.lqr",
    "rmpc.laws.flexible.mtsmc",
    "rmpc.laws.flexible.nonlinear_pd",
    "rmpc.laws.flexible.robust_avc",
    "rmpc.laws.mrp.cf_backstepping",
    "rmpc.laws.mrp.command_filter",
    "rmpc.laws.mrp.mab",
    "rmpc.laws.mrp.neso",
    "rmpc.laws.mrp.tuning_function_ab",
    "rmpc.laws.wheel.adaptive_backstepping",
    "rmpc.mpc.adaptation",
    "rmpc.mpc.crmpc",
    "rmpc.mpc.fallback",
    "rmpc.mpc.gipc",
    "rmpc.mpc.lqr",
    "rmpc.mpc.mras",
    "rmpc.mpc.multistage",
    "rmpc.mpc.offline",
    "rmpc.mpc.robust_mpc",
    "rmpc.mpc.scenario_tree",
    "rmpc.mpc.scheduled",
    "rmpc.mpc.switching_runs",
    "rmpc.mpc.tube",
    "rmpc.mpc.tube_runs",
    "rmpc.qp",
    "rmpc.qp.clarabel_backend",
    "rmpc.qp.cvxpy_backend",
    "rmpc.qp.factory",
    "rmpc.qp.osqp_backend",
    "rmpc.qp.problem",
    "rmpc.qp.proxqp_backend",
    "rmpc.qp.reference",
    "rmpc.sets",
    "rmpc.sets.invariant",
    "rmpc.sets.polytope",
    "rmpc.sim.disturbances",
    "rmpc.sim.integrators",
    "rmpc.sim.plants",
    "rmpc.sim.rhs",
    "rmpc.sim.simulate",
    "rmpc.wrappers",
    "toolkit_common.interrupts",
    "toolkit_common.status",
    "toolkit_common.validation",
)


def _modules() -> list[str]:
    """Every module of the packages, the packages themselves included."""
    names = []
    for package in PACKAGES:
        pkg = importlib.import_module(package)
        names.append(package)
        for info in pkgutil.walk_packages(pkg.__path__, prefix=f"{package}."):
            names.append(info.name)
    return sorted(names)


def _examples(name: str) -> list[doctest.DocTest]:
    """The docstring tests with at least one example defined in module ``name``."""
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    return [t for t in finder.find(module, name) if t.examples]


def test_the_list_names_exactly_the_modules_with_examples() -> None:
    modules = _modules()
    with_examples = {name for name in modules if _examples(name)}
    listed = set(MODULES_WITH_EXAMPLES)
    assert len(listed) == len(MODULES_WITH_EXAMPLES), "MODULES_WITH_EXAMPLES names a module twice"
    assert listed <= set(modules), f"listed but not a module: {sorted(listed - set(modules))}"
    assert not listed - with_examples, (
        f"listed in MODULES_WITH_EXAMPLES but without examples: {sorted(listed - with_examples)}"
    )
    assert not with_examples - listed, (
        f"with examples but not in MODULES_WITH_EXAMPLES: {sorted(with_examples - listed)}"
    )


@pytest.mark.parametrize("name", MODULES_WITH_EXAMPLES)
def test_docstring_examples(name: str) -> None:
    tests = _examples(name)
    assert tests, f"{name} is listed in MODULES_WITH_EXAMPLES but its docstrings hold no example"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in tests:
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name}"
