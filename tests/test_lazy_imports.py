"""Importing the toolkit's packages loads none of the heavy libraries; using a feature loads its own.

``import rmpc`` took 4-5 s when it imported every controller, and with them python-control,
matplotlib, scipy's signal and statistics packages and numba. The packages' public names are
now imported on first use (:mod:`toolkit_common.lazy`), python-control, scipy's integrators
and the interior-point solver's numba kernels where they are used. Speed is machine-dependent
and not asserted here; what is asserted is which modules a fresh interpreter holds after each
step, run in a subprocess (the test process has imported everything already).
"""

from __future__ import annotations

import ast
import importlib
import json
import os
import pkgutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.lazy import lazy_exports

ROOT = Path(__file__).resolve().parents[1]

#: Deferred: none of these may be imported by importing the packages or taking their public names.
HEAVY = ("control", "matplotlib", "cvxpy", "numba", "dask", "rich", "scipy.signal", "scipy.stats",
         "scipy.integrate")

#: The packages whose ``__init__`` loads its names on first use.
LAZY_PACKAGES = ("rmpc", "models", "lmi", "lmi.ipm.kernels")


def _modules_after(steps: list[str], env: dict[str, str] | None = None) -> list[list[str]]:
    """Run ``steps`` in order in a fresh interpreter; after each, the ``HEAVY`` modules loaded."""
    script = textwrap.dedent(f"""
        import json, sys
        HEAVY = {HEAVY!r}
        seen = []
        for step in {steps!r}:
            exec(step)
            seen.append([m for m in HEAVY if m in sys.modules])
        print(json.dumps(seen))
    """)
    out = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True,
                         timeout=600, env={**os.environ, **(env or {})}, check=False)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_importing_the_packages_and_every_public_name_loads_no_heavy_module() -> None:
    steps = ["import rmpc", "import models", "import lmi", "import lmi.ipm",
             "from rmpc import *", "from models import *", "from lmi import *",
             "import rmpc.mpc, rmpc.laws.flexible, rmpc.sim, rmpc.qp, models.flexible"]
    seen = _modules_after(steps)
    assert dict(zip(steps, seen, strict=True)) == {step: [] for step in steps}


def test_each_deferred_module_is_imported_by_the_feature_that_uses_it() -> None:
    setup = ("import numpy as np; from models import RigidSatellite, FlexibleSatellite; "
             "sat = RigidSatellite.paper_p(); "
             "plant = sat.polytope(sat.initial_state(), dt=0.1, spread=0.3, mode='scalar')")
    steps = [
        setup,
        "from rmpc.sim.integrators import DOP853\nDOP853().advance(None, lambda t, x: -x, np.ones(2), 0, 1)",
        "import rmpc; rmpc.LQR(plant, np.eye(6), np.eye(3))",
        "import lmi; lmi.BlockLMISolver([1.0], [(-np.eye(2), -np.eye(2)[None])])",
        "lmi.KothareProblem(plant.A, plant.B, np.eye(6), np.eye(3), u_max=1.0, backend='cvxpy')",
    ]
    seen = [set(s) for s in _modules_after(steps, env={"RMPC_QUIET": "1"})]
    assert seen[0] == set()
    assert seen[1] == {"scipy.integrate"}                    # the adaptive integrator: solve_ivp
    assert {"control", "matplotlib"} <= seen[2] - seen[1]    # the LQR gain: python-control
    assert "numba" in seen[3] - seen[2]                      # the interior-point solver's kernels
    assert "cvxpy" in seen[4] - seen[3]                      # the cvxpy back-end of Kothare's problem
    assert not {"dask", "rich"} & seen[4]                    # only the benchmarks use these


@pytest.mark.parametrize("package", LAZY_PACKAGES)
def test_every_listed_name_resolves_to_what_its_module_defines(package: str) -> None:
    pkg = importlib.import_module(package)
    exports = pkg._EXPORTS
    listed = {name for names in exports.values() for name in names}
    assert listed == set(pkg.__all__)
    assert set(pkg.__all__) <= set(dir(pkg))
    for module, names in exports.items():
        for name in names:
            assert getattr(pkg, name) is getattr(importlib.import_module(module), name), name
    # a name listed may not be a submodule too: importing the submodule would replace it
    submodules = {m.name for m in pkgutil.iter_modules(pkg.__path__)}
    assert listed & submodules == set()
    with pytest.raises(AttributeError, match=f"module '{package}' has no attribute 'no_such_name'"):
        pkg.no_such_name  # noqa: B018


@pytest.mark.parametrize("package", LAZY_PACKAGES)
def test_the_type_checking_imports_list_the_same_names_as_the_lazy_table(package: str) -> None:
    # type checkers and the import-graph test read the imports under TYPE_CHECKING, the run
    # time reads _EXPORTS: they must agree
    path = ROOT / Path(*package.split(".")) / "__init__.py"
    tree = ast.parse(path.read_text())
    guarded = next(n for n in tree.body if isinstance(n, ast.If) and ast.unparse(n.test) == "TYPE_CHECKING")
    static = {(n.module, a.name) for n in guarded.body if isinstance(n, ast.ImportFrom) for a in n.names}
    exports = importlib.import_module(package)._EXPORTS
    assert static == {(m, name) for m, names in exports.items() for name in names}


def test_lazy_exports_refuses_a_name_listed_twice_and_unknown_names() -> None:
    with pytest.raises(InvalidArgumentError, match=r"'x' under 'a\.b' and 'a\.c'"):
        lazy_exports("pkg", {"a.b": ("x",), "a.c": ("x", "y")})
    get, names = lazy_exports("toolkit_common", {"toolkit_common.status": ("STATUS_TABLE",)})
    assert "STATUS_TABLE" in names()
    with pytest.raises(AttributeError, match="module 'toolkit_common' has no attribute 'STATUS'"):
        get("STATUS")
