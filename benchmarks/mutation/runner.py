"""The mutation check: list the mutants, map lines to tests, run a seeded sample, classify each one.

The tests of a mutant (the rule the report states):

- a line inside a function: the tests that ran that line (any line of the mutant's span) in the
  map run, lines run by the fixtures a test uses counting as the test's;
- a line that runs on import (a module constant, a default value, a class body): the tests that
  ran any line inside a function of that module;
- a line inside a numba-compiled function (which a line tracer never sees): the tests that ran
  any line inside a function of the modules that import its module or its package, and the
  tests in test files that import its module or its package (they may call the kernel directly).

Only tests that passed in the map run are used. They run fastest first, with ``-x``, and the list
is cut where the map run's durations add up to ``max_test_seconds`` (the report gives, for each
mutant, how many of its tests ran). A mutant is *caught* when its run fails (a test fails, the
collection breaks, or the process crashes), *survived* when every test passes, or when no test
runs its line (``no test``), *timeout* when its run outlasts ``timeout_base + timeout_factor x``
the tests' durations, and *error* when pytest reports a usage error or runs no test.
"""

from __future__ import annotations

import ast
import hashlib
import json
import random
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.mutation.operators import OPERATORS, Mutant, find_mutants
from benchmarks.mutation.sandbox import Sandbox, run_child

__all__ = [
    "CheckConfig", "LineMap", "MutantResult", "list_mutants", "module_files", "run_check", "sample_mutants",
]


@dataclass
class CheckConfig:
    """What to mutate, which tests to run, and the budget.

    Attributes
    ----------
    root : Path
        The project (working files, never written).
    modules : list of str
        Dotted names of packages or modules to mutate (``lmi``, ``rmpc.mpc``, ``lmi.kothare``).
    tests : list of str
        Test files or folders, relative to ``root``, that the map run runs.
    out : Path
        Folder for ``map.json``, ``mutants.jsonl``, ``results.json`` and ``report.md``.
    max_mutants : int or None
        Size of the seeded sample (``None``: every mutant).
    seed : int
        Seed of the sample.
    operators : tuple of str
        Operator families to draw from.
    mutant_ids : list of str
        Run exactly these mutants (ids as the report prints them) instead of a sample.
    timeout_base, timeout_factor : float
        A mutant's run is killed after ``timeout_base + timeout_factor * d`` seconds, ``d`` being the
        map run's durations of the tests it runs.
    max_test_seconds : float or None
        Cut a mutant's test list where those durations add up to this (``None``: no cut).
    budget_minutes : float or None
        Start no new mutant after this long (the rest are reported as ``not run``).
    python : str
        Interpreter of the child processes.
    keep_sandbox : bool
        Leave the temporary copy on disk.
    """

    root: Path
    modules: list[str]
    tests: list[str]
    out: Path
    max_mutants: int | None = 100
    seed: int = 0
    operators: tuple[str, ...] = OPERATORS
    mutant_ids: list[str] = field(default_factory=list)
    timeout_base: float = 60.0
    timeout_factor: float = 3.0
    max_test_seconds: float | None = 120.0
    budget_minutes: float | None = None
    python: str = "python"
    keep_sandbox: bool = False


@dataclass
class MutantResult:
    """A mutant and what became of it."""

    mutant: Mutant
    status: str  # caught | survived | timeout | error | not run
    detail: str = ""
    tests_covering: int = 0
    tests_run: int = 0
    seconds: float = 0.0
    timeout: float = 0.0

    def to_json(self) -> dict[str, Any]:
        """A flat record: the mutant's fields, its id, and the outcome."""
        return {"id": self.mutant.id, **asdict(self.mutant), **{k: v for k, v in asdict(self).items()
                                                                 if k != "mutant"}}


def module_files(root: Path, modules: Sequence[str]) -> dict[str, str]:
    """Dotted module name -> file relative to ``root`` for every module in ``modules`` (packages expanded)."""
    found: dict[str, str] = {}
    for name in modules:
        base = root / Path(*name.split("."))
        if base.is_dir():
            files = sorted(p for p in base.rglob("*.py") if "__pycache__" not in p.parts)
        elif base.with_suffix(".py").is_file():
            files = [base.with_suffix(".py")]
        else:
            raise ValueError(f"--modules: {name!r} is neither a package nor a module under {root}")
        for file in files:
            rel = file.relative_to(root)
            parts = list(rel.with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            found[".".join(parts)] = rel.as_posix()
    return found


def list_mutants(root: Path, modules: Sequence[str], operators: Sequence[str] = OPERATORS) -> list[Mutant]:
    """Every mutant of the given modules with the given operators, in module and source order."""
    mutants: list[Mutant] = []
    for name, rel in module_files(root, modules).items():
        source = (root / rel).read_text(encoding="utf-8")
        mutants.extend(m for m in find_mutants(source, name, rel) if m.operator in operators)
    return mutants


def _imported_names(source: str) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def _wanted_names(module: str) -> set[str]:
    """``module`` and its package (not a top-level package): the imports that reach it."""
    parts = module.split(".")
    return {".".join(parts[:i]) for i in range(max(2, len(parts) - 1), len(parts) + 1)}


class LineMap:
    """Which tests ran which lines, read from the map run's output.

    Parameters
    ----------
    data : dict
        The plugin's ``--mutation-trace`` output.
    files : dict
        Dotted module name -> relative path of the modules that can be mutated.
    """

    def __init__(self, data: dict[str, Any], files: dict[str, str]) -> None:
        self.tests = [t for t in data["tests"] if t["passed"]]
        rel = dict(enumerate(data["files"]))
        self.lines: dict[tuple[str, int], set[int]] = {}
        for k, test in enumerate(self.tests):
            for index, line in test["lines"]:
                self.lines.setdefault((rel[index], line), set()).add(k)
        self.files = files
        self._function_lines: dict[str, set[int]] = {}
        self._importers: dict[str, set[str]] = {}

    def _module_tests(self, root: Path, path: str) -> set[int]:
        if path not in self._function_lines:
            tree = ast.parse((root / path).read_text(encoding="utf-8"))
            inside: set[int] = set()
            for node in ast.walk(tree):
                if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                    for stmt in node.body:
                        inside.update(range(stmt.lineno, (stmt.end_lineno or stmt.lineno) + 1))
            self._function_lines[path] = inside
        tests: set[int] = set()
        for line in self._function_lines[path]:
            tests |= self.lines.get((path, line), set())
        return tests

    def _importers_of(self, root: Path, module: str) -> set[str]:
        if not self._importers:
            for name, rel in self.files.items():
                self._importers[name] = _imported_names((root / rel).read_text(encoding="utf-8"))
        wanted = _wanted_names(module)
        return {self.files[name] for name, names in self._importers.items()
                if names & wanted and name != module}

    def tests_for(self, root: Path, mutant: Mutant) -> list[int]:
        """Indices into :attr:`tests` of the tests of ``mutant`` by the rule in the module docstring."""
        if mutant.scope == "function":
            found: set[int] = set()
            for line in range(mutant.line, mutant.end_line + 1):
                found |= self.lines.get((mutant.path, line), set())
        elif mutant.scope == "module":
            found = self._module_tests(root, mutant.path)
        else:
            found = set()
            for path in self._importers_of(root, mutant.module):
                found |= self._module_tests(root, path)
            found |= self._importing_tests(root, mutant.module)
        return sorted(found, key=lambda k: (self.tests[k]["duration"], k))

    def _importing_tests(self, root: Path, module: str) -> set[int]:
        """The tests in test files that import ``module`` or its package (they may call a compiled
        kernel directly, running no traced line)."""
        wanted = _wanted_names(module)
        files: dict[str, bool] = {}
        found: set[int] = set()
        for k, test in enumerate(self.tests):
            file = test["nodeid"].split("::")[0]
            if file not in files:
                path = root / file
                files[file] = path.is_file() and bool(
                    _imported_names(path.read_text(encoding="utf-8")) & wanted)
            if files[file]:
                found.add(k)
        return found


#: Changes when the map's contents change meaning (a cached map of another format is not reused).
_MAP_FORMAT = 2


def _source_key(tree: Path, tests: Sequence[str], files: dict[str, str]) -> str:
    digest = hashlib.sha256(json.dumps([_MAP_FORMAT, sorted(tests), sorted(files.values())]).encode())
    for path in sorted(tree.rglob("*.py")):
        digest.update(path.relative_to(tree).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _build_map(config: CheckConfig, box: Sandbox, files: dict[str, str], log: Callable[[str], None]) -> dict:
    key = _source_key(box.tree, config.tests, files)
    cached = config.out / "map.json"
    if cached.is_file():
        data = json.loads(cached.read_text(encoding="utf-8"))
        if data.get("key") == key:
            log(f"map: reusing {cached} ({len(data['tests'])} tests)")
            return {**data, "reused": True}
    targets = box.path / "targets.json"
    targets.write_text(json.dumps([str(box.tree / rel) for rel in files.values()]), encoding="utf-8")
    trace = box.path / "trace.json"
    log(f"map: running {' '.join(config.tests)} under the line tracer")
    args = ["-q", "--mutation-trace", str(trace), "--mutation-targets", str(targets), *config.tests]
    result = run_child(box.pytest_command(config.python, args), box.tree, box.env(), None)
    if not trace.is_file():
        raise RuntimeError(f"the map run wrote no map (exit {result.returncode}):\n{result.output[-3000:]}")
    data = json.loads(trace.read_text(encoding="utf-8"))
    data["files"] = [Path(f).relative_to(box.tree).as_posix() for f in data["files"]]
    data.update(key=key, seconds=result.seconds, returncode=result.returncode,
                summary=result.output.strip().splitlines()[-1:] if result.output.strip() else [])
    cached.write_text(json.dumps(data), encoding="utf-8")
    return data


_FAILED = re.compile(r"^(?:FAILED|ERROR) (\S+)", re.MULTILINE)


def _classify(returncode: int | None, output: str) -> tuple[str, str]:
    if returncode is None:
        return "timeout", ""
    if returncode == 0:
        return "survived", ""
    if returncode in (1, 2):
        failed = _FAILED.findall(output)
        return "caught", failed[0] if failed else ("collection failed" if returncode == 2 else "")
    if returncode < 0:
        return "caught", f"crashed (signal {-returncode})"
    tail = output.strip().splitlines()[-1] if output.strip() else ""
    return "error", f"exit {returncode}: {tail}"


def sample_mutants(mutants: list[Mutant], config: CheckConfig) -> list[Mutant]:
    """``config.mutant_ids`` if given, else ``config.max_mutants`` of them drawn with ``config.seed``."""
    if config.mutant_ids:
        by_id = {m.id: m for m in mutants}
        missing = [i for i in config.mutant_ids if i not in by_id]
        if missing:
            raise ValueError(f"--mutant: no such mutant {missing[0]!r} (ids as the report prints them)")
        return [by_id[i] for i in config.mutant_ids]
    if config.max_mutants is None or config.max_mutants >= len(mutants):
        return list(mutants)
    return random.Random(config.seed).sample(mutants, config.max_mutants)


def _hash_files(root: Path, files: dict[str, str]) -> str:
    digest = hashlib.sha256()
    for rel in sorted(files.values()):
        digest.update((root / rel).read_bytes())
    return digest.hexdigest()


def run_check(config: CheckConfig, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Run the mutation check and write its outputs into ``config.out``.

    Returns
    -------
    dict
        What ``results.json`` holds: the settings, the map run, the counts and every mutant's record.
        If interrupted, the mutants finished so far are written before ``KeyboardInterrupt`` propagates.
    """
    from benchmarks.mutation.report import project_commit, summarize, write_report

    start = time.perf_counter()
    root = config.root.resolve()
    commit = project_commit(root)  # the tree the sandbox copies, not the one at the end
    config.out.mkdir(parents=True, exist_ok=True)
    files = module_files(root, config.modules)
    before = _hash_files(root, files)
    every = list_mutants(root, config.modules, config.operators)
    chosen = sample_mutants(every, config)
    results: list[MutantResult] = []
    map_info: dict[str, Any] = {}
    journal = config.out / "mutants.jsonl"
    journal.write_text("", encoding="utf-8")
    interrupted = False
    try:
        with Sandbox(root, exclude=[config.out], keep=config.keep_sandbox) as box:
            data = _build_map(config, box, files, log)
            line_map = LineMap(data, files)
            map_info = {"seconds": data["seconds"], "reused": bool(data.get("reused")),
                        "tests": len(data["tests"]), "tests_passed": len(line_map.tests),
                        "summary": data.get("summary", [])}
            for i, mutant in enumerate(chosen):
                elapsed = time.perf_counter() - start
                if config.budget_minutes is not None and elapsed > 60.0 * config.budget_minutes:
                    results.extend(MutantResult(m, "not run", "budget spent") for m in chosen[i:])
                    break
                result = _run_one(config, box, line_map, mutant)
                results.append(result)
                with journal.open("a", encoding="utf-8") as fh:
                    fh.write(json.dumps(result.to_json()) + "\n")
                log(f"[{i + 1}/{len(chosen)}] {result.status:8s} {result.seconds:6.1f}s  {mutant.id}")
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        untouched = _hash_files(root, files) == before
        summary = summarize(config, every, results, map_info, time.perf_counter() - start,
                            interrupted=interrupted, untouched=untouched, commit=commit)
        write_report(config.out, summary)
    return summary


def _run_one(config: CheckConfig, box: Sandbox, line_map: LineMap, mutant: Mutant) -> MutantResult:
    covering = line_map.tests_for(box.tree, mutant)
    if not covering:
        return MutantResult(mutant, "survived", "no test runs it")
    chosen: list[int] = []
    total = 0.0
    for k in covering:
        duration = line_map.tests[k]["duration"]
        if chosen and config.max_test_seconds is not None and total + duration > config.max_test_seconds:
            break
        chosen.append(k)
        total += duration
    nodeids = [line_map.tests[k]["nodeid"] for k in chosen]
    select = box.path / "select.json"
    select.write_text(json.dumps(nodeids), encoding="utf-8")
    test_files = sorted({nodeid.split("::")[0] for nodeid in nodeids})
    packages = sorted({m.split(".")[0] for m in config.modules})
    timeout = config.timeout_base + config.timeout_factor * total
    if mutant.scope == "compiled":
        timeout += config.timeout_base  # its kernels are compiled afresh
    args = ["-x", "-q", "-rfE", "--mutation-select", str(select), "--mutation-root", str(box.tree),
            "--mutation-packages", ",".join(packages), *test_files]
    with box.mutated(mutant) as env:
        child = run_child(box.pytest_command(config.python, args), box.tree, env, timeout)
    status, detail = _classify(child.returncode, child.output)
    return MutantResult(mutant, status, detail, len(covering), len(chosen), round(child.seconds, 2),
                        round(timeout, 1))
