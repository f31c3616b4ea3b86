"""Every value of the wheel-fault benchmarks that paper W leaves out.

Paper W ("adaptive backstepping compensation of reaction-wheel failures") prints its plant, its
gains c1 and c2 and its scenarios, but not the adaptation gains (lost with its appendix), the run
lengths, the initial rates, the sampling of the simulation, the friction of its wheels or the
inertia error of its fourth scenario. Every such value here is the toolkit's assumption, printed
in every report by :func:`settings_rows` with the reason (:func:`rationale`).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

__all__ = [
    "ANGLE_NOISE_DEG",
    "CONTROLLER_DEFAULTS",
    "COULOMB_FRICTION",
    "DT",
    "D_TILT_DEG",
    "RECOVERY_DEG",
    "SETTING_CHOICES",
    "U_MAX",
    "VISCOUS_FRICTION",
    "W5_GAMMAS",
    "W5_GAMMAS_SHORT",
    "rationale",
    "settings_rows",
]

#: Control period (s): paper W's 40 ms zero-order hold.
DT: float = 0.04
#: Per-wheel torque limit the controllers design for (N m), paper W's wheels.
U_MAX: float = 0.123
#: Recovery after a fault: every angle back within this many degrees (assumed: paper W gives none).
RECOVERY_DEG: float = 2.0
#: RK4 step inside the hold (s; assumed: paper W gives no simulation step).
SUBSTEP: float = 0.005

#: W5: the adaptation gains ``Gamma_0 = Gamma_j = Gamma I3`` studied (the suite's full run).
W5_GAMMAS: tuple[float, ...] = (0.03, 0.1, 0.3, 1.0, 3.0, 10.0)
#: W5 under ``--short``: two gains, freeze off only (a smoke run).
W5_GAMMAS_SHORT: tuple[float, ...] = (0.1, 1.0)
#: W6: viscous bearing friction of every wheel, N m s/rad (assumed: paper W blames friction for
#: its hardware results but gives no value; 0.025 N m at the 50.8 rad/s momentum limit).
VISCOUS_FRICTION: float = 5e-4
#: W6: Coulomb bearing friction of every wheel, N m (assumed, 1.6 % of the torque limit).
COULOMB_FRICTION: float = 2e-3
#: W6: standard deviation of the angle noise, deg (paper W's sensors: 0.2 deg accuracy).
ANGLE_NOISE_DEG: float = 0.2
#: W7: tilt of every wheel axis of the plant, deg (seeded directions; each unit column moves 8.7 %).
D_TILT_DEG: float = 5.0

_Q_DIAG = (1.0, 1.0, 1.0, 0.1, 0.1, 0.1)
_R_DIAG = (1.0, 1.0, 1.0, 1.0)

#: Controller name -> every setting with its default.
CONTROLLER_DEFAULTS: Mapping[str, Mapping[str, Any]] = MappingProxyType(
    {
        "ABFTC": MappingProxyType(
            {"c1": 0.5, "c2": 3.0, "gamma_g": 0.1, "gamma_theta": 0.1, "freeze": False, "leakage": 0.0}
        ),
        "RMPC": MappingProxyType(
            {
                "Q_diag": _Q_DIAG,
                "R_diag": _R_DIAG,
                "input_constraint": "peak",
                "resolve_threshold": 1.0,
                "backend": "ipm",
            }
        ),
        "CRMPC": MappingProxyType(
            {
                "Q_diag": _Q_DIAG,
                "R_diag": _R_DIAG,
                "input_constraint": "peak",
                "adaptation_gain": 25.0,
                "theta_fraction": 0.8,
                "torque_budget": "current",
                "backend": "ipm",
            }
        ),
        "GIPC": MappingProxyType(
            {"Np": 100, "Nc": 4, "Qy": 1.0, "R_du": 0.3, "du_max": 0.01, "backend": "proxqp"}
        ),
    }
)

#: Allowed values of the string settings.
SETTING_CHOICES: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        "input_constraint": ("peak", "ellipsoid"),
        "backend": ("ipm", "clarabel", "cvxpy", "proxqp", "osqp"),
        "torque_budget": ("current", "split"),
    }
)


def settings_rows() -> list[tuple[str, str, str]]:
    """(setting, value, source) for the report's settings table."""
    return [
        (
            "control period / RK4 step (s)",
            f"{DT:g} / {SUBSTEP:g}",
            "assumed: paper W gives the 40 ms hardware loop, no simulation step",
        ),
        ("per-wheel torque limit (N m)", f"{U_MAX:g}", "paper W"),
        ("run lengths S1/S2/S3/S4 (s)", "60 / 150 / 150 / 150", "assumed: paper W does not print them"),
        ("initial rates", "zero", "likely: paper W releases the platform by hand, at about rest"),
        ("S1 stuck torque (N m)", "0.05 (0.03 in paper W's fault list)", "paper W, inconsistent"),
        (
            "S4 plant inertia",
            "1.2 J and 0.8 J, controllers keep J",
            "assumed: paper W states a 20 % error, not its sign",
        ),
        (
            "S4 wheel disturbance",
            "0.001 + 0.05 sin(2 pi t/800) + noise of variance 0.0052, every 40 ms, random seed 0",
            "paper W / assumed placement",
        ),
        ("gravity", "pendulous, known to ABFTC", "assumed: paper W's signs conflict; inverted topples S1"),
        ("recovery threshold", f"every angle within {RECOVERY_DEG:g} deg", "assumed: paper W gives none"),
        (
            "ABFTC c1, c2, Gamma_0, Gamma_j",
            "0.5, 3, 0.1 I, 0.1 I; basis [1, sin 0.2 t]; freeze and leakage off",
            "paper W gains c1, c2; Gamma assumed (paper W's appendix, which held it, is lost; W5 varies it)",
        ),
        ("RMPC, CRMPC Q, R", f"diag{_Q_DIAG}, I4; per-wheel peak bound |u_j| <= {U_MAX:g}", "toolkit"),
        (
            "RMPC polytope",
            "single-outage wheel effectiveness (5 vertices); x (1 +- 0.2) inertia for S4 (10)",
            "toolkit",
        ),
        (
            "CRMPC adaptation",
            "Lyapunov rule, g = 25 1/s^2 (Ts g = 1), |theta_j| <= 0.8 u_max, 'current' budget",
            "toolkit",
        ),
        ("GIPC Np, Nc, Qy, R_du, du_max", "100 (4 s), 4, 1, 0.3, 0.01 N m", "toolkit"),
        ("what RMPC/CRMPC/GIPC see", "attitude and rates (not the wheel momenta)", "toolkit"),
        (
            "W5 adaptation gains",
            "Gamma_0 = Gamma_j = Gamma I3, Gamma in " + ", ".join(f"{g:g}" for g in W5_GAMMAS)
            + "; wheel limits on/off; freeze off/on",
            "assumed (Gamma lost with paper W's appendix)",
        ),
        (
            "W6 wheel friction, angle noise",
            f"b = {VISCOUS_FRICTION:g} N m s/rad, c = {COULOMB_FRICTION:g} N m; {ANGLE_NOISE_DEG:g} deg "
            "(1 sigma, random seed 0)",
            "friction assumed (paper W gives none); noise: paper W's sensor accuracy",
        ),
        (
            "W7 error in D",
            f"every plant wheel axis tilted {D_TILT_DEG:g} deg (random seed 0); controllers keep the "
            "nominal D",
            "assumed (paper W claims robustness to it, gives no size)",
        ),
    ]


def rationale() -> str:
    """Why the values paper W leaves out are what they are (for the report)."""
    return (
        "Paper W's scenario lengths, initial rates and S4's inertia error are not printed: the runs "
        "last long enough for the last fault to be followed by 30 s or more, start at rest (the "
        "platform is released by hand) and S4 runs with the plant's inertia 20 % above and below "
        "the controllers'. Its adaptation gains were printed in an appendix that is lost: "
        "Gamma = 0.1 I3 is the toolkit's choice, and W5 measures how recovery depends on it. "
        "The robust MPC family runs on the linear model at level "
        "attitude with the wheel-effectiveness polytope (every single outage is a vertex), under "
        "the per-wheel peak bound of the wheels, so its torque commands stay inside the limit by "
        "construction; paper W's compensator is unconstrained and its printed gains ask for up to "
        "13x the wheel torque at the start of S1: the plant clips every wheel and the "
        "suite reports the saturated fraction. Only ABFTC is told the sinusoid's frequency (its "
        "basis). Recovery is measured from each fault's onset until every angle stays within "
        f"{RECOVERY_DEG:g} deg; momentum limits stop outward torque (faulty wheels included)."
    )
