"""Every value of paper M's benchmarks that paper M leaves out.

All are **assumed** and printed in every report by :func:`settings_rows`.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

__all__ = ["CONTROLLER_DEFAULTS", "SETTING_CHOICES", "U_MAX", "rationale", "settings_rows"]

#: Per-axis torque limit of M3 (N m): paper P's, since paper M promises input limits but gives no value.
U_MAX: float = 1.0

_Q_DIAG = (10.0, 10.0, 10.0, 10.0, 10.0, 10.0)
_R_DIAG = (1.0, 1.0, 1.0)

#: Controller name -> every setting with its default.
CONTROLLER_DEFAULTS: Mapping[str, Mapping[str, Any]] = MappingProxyType(
    {
        "BS": MappingProxyType({"c1": 0.5, "c2": 2.0}),
        "MAB": MappingProxyType({"c1": 0.5, "c2": 2.0, "kappa": 3.0, "observer_bandwidth": 10.0}),
        "TFAB": MappingProxyType({"c1": 0.5, "c2": 2.0, "gamma": 10.0}),
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
                "adaptation_gain": 100.0,
                "theta_fraction": 0.8,
                "torque_budget": "current",
                "backend": "ipm",
            }
        ),
    }
)

#: Allowed values of the string settings.
SETTING_CHOICES: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        "input_constraint": ("peak", "ellipsoid"),
        "backend": ("ipm", "clarabel", "cvxpy"),
        "torque_budget": ("current", "split"),
    }
)


def settings_rows() -> list[tuple[str, str, str]]:
    """(setting, value, source) for the report's settings table."""
    return [
        (
            "initial attitude / target (3-2-1, deg, relative to LVLH)",
            "(40, -30, 20) / (10, 5, -10)",
            "assumed: lost from paper M",
        ),
        ("run length, steady window", "100 s, [50, 100] s", "assumed: lost from paper M"),
        (
            "control period / plant RK4 step in rmpc bench mrp",
            "0.05 s / 0.01 s for every controller",
            "assumed (paper M's step was lost; the backstepping results are the same at 0.01 s and 0.05 s)",
        ),
        ("orbit", "circular, 650 km; gravity gradient off", "paper M / assumed"),
        ("inertia J0", "diag(3, 3, 2) kg m^2 (J2 and J3 may be swapped in paper M)", "paper M, likely"),
        (
            "M3",
            "spinning disk, true inertia 1.3 J0 and 0.7 J0, 1 N m per-axis limit",
            "assumed: paper M's scenario values were lost; it promises input limits, gives no value",
        ),
        ("BS, MAB, TFAB c1, c2", "0.5, 2", "assumed: paper M's gains were lost"),
        (
            "MAB kappa, observer",
            "3; NESO matched to a double pole at -10 rad/s",
            "assumed: paper M's values were lost",
        ),
        (
            "TFAB Gamma",
            "10 I",
            "assumed: lost from paper M; with Gamma = 100 TFAB beats MAB on M2, so paper M's ranking "
            "depends on tuning",
        ),
        ("RMPC / CRMPC Q, R", "10 I6, I3; per-axis peak bound in M3", "assumed (paper M has no robust MPC)"),
        (
            "RMPC / CRMPC polytope",
            "rigid satellite at the target: inertia +-30 % x the kinematics over the "
            "initial error's box (the toolkit's covering polytope)",
            "toolkit",
        ),
        (
            "CRMPC adaptation",
            "Lyapunov rule, g = 100 1/s^2, |theta| <= 0.8 u_max, 'current' budget",
            "toolkit",
        ),
    ]


def rationale() -> str:
    """Why the values paper M leaves out are what they are (for the report)."""
    return (
        "Paper M's initial state, target, run length and step were lost; the toolkit's choices are used "
        "(an initial error of 57.8 deg). The robust MPC runs on the error attitude in 3-2-1 angles and "
        "the rates relative to the orbital frame (models.mrp.tracking.RMPCStateMap), designed on the rigid "
        "satellite linearised at the target; its polytope also covers the kinematics over the box of "
        "attitude errors the manoeuvre sweeps. Its LMI guarantees (invariant ellipsoid, torque bound) "
        "hold for every frozen-attitude linear model over that box with the inertia scaled by 0.7 to 1.3, "
        "not for the plant: the gyroscopic torque w x J w, the disk's torque and the orbital terms of "
        "order n (about 1e-3 1/s) are outside the polytope and act on it as unmodelled disturbances. "
        "Paper M's controllers see the MRP state and the target; only MAB and TFAB estimate the disk's "
        "torque."
    )
