"""The installed distribution holds the toolkit, not its development tools, and never imports them.

``pip install .`` installs the packages that ``[tool.setuptools.packages.find]`` of
``pyproject.toml`` finds; the package list here is setuptools' own expansion of that section
(:func:`setuptools.config.pyprojecttoml.read_configuration`), so a pattern that starts catching
``dev`` or a tool moved back under ``benchmarks`` shows up without building a wheel. The
development tools (the robustness probe, the stress sets, the verification scripts) live in
``dev/`` at the repository root; the second half reads the import graph of the shipped packages
(:mod:`import_graph`, from the source) and fails on any import of ``dev``.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest
from import_graph import LEVELS, PACKAGES, build_graph, package_of
from setuptools.config.pyprojecttoml import read_configuration

ROOT = Path(__file__).resolve().parents[1]

#: The development tools by module name: none of these may be installed under any name.
DEV_MODULES = ("robustness", "mutation", "stress", "generic_stress", "far_states", "public_lmi",
               "offline_timing", "blas_kernels")


def shipped_packages(root: Path = ROOT) -> list[str]:
    """The packages ``pip install`` puts in site-packages, as setuptools reads ``pyproject.toml``."""
    config = read_configuration(root / "pyproject.toml", expand=True)  # found from its folder
    return sorted(config["tool"]["setuptools"]["packages"])


def shipped_modules(root: Path = ROOT) -> list[str]:
    """Every module of the shipped packages (a package's ``.py`` files, not its sub-packages')."""
    out = []
    for package in shipped_packages(root):
        folder = root.joinpath(*package.split("."))
        out += [f"{package}.{path.stem}" for path in sorted(folder.glob("*.py"))]
    return out


def dev_imports(root: Path = ROOT, packages: tuple[str, ...] = PACKAGES) -> list[str]:
    """``module -> target (level)`` for every import of ``dev`` by a module of ``packages``."""
    graph = build_graph(root, (*packages, "dev"))
    return sorted(
        f"{module} -> {target} ({level})"
        for level in LEVELS
        for module, targets in graph.edges[level].items()
        for target in targets
        if package_of(target) == "dev" and package_of(module) != "dev"
    )


#: A string that names a module of ``dev`` (``importlib.import_module("dev.stress")``,
#: ``[python, "-m", "dev.robustness"]``): the imports the graph cannot see.
_DEV_NAME = re.compile(r"dev(\.\w+)*")


def dev_names_in_strings(root: Path = ROOT, packages: tuple[str, ...] = PACKAGES) -> list[str]:
    """``file: 'string'`` for every string constant of ``packages`` that is a module name in ``dev``."""
    found = []
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Constant) and isinstance(node.value, str) \
                        and _DEV_NAME.fullmatch(node.value):
                    found.append(f"{path.relative_to(root).as_posix()}: {node.value!r}")
    return found


def test_the_distribution_holds_the_toolkit() -> None:
    packages = shipped_packages()
    assert set(PACKAGES) <= set(packages)
    for expected in ("lmi.ipm.kernels", "benchmarks.core", "benchmarks.timing", "benchmarks.suites",
                     "rmpc.laws.wheel", "models.flexible"):
        assert expected in packages
    assert "benchmarks.cli" in shipped_modules()  # the ``rmpc`` command


def test_the_distribution_holds_the_c_core() -> None:
    """The C sources of :mod:`lmi.ccore` are package data (``write_solver`` copies them from the
    installed package): every ``.c`` and ``.h`` there matches a pattern of ``lmi``'s."""
    config = read_configuration(ROOT / "pyproject.toml", expand=True)
    assert "lmi.ccore" in config["tool"]["setuptools"]["packages"]
    patterns = config["tool"]["setuptools"]["package-data"]["lmi"]
    sources = sorted(p.relative_to(ROOT / "lmi").as_posix() for p in (ROOT / "lmi" / "ccore").glob("*.[ch]"))
    assert {"ccore/ipm.c", "ccore/ipm.h", "ccore/dense.c", "ccore/dense.h", "ccore/driver.c"} <= set(sources)
    assert [s for s in sources if not any(Path(s).match(p) for p in patterns)] == []


def test_the_distribution_holds_no_development_tool() -> None:
    packages = shipped_packages()
    assert [p for p in packages if package_of(p) not in PACKAGES] == []
    assert not [p for p in packages if p.rsplit(".", 1)[-1] in DEV_MODULES], packages
    modules = shipped_modules()
    assert not [m for m in modules if m.rsplit(".", 1)[-1] in DEV_MODULES], modules


def test_the_development_tools_are_in_dev() -> None:
    for name in ("robustness/__init__.py", "robustness/__main__.py", "stress.py", "generic_stress.py",
                 "far_states.py", "public_lmi.py", "offline_timing.py", "blas_kernels.py"):
        assert (ROOT / "dev" / name).is_file(), name
    assert not (ROOT / "benchmarks" / "mutation").exists()


def test_no_shipped_module_imports_dev() -> None:
    assert dev_imports() == []
    assert dev_names_in_strings() == []


def test_the_checks_fail_on_what_they_guard(tmp_path: Path) -> None:
    """A tool moved back under ``benchmarks``, a pattern that finds ``dev``, an import of ``dev``."""
    (tmp_path / "benchmarks" / "robustness").mkdir(parents=True)
    (tmp_path / "benchmarks" / "__init__.py").write_text("")
    (tmp_path / "benchmarks" / "robustness" / "__init__.py").write_text("")
    (tmp_path / "benchmarks" / "stress.py").write_text("")
    (tmp_path / "benchmarks" / "cli.py").write_text(
        "import subprocess\n\ndef run():\n    from dev.stress import make_problem\n"
        "    subprocess.run(['python', '-m', 'dev.robustness'])\n"
    )
    (tmp_path / "dev").mkdir()
    (tmp_path / "dev" / "__init__.py").write_text("")
    (tmp_path / "dev" / "stress.py").write_text("def make_problem(): ...\n")
    (tmp_path / "pyproject.toml").write_text(
        '[project]\nname = "x"\nversion = "0"\n'
        '[tool.setuptools.packages.find]\ninclude = ["benchmarks*", "dev*"]\n'
    )
    packages = shipped_packages(tmp_path)
    assert packages == ["benchmarks", "benchmarks.robustness", "dev"]
    assert {"benchmarks.stress", "dev.stress"} <= set(shipped_modules(tmp_path))
    assert dev_imports(tmp_path, ("benchmarks",)) == ["benchmarks.cli -> dev.stress (function)"]
    assert dev_names_in_strings(tmp_path, ("benchmarks",)) == ["benchmarks/cli.py: 'dev.robustness'"]


@pytest.mark.parametrize("text", ["dev", "dev.stress", "dev.robustness.cli"])
def test_dev_module_names(text: str) -> None:
    assert _DEV_NAME.fullmatch(text)


@pytest.mark.parametrize("text", ["device", "dev/stress.py", "python -m dev.stress", "developer"])
def test_not_dev_module_names(text: str) -> None:
    assert not _DEV_NAME.fullmatch(text)
