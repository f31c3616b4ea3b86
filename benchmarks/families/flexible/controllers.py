"""The controllers of the flexible-satellite benchmarks and how each meets the torque limit.

``saturation``: ``"none"`` (no limit), ``"limiter"`` (the hub torque is clipped per axis at
``u_max`` in the loop, paper V's "saturation considered") or ``"constraint"`` (``RMPC`` and
``OfflineRMPC``: a per-axis peak bound in the LMIs). The PZT commands are never limited.

- ``MTSMC`` (:class:`rmpc.MTSMC`, the moving surface with the schedule ``alpha(t)``, boundary
  layer ``epsilon``, integral gain ``integral_gain``) and ``CSMC`` (:class:`rmpc.CSMC`, switch
  ``"sign"`` or ``"tanh"``), each with paper V's robust AVC (:class:`rmpc.RobustAVC`) when the
  scenario's ``avc`` is true, through :class:`rmpc.FlexibleHybrid`;
- ``PD`` (:class:`rmpc.AttitudePD`, paper S's industrial anchor, optionally with its disturbance
  observer) and ``LQR`` (:func:`rmpc.flexible_lqr`, the unconstrained one-vertex reference), also
  with AVC on request;
- paper S's other baselines: ``ASMC`` (:class:`rmpc.AdaptiveSMC`), ``NPD``
  (:class:`rmpc.NonlinearPD`, saturated proportional term), ``APD`` (:class:`rmpc.AdaptivePD`,
  gains adapted in a box) and ``ZVD-PD`` (:class:`rmpc.ShapedPD`, PD behind a ZVD shaper on the
  first mode), also with AVC on request;
- ``RMPC`` (:class:`rmpc.RMPC`, on-line, holding its last solution while the state stays in
  the ``resolve_threshold`` level set of its ellipsoid) and ``OfflineRMPC``
  (:class:`rmpc.OfflineRMPC`, Wan & Kothare 2003, its table designed once from the initial
  state) on the 14-state linear model ``[q_v, w, eta, eta']`` of the error quaternion
  (:meth:`models.FlexibleSatellite.linear_state`), through :class:`rmpc.MappedController`; their
  PZT commands are zero (or AVC's). With ``modal_bound`` set, both bound the modal coordinates
  through Kothare's output constraint (:func:`modal_output`). With ``handover_deg`` set,
  ``OfflineRMPC`` takes over from MTSMC once the rotation error first falls below that angle
  (:class:`HandOver`, the hand-over for the large slew, which the linear model does not cover); its
  table is then designed from the state at the hand-over.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from benchmarks.core.family import BuiltController, check_ellipsoid_count
from toolkit_common.errors import ConfigError

__all__ = [
    "CONSTRAINED",
    "CONTROLLERS",
    "PD_LIKE",
    "FlexibleModel",
    "HandOver",
    "linear_weights",
    "modal_output",
    "settings_check",
]


class FlexibleModel:
    """What the controllers are built on: the satellite, the control period and the RMPC polytope."""

    def __init__(self, satellite: Any, dt: float, polytope: Any = None, x_design: Any = None) -> None:
        self.satellite = satellite
        self.dt = dt
        self.polytope = polytope
        self.x_design = x_design


class HandOver:
    """A slew law until the rotation error first falls below ``angle``, then a fine law for good.

    Parameters
    ----------
    slew : Controller
        The large-angle law, returning ``[u; v]`` and taking the PZT command ``v`` through
        ``StepInputs(pzt=v)`` (:class:`rmpc.MTSMC`).
    fine : Controller
        The law near the target, ``step(x)`` returning ``[u; 0]`` (the mapped robust MPC); its
        PZT entries are replaced by ``v``.
    angle : float
        The hand-over rotation error (rad).

    Attributes
    ----------
    name : str
        ``"<slew>><fine>"`` from the two laws' names, e.g. ``"MTSMC>OfflineRMPC"``.
    accepts : frozenset of str
        ``{"pzt"}``: this sample's PZT command, passed to the slew law or into the output.
    controller : object
        The fine law's inner controller (its table or gain, for the report).
    handover_step : int or None
        The step at which the fine law took over (``None``: not yet).
    """

    accepts: ClassVar[frozenset[str]] = frozenset({"pzt"})

    def __init__(self, slew: Any, fine: Any, angle: float) -> None:
        self.slew = slew
        self.fine = fine
        self.angle = float(angle)
        self.name = ">".join(getattr(law, "name", type(law).__name__) for law in (slew, fine))
        self.controller = getattr(fine, "controller", fine)
        self.handover_step: int | None = None
        self._count = 0
        self.last: Any = None

    def reset(self) -> None:
        """Reset both laws; the slew law runs again first."""
        self.slew.reset()
        self.fine.reset()
        self.handover_step = None
        self._count = 0
        self.last = None

    def step(self, x: Any, inputs: Any = None) -> np.ndarray:
        """``[u; v]`` from the slew law, or from the fine law once the error was below ``angle``."""
        from models.attitude.quaternion import rotation_angle
        from rmpc.controller import check_step_inputs

        pzt = check_step_inputs(inputs, self.accepts, self.name).pzt
        if self.handover_step is None and rotation_angle(np.asarray(x, dtype=float)[:4]) < self.angle:
            self.handover_step = self._count
        self._count += 1
        if self.handover_step is None:
            u = np.asarray(self.slew.step(x, inputs), dtype=float)
            self.last = self.slew.last
            return u
        u = np.array(self.fine.step(x), dtype=float)
        if pzt is not None:
            u[3:] = pzt
        self.last = self.fine.last
        return u


def _with_avc(law: Any, m: FlexibleModel, scenario: Any) -> Any:
    from rmpc import FlexibleHybrid, RobustAVC

    return FlexibleHybrid(law, RobustAVC(m.satellite, m.dt) if scenario.avc else None)


def _limited(scenario: Any) -> bool:
    return scenario.saturation == "limiter"


def _mtsmc(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import MTSMC

    law = MTSMC(
        m.satellite,
        m.dt,
        alpha_f=s["alpha_f"],
        tau_a=s["tau_a"],
        K_s=s["K_s"],
        W_0=s["W_0"],
        eps=scenario.epsilon,
        k_I=scenario.integral_gain,
    )
    return BuiltController(_with_avc(law, m, scenario), _limited(scenario))


def _csmc(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import CSMC

    law = CSMC(
        m.satellite,
        m.dt,
        lam=s["lam"],
        K_s=s["K_s"],
        W_0=s["W_0"],
        switch=scenario.switch,
        eps=scenario.epsilon,
    )
    return BuiltController(_with_avc(law, m, scenario), _limited(scenario))


def _pd(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import AttitudePD

    law = AttitudePD(
        m.satellite, m.dt, K_p=s["K_p"], K_d=s["K_d"], disturbance_observer=s["disturbance_observer"]
    )
    return BuiltController(_with_avc(law, m, scenario), _limited(scenario))


def _asmc(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import AdaptiveSMC

    keys = ("lam", "K_s", "s_b", "n0", "e0", "n1", "e1")
    law = AdaptiveSMC(m.satellite, m.dt, **{k: s[k] for k in keys})
    return BuiltController(_with_avc(law, m, scenario), _limited(scenario))


def _npd(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import NonlinearPD

    law = NonlinearPD(m.satellite, m.dt, K_p=s["K_p"], K_d=s["K_d"], q_s=s["q_s"])
    return BuiltController(_with_avc(law, m, scenario), _limited(scenario))


def _apd(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import AdaptivePD

    keys = ("k_p0", "k_d0", "k_p_max", "k_d_max", "gamma_p", "gamma_d", "sigma")
    law = AdaptivePD(m.satellite, m.dt, **{k: s[k] for k in keys})
    return BuiltController(_with_avc(law, m, scenario), _limited(scenario))


def _zvd_pd(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import ShapedPD

    law = ShapedPD(m.satellite, m.dt, K_p=s["K_p"], K_d=s["K_d"], kind="zvd")
    return BuiltController(_with_avc(law, m, scenario), _limited(scenario))


#: Paper S's baselines with their PD-like gains ``(K_p, K_d)`` near the target (for the regime
#: label's bandwidth): PD, nonlinear PD (unsaturated there), adaptive-gain PD (its lowest gains)
#: and PD behind the ZVD shaper.
PD_LIKE: Mapping[str, tuple[str, str]] = {
    "PD": ("K_p", "K_d"),
    "NPD": ("K_p", "K_d"),
    "APD": ("k_p0", "k_d0"),
    "ZVD-PD": ("K_p", "K_d"),
}


def linear_weights(settings: Mapping[str, Any], n_modes: int) -> tuple[np.ndarray, np.ndarray]:
    """``(Q, R)`` on ``[q_v, w, eta, eta']`` and the hub torques from the scalar weight settings."""
    diag = [settings["q_weight"]] * 3 + [settings["w_weight"]] * 3 + [settings["eta_weight"]] * (2 * n_modes)
    return np.diag(diag), settings["r_weight"] * np.eye(3)


def _lqr(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import flexible_lqr

    Q, R = linear_weights(s, m.satellite.n_modes)
    law = flexible_lqr(m.satellite, m.dt, Q=Q, R=R)
    return BuiltController(_with_avc(law, m, scenario), _limited(scenario))


def _mapped(ctrl: Any, m: FlexibleModel, name: str) -> Any:
    from rmpc import MappedController

    sat = m.satellite
    n_pzt = sat.n_pzt

    def measure(x: np.ndarray) -> np.ndarray:
        return sat.linear_state(x, attitude="quaternion")

    def output(u: np.ndarray) -> np.ndarray:
        return np.concatenate((u, np.zeros(n_pzt)))

    return MappedController(ctrl, measure, output=output, name=name)


def modal_output(n_modes: int, bound: float | None) -> dict[str, Any]:
    """``output_matrix`` and ``y_max`` bounding every modal coordinate ``eta_i`` by ``bound``.

    ``C`` picks ``eta`` (entries ``6 .. 6 + N``, kg^1/2 m) of the linear state
    ``[q_v, w, eta, eta']``; Kothare's output constraint then bounds ``|eta_i(k + j)|``,
    ``j >= 1``, at the samples, for every model of the polytope. ``bound=None``: no constraint.

    Examples
    --------
    >>> out = modal_output(4, 0.02)
    >>> out["output_matrix"].shape, float(out["output_matrix"][:, 6:10].trace()), out["y_max"].tolist()
    ((4, 14), 4.0, [0.02, 0.02, 0.02, 0.02])
    >>> modal_output(4, None)
    {'output_matrix': None, 'y_max': None}
    """
    if bound is None:
        return {"output_matrix": None, "y_max": None}
    c = np.zeros((n_modes, 6 + 2 * n_modes))
    c[:, 6 : 6 + n_modes] = np.eye(n_modes)
    return {"output_matrix": c, "y_max": np.full(n_modes, float(bound))}


def _rmpc(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from benchmarks.families.rmpc_forms import rmpc_kwargs
    from rmpc import RMPC

    constrained = scenario.saturation == "constraint"
    Q, R = linear_weights(s, m.satellite.n_modes)
    ctrl = RMPC(
        m.polytope,
        Q,
        R,
        u_max=scenario.u_max if constrained else None,
        input_constraint=s["input_constraint"] if constrained else None,
        **modal_output(m.satellite.n_modes, scenario.modal_bound),
        resolve_threshold=s["resolve_threshold"],
        backend=s["backend"],
        certificate_tol=s["certificate_tol"],
        on_failure=s["on_failure"],
        **rmpc_kwargs(s),
    )
    return BuiltController(_with_avc(_mapped(ctrl, m, "RMPC"), m, scenario), _limited(scenario))


def _offline(m: FlexibleModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import MTSMC, OfflineRMPC

    constrained = scenario.saturation == "constraint"
    Q, R = linear_weights(s, m.satellite.n_modes)
    ctrl = OfflineRMPC(
        m.polytope,
        Q,
        R,
        u_max=scenario.u_max if constrained else None,
        input_constraint=s["input_constraint"] if constrained else None,
        **modal_output(m.satellite.n_modes, scenario.modal_bound),
        x_design=None if scenario.handover_deg is not None else m.x_design,
        n_ellipsoids=s["n_ellipsoids"],
        shrink=s["shrink"],
        formulation=s["formulation"],
        cost=s["cost"],
        backend=s["backend"],
        solver=s["solver"],
        solver_options=None if s["solver_options"] is None else dict(s["solver_options"]),
        certificate_tol=s["certificate_tol"],
        path=s["path"],
    )
    law = _mapped(ctrl, m, "OfflineRMPC")
    if scenario.handover_deg is not None:
        slew = MTSMC(m.satellite, m.dt, eps=scenario.epsilon, **_MTSMC_HANDOVER)
        law = HandOver(slew, law, np.deg2rad(scenario.handover_deg))
        # MTSMC has no constraint: the limiter stays in the loop (the LMIs' bound is inside it)
        return BuiltController(_with_avc(law, m, scenario), scenario.saturation != "none")
    return BuiltController(_with_avc(law, m, scenario), _limited(scenario))


#: MTSMC's settings in the hand-over (its defaults in :mod:`benchmarks.families.flexible.defaults`).
_MTSMC_HANDOVER: Mapping[str, float] = {"alpha_f": 0.1, "tau_a": 15.0, "K_s": 20.0, "W_0": 1.0}


#: Controller name -> factory ``(FlexibleModel, scenario, settings) -> BuiltController``.
CONTROLLERS: Mapping[str, Callable[[Any, Any, Mapping[str, Any]], BuiltController]] = {
    "MTSMC": _mtsmc,
    "CSMC": _csmc,
    "PD": _pd,
    "LQR": _lqr,
    "ASMC": _asmc,
    "NPD": _npd,
    "APD": _apd,
    "ZVD-PD": _zvd_pd,
    "RMPC": _rmpc,
    "OfflineRMPC": _offline,
}

#: Controllers that design for the torque limit themselves (``saturation = "constraint"``).
CONSTRAINED = ("RMPC", "OfflineRMPC")


def settings_check(controller: str, out: dict[str, Any], where: str) -> None:
    """Checks between the settings of one controller."""
    if controller == "RMPC" and out["resolve_threshold"] > 1.0:
        raise ConfigError(f"{where}.resolve_threshold", "a level in (0, 1]", repr(out["resolve_threshold"]))
    if controller == "OfflineRMPC" and out["shrink"] >= 1.0:
        raise ConfigError(f"{where}.shrink", "a factor in (0, 1)", repr(out["shrink"]))
    if controller == "OfflineRMPC":
        check_ellipsoid_count(out["n_ellipsoids"], out["shrink"], f"{where}.n_ellipsoids")
