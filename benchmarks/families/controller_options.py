"""The solve options of GIPC and OfflineRMPC as settings of a sweep, checked by the constructors.

``settings.solver_options`` of a family's ``"GIPC"`` is a table of the QP back-end's settings
(``{eps_abs = 1e-6, max_iter = 2000}`` for ``backend = "proxqp"``); each table is checked by
:class:`rmpc.GIPC` itself with the case's ``backend`` (:func:`check_gipc_solver_options`), its
error naming the key path ``settings.solver_options.<name>``. The table's own shape (a table of
scalars) is checked by the setting check of :mod:`benchmarks.families.rmpc_forms`. Left out of a
case's record at its default (``None``), so no case id changes.

OfflineRMPC's ``backend`` (``"ipm"``, ``"clarabel"``, ``"cvxpy"``), ``solver`` (the cvxpy
solver with ``backend = "cvxpy"``), ``solver_options``, ``certificate_tol`` and ``path``
(``"ray"`` or ``"trajectory"``: how the design states are generated; not a file) (rigid and
flexible families) are checked by :class:`rmpc.OfflineRMPC` itself (:func:`check_offline_options`)
and left out of a record at the constructor's defaults (:data:`OFFLINE_DEFAULTS`).

Examples
--------
>>> from benchmarks.core.scenario import Scenario
>>> sc = Scenario.from_dict({"controller": "GIPC", "settings": {"solver_options": {"max_iter": 50}}})
>>> dict(sc.settings["solver_options"]), "solver_options" in Scenario.from_dict(
...     {"controller": "GIPC"}).to_dict()["settings"]
({'max_iter': 50}, False)
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

from benchmarks.families.rmpc_forms import raise_at_key_path
from toolkit_common.errors import ArgumentTypeError, ConfigError, InvalidArgumentError

__all__ = [
    "OFFLINE_DEFAULTS", "OFFLINE_QUIET", "check_gipc_solver_options", "check_offline_options", "options_path",
]


def options_path(argument: str, where: str) -> str | None:
    """The key path of a back-end's error, or None when the error is not about the options.

    ``"ProxQPSettings.eps_abs"`` -> ``<where>.eps_abs``; ``"settings 'eps'"`` (an unknown
    setting, named in the error's ``found``) -> ``<where>``.
    """
    named = re.match(r"^\w+Settings\.(\w+)$", argument)
    if named is not None:
        return f"{where}.{named.group(1)}"
    if argument.startswith("settings ") or argument.startswith("solver_options"):
        return where
    return None


def check_gipc_solver_options(settings: Mapping[str, Any], where: str) -> None:
    """``settings.backend`` and ``settings.solver_options`` checked by :class:`rmpc.GIPC` itself.

    The family's ``backend`` choices are shared with its RMPC (``"ipm"`` is one of them): a GIPC
    with a back-end it does not take is refused here, when the sweep file is read, naming
    ``<where>.backend``, not when its cases run.

    A GIPC is built on a one-vertex, one-state stand-in (the check of the options does not depend
    on the model); its error names the key path ``<where>.solver_options.<name>``.

    Raises
    ------
    ConfigError
        Naming the option the backend refuses.
    """
    options = settings.get("solver_options")
    from models import PolytopicModel
    from rmpc.mpc.gipc import GIPC

    stand_in = PolytopicModel([(np.array([[0.5]]), np.array([[1.0]]))], dt=1.0)
    try:
        GIPC(stand_in, Np=2, Nc=1, backend=settings["backend"],
             solver_options=None if options is None else dict(options))
    except (InvalidArgumentError, ArgumentTypeError) as err:
        if err.argument == "backend":  # an LMI back-end ("ipm") the setting's choices share with RMPC's
            expected = f"{err.expected} (GIPC's QP back-ends)"
            raise ConfigError(f"{where}.backend", expected, err.found) from None
        path = options_path(err.argument, f"{where}.solver_options")
        if path is None:
            return  # not the options': the case's own build reports it
        raise ConfigError(path, f"{err.expected} (backend {settings['backend']!r})", err.found) from None


#: OfflineRMPC's solve options with the constructor's defaults (left out of a record at them).
OFFLINE_DEFAULTS: Mapping[str, Any] = MappingProxyType(
    {"backend": "ipm", "solver": None, "solver_options": None, "certificate_tol": 1e-7, "path": "ray"}
)
#: The family's ``quiet_settings`` entries of :data:`OFFLINE_DEFAULTS`.
OFFLINE_QUIET: frozenset[str] = frozenset(f"OfflineRMPC.{key}" for key in OFFLINE_DEFAULTS)


def check_offline_options(settings: Mapping[str, Any], where: str) -> None:
    """OfflineRMPC's ``backend``, ``solver``, ``solver_options``, ``certificate_tol`` and ``path``
    checked by its constructor.

    An :class:`rmpc.OfflineRMPC` is built (nothing is designed without ``x_design``) on a
    one-vertex, one-state stand-in; its error names the key path (``<where>.backend``,
    ``<where>.solver``, ``<where>.path``, ``<where>.certificate_tol``,
    ``<where>.solver_options.<name>``).

    Raises
    ------
    ConfigError
        Naming the setting the constructor refuses.
    """
    if all(settings.get(key) == default for key, default in OFFLINE_DEFAULTS.items()):
        return
    from models import PolytopicModel
    from rmpc.mpc.offline import OfflineRMPC

    stand_in = PolytopicModel([(np.array([[0.5]]), np.array([[1.0]]))], dt=1.0)
    options = settings.get("solver_options")
    try:
        OfflineRMPC(
            stand_in, np.eye(1), np.eye(1), u_max=1.0, backend=settings["backend"],
            solver=settings["solver"], solver_options=None if options is None else dict(options),
            certificate_tol=settings["certificate_tol"], path=settings["path"],
        )
    except (InvalidArgumentError, ArgumentTypeError) as err:
        raise_at_key_path(err, where, settings["backend"], ("backend", "certificate_tol", "path", "solver"))
