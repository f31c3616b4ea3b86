"""Sweep files that set the robust MPC's forms, a read-only ``--out``, a form over too many vertices.

Each form option of :class:`rmpc.RMPC` (``lyapunov``, ``cost``, ``free_moves``, ``saturation``,
``soft``, ``disturbance``, ``certificate_tol``, ``on_failure``) is tried in a sweep file's
``settings`` with a good value (the tiny sweep must run: ``either``) and with bad values (refused
with exit 2, the message naming the key path ``base.settings.<name>`` down to the wrong entry);
so are RMPC's ``solver_options`` and OfflineRMPC's ``cost``.
"""

from __future__ import annotations

import os
from collections.abc import Callable

import numpy as np

from dev.robustness.probe import Expect, Probe

FORM_SWEEP = """name = "forms"
[base]
plant = "linear"
controller = "RMPC"
saturation = "constraint"
duration = 0.03
[base.settings]
{settings}
"""
"""One RMPC case of three samples on the linear satellite, with ``{settings}`` in its settings."""

SWEEP_ARGV = (
    "bench", "sweep", "--config", "{tmp}/sweep.toml", "--out", "{tmp}/out", "--workers", "0", "--no-progress",
)
"""``rmpc`` arguments of a sweep of ``{tmp}/sweep.toml`` into ``{tmp}/out``, run in-process."""

_E_ROWS = "[[0.0], [0.0], [0.0], [1.0], [0.0], [0.0]]"
"""A disturbance on the roll rate of the 6-state satellite (E is 6 x 1)."""

_MUST_RUN = ("(a good value: the sweep must run)",)
"""The ``names`` of a good value: no refusal contains them, so a refusal is not ``clear`` (the verdicts
take a clear refusal of an ``either`` input as a good answer) and only a run that exits 0 is."""

#: (label, settings lines, names a clear refusal contains, expect)
_CASES: tuple[tuple[str, str, tuple[str, ...], Expect], ...] = (
    ("lyapunov vertex", 'lyapunov = "vertex"', _MUST_RUN, "either"),
    ("lyapunov vertex_pairs", 'lyapunov = "vertex_pairs"', _MUST_RUN, "either"),
    ("lyapunov bad", 'lyapunov = "quartic"', ("settings.lyapunov: expected one of",), "error"),
    ("lyapunov number", "lyapunov = 3", ("settings.lyapunov: expected one of",), "error"),
    ("cost nominal", 'cost = "nominal"', _MUST_RUN, "either"),
    ("cost bad", 'cost = "average"', ("settings.cost: expected one of",), "error"),
    ("cost nominal with vertex", 'cost = "nominal"\nlyapunov = "vertex"', ("settings.cost, ",), "error"),
    ("free_moves 1", "free_moves = 1", _MUST_RUN, "either"),
    ("free_moves 2", "free_moves = 2", ("settings.free_moves: expected 0 or 1",), "error"),
    ("free_moves true", "free_moves = true", ("settings.free_moves: expected",), "error"),
    ("saturation auxiliary", 'saturation = "auxiliary"\ninput_constraint = "peak"', _MUST_RUN,
     "either"),
    ("saturation auxiliary ellipsoid", 'saturation = "auxiliary"', ("settings.input_constraint",), "error"),
    ("saturation bad", 'saturation = "clip"', ("settings.saturation: expected one of",), "error"),
    ("soft u", "soft = {u = 100.0}", _MUST_RUN, "either"),
    # the largest weights: a run, or a clear refusal at the forms' stated limit (lmi.forms MAX_SOFT_WEIGHT)
    ("soft u 1e308", "soft = {u = 1e308}", ("settings.soft.u: expected a weight <=",), "either"),
    ("soft negative", "soft = {u = -1.0}", ("settings.soft.u",), "error"),
    ("soft nan", "soft = {u = nan}", ("settings.soft.u",), "error"),
    ("soft string", 'soft = {u = "big"}', ("settings.soft.u",), "error"),
    ("soft y", "soft = {y = 1.0}", ("settings.soft: expected no \"y\"",), "error"),
    ("soft unknown key", "soft = {x = 1.0}", ("settings.soft: expected weights",), "error"),
    ("soft empty", "soft = {}", ("settings.soft: expected at least one",), "error"),
    ("soft number", "soft = 5", ("settings.soft: expected a table",), "error"),
    ("disturbance", f"disturbance = {{E = {_E_ROWS}, w_max = 0.01}}", _MUST_RUN, "either"),
    ("disturbance list", f"disturbance = [{_E_ROWS}, 0.01, 0.5]", _MUST_RUN, "either"),
    ("disturbance E shape", "disturbance = {E = [[1.0]], w_max = 0.01}", ("settings.disturbance.e",),
     "error"),
    ("disturbance w_max negative", f"disturbance = {{E = {_E_ROWS}, w_max = -1.0}}",
     ("settings.disturbance.w_max",), "error"),
    ("disturbance lam 1", f"disturbance = {{E = {_E_ROWS}, w_max = 0.01, lam = 1.0}}",
     ("settings.disturbance.lam",), "error"),
    ("disturbance no w_max", f"disturbance = {{E = {_E_ROWS}}}", ("settings.disturbance.w_max",), "error"),
    ("disturbance unknown key", f"disturbance = {{E = {_E_ROWS}, w_max = 0.1, q = 1}}",
     ("settings.disturbance.q",), "error"),
    ("disturbance with free_moves", f"disturbance = {{E = {_E_ROWS}, w_max = 0.01}}\nfree_moves = 1",
     ("settings.free_moves, ",), "error"),
    ("on_failure raise", 'on_failure = "raise"', _MUST_RUN, "either"),
    ("on_failure bad", 'on_failure = "ignore"', ("settings.on_failure: expected one of",), "error"),
    ("certificate_tol 0", "certificate_tol = 0.0", ("settings.certificate_tol: expected a number > 0",),
     "error"),
    ("solver_options core numba", 'solver_options = {core = "numba", max_iter = 60}', _MUST_RUN, "either"),
    ("solver_options core bad", 'solver_options = {core = "fortran"}',
     ("settings.solver_options.core: expected one of",), "error"),
    ("solver_options unknown", "solver_options = {bogus = 1}",
     ("settings.solver_options: expected ipm settings",), "error"),
    ("solver_options max_iter 0", "solver_options = {max_iter = 0}",
     ("settings.solver_options.max_iter: expected an integer >= 1",), "error"),
    ("solver_options number", "solver_options = 5", ("settings.solver_options: expected a table",), "error"),
    ("solver_options nested", "solver_options = {core = [1]}", ("settings.solver_options.core: expected",),
     "error"),
    ("solver_options clarabel core", 'backend = "clarabel"\nsolver_options = {core = "c"}',
     ("settings.solver_options: expected clarabel settings",), "error"),
)

OFFLINE_SWEEP = FORM_SWEEP.replace('controller = "RMPC"', 'controller = "OfflineRMPC"')
"""One OfflineRMPC case of three samples on the linear satellite, with ``{settings}`` in its settings."""

#: (label, settings lines, names a clear refusal contains, expect) of OfflineRMPC
_OFFLINE_CASES: tuple[tuple[str, str, tuple[str, ...], Expect], ...] = (
    ("cost nominal", 'cost = "nominal"\nn_ellipsoids = 3', _MUST_RUN, "either"),
    ("cost bad", 'cost = "average"', ("settings.cost: expected one of",), "error"),
)


def _write(name: str, text: str) -> Callable[[str], None]:
    def setup(tmp: str) -> None:
        with open(os.path.join(tmp, name), "w") as handle:
            handle.write(text)

    return setup


def _read_only_out(tmp: str) -> None:
    """A sweep file and an ``--out`` folder nobody can write (``/proc/self`` when run as root)."""
    _write("sweep.toml", FORM_SWEEP.format(settings=""))(tmp)
    out = os.path.join(tmp, "ro")
    os.makedirs(out)
    os.chmod(out, 0o555)


def _read_only_argv() -> tuple[str, ...]:
    out = "{tmp}/ro" if os.geteuid() != 0 else "/proc/self"  # root writes through a mode of 0o555
    return ("bench", "sweep", "--config", "{tmp}/sweep.toml", "--out", out, "--workers", "0", "--no-progress")


def _many_vertices() -> object:
    """An RMPC over 256 vertices with one Lyapunov matrix per vertex pair: too big, refused by size."""
    from models import PolytopicModel
    from rmpc import RMPC

    b = np.array([[0.0], [0.1]])
    vertices = [(np.array([[1.0, 0.1], [0.0, 1.0 + 0.001 * k]]), b) for k in range(256)]
    plant = PolytopicModel(vertices=vertices, dt=0.1)
    return RMPC(plant, np.eye(2), np.eye(1), u_max=1.0, lyapunov="vertex_pairs")


def sweep_probes() -> list[Probe]:
    """Every probe of the sweep forms, ``--out`` and the form size messages."""
    probes = [
        Probe(
            f"cli:sweep form {label}",
            "cli",
            names,
            argv=SWEEP_ARGV,
            setup=_write("sweep.toml", FORM_SWEEP.format(settings=body)),
            expect=expect,
            kind="sweep form",
        )
        for label, body, names, expect in _CASES
    ]
    probes += [
        Probe(
            f"cli:sweep OfflineRMPC {label}",
            "cli",
            names,
            argv=SWEEP_ARGV,
            setup=_write("sweep.toml", OFFLINE_SWEEP.format(settings=body)),
            expect=expect,
            kind="sweep form",
        )
        for label, body, names, expect in _OFFLINE_CASES
    ]
    probes += [
        Probe(
            "cli:sweep --out read-only",
            "cli",
            ("not writable",),
            argv=_read_only_argv(),
            setup=_read_only_out,
            kind="out",
        ),
        Probe(
            "cli:sweep --out under /proc",
            "cli",
            ("argument --out",),
            argv=("bench", "sweep", "--config", "{tmp}/sweep.toml", "--out", "/proc/rmpc-probe/out",
                  "--workers", "0", "--no-progress"),
            setup=_write("sweep.toml", FORM_SWEEP.format(settings="")),
            kind="out",
        ),
        Probe(
            "RMPC.lyapunov:vertex_pairs over 256 vertices",
            "api",
            ("256 vertices",),
            call=_many_vertices,
            kind="size",
        ),
    ]
    return probes
