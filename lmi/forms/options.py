"""The options that select a robust MPC form, validated once, and the combinations that exist.

Each option is one idea of the field (see the page "The field's robust MPC forms" of the docs):
the Lyapunov function (``lyapunov``), what the cost bound is taken on (``cost``), a free first move
(``free_moves``), saturation-aware gains (``saturation``), soft bounds (``soft``) and a bounded
disturbance (``disturbance``). :func:`form_options` checks each value and each combination and
names the arguments of an error.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from lmi.forms.soft import check_soft
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_real_array

__all__ = [
    "COSTS", "LYAPUNOV_FORMS", "MAX_HORIZON", "MAX_SATURATION_INPUTS", "MAX_SOFT_WEIGHT",
    "MAX_UNSATURATED_WEIGHT", "SATURATIONS", "STEP_GAINS", "Disturbance", "FormOptions", "form_options",
]

#: ``"common"``: one quadratic Lyapunov function (Kothare 1996); ``"vertex"``: one ``Q_j`` per
#: vertex and a slack ``G`` (uncertainty constant in time); ``"vertex_pairs"``: every vertex pair
#: (uncertainty that may change at every sample); ``"saturation_dependent"``: one ``Q_k`` per sign
#: pattern of the auxiliary saturation and a slack ``G`` (Zhang, Wang & Li 2013).
LYAPUNOV_FORMS: tuple[str, ...] = ("common", "vertex", "vertex_pairs", "saturation_dependent")
#: The cost bound over every vertex, or on the nominal model with robust invariance.
COSTS: tuple[str, ...] = ("worst_case", "nominal")
#: ``None`` (the law ``F x`` meets the bound) or ``"auxiliary"`` (``sat(F x)`` with an auxiliary gain).
SATURATIONS: tuple[str | None, ...] = (None, "auxiliary")


@dataclass(frozen=True)
class Disturbance:
    """``x+ = A x + B u + E w`` with ``||w|| <= w_max``; ``lam`` the S-procedure's contraction
    factor in ``(0, 1)``, or ``None`` to search it."""

    E: np.ndarray
    w_max: float
    lam: float | None = None


@dataclass(frozen=True)
class FormOptions:
    """A validated choice of form (see :func:`form_options`)."""

    lyapunov: Literal["common", "vertex", "vertex_pairs", "saturation_dependent"] = "common"
    cost: Literal["worst_case", "nominal"] = "worst_case"
    free_moves: int = 0
    saturation: Literal["auxiliary"] | None = None
    #: ``{"u": w_u, "y": w_y}`` (one slack per family), or per component ``{"u": (w_1, ...),
    #: "u_limit": (l_1, ...)}`` (:mod:`lmi.forms.soft`)
    soft: Mapping[str, float | tuple[float, ...]] | None = None
    disturbance: Disturbance | None = None
    horizon: int = 1
    step_gains: Literal["common", "vertex"] = "common"
    unsaturated_weight: float | None = None

    @property
    def is_kothare(self) -> bool:
        """Whether these are Kothare's LMIs (the defaults; a zero disturbance counts as none)."""
        return (
            self.lyapunov == "common" and self.cost == "worst_case" and self.free_moves == 0
            and self.saturation is None and self.soft is None and self.unsaturated_weight is None
            and (self.disturbance is None or self.disturbance.w_max == 0.0)
            and not self.has_steps
        )

    @property
    def has_steps(self) -> bool:
        """Whether the form has later steps with gains of their own (``horizon > 1``)."""
        return self.horizon > 1

    @property
    def vertex_lyapunov(self) -> bool:
        """One ``Q_j`` per vertex (or per sign pattern) and a slack ``G``."""
        return self.lyapunov != "common"

    @property
    def saturation_dependent(self) -> bool:
        """One ``Q_k`` per sign pattern of the auxiliary saturation (Zhang, Wang & Li 2013)."""
        return self.lyapunov == "saturation_dependent"


def _choice(value: Any, allowed: tuple, name: str) -> Any:
    if not any(value is a or (isinstance(value, str) and value == a) for a in allowed):
        raise InvalidArgumentError(name, "one of " + ", ".join(repr(a) for a in allowed), repr(value))
    return value


#: The largest weight of a soft bound (``soft={"u": w_u, "y": w_y}``); a larger one is refused.
#: The objective ``gamma + w s`` then spans ``w`` from its smallest to its largest coefficient,
#: and the solvers lose the cost bound beside the penalty. Measured on Kothare's examples 1 and 2,
#: MUP's demo system, paper P's satellite (2 vertices) and paper W's at ``x0`` and ``4 x0``, each
#: form with one Lyapunov function and with one per vertex: weights 1e3 to 1e9 gave certified
#: ``"optimal"`` answers on all of them (where the hard problem is feasible, the same gamma at
#: every weight from 1e6 on, with slacks of 1e-9 or less). The first failure came at 1e10, on
#: paper W's satellite with one Lyapunov function per vertex (``"max_iterations"``, then phase
#: one's point, ``"inaccurate"``, gamma 7 times the optimum); on the others from 1e15 (phase one's
#: point, gamma 5 to 80 times the optimum; Kothare's example 2 from 1e20), where Clarabel, the
#: fallback, called several of them unbounded, and at 1e200 the kernels divided by zero. 1e8 keeps
#: a factor of 100 from the first failure.
MAX_SOFT_WEIGHT = 1e8


def _disturbance(disturbance: Any, n: int) -> Disturbance | None:
    if disturbance is None:
        return None
    if isinstance(disturbance, Disturbance):
        disturbance = (disturbance.E, disturbance.w_max, disturbance.lam)
    if not isinstance(disturbance, tuple | list) or len(disturbance) not in (2, 3):
        expected = "None, (E, w_max) or (E, w_max, lam)"
        raise ArgumentTypeError("disturbance", expected, type(disturbance).__name__)
    e_mat = np.array(as_real_array(disturbance[0], "disturbance E", "a numeric (n, q) matrix"))
    if e_mat.ndim == 1:
        e_mat = e_mat[:, None]
    if e_mat.ndim != 2 or e_mat.shape[0] != n or e_mat.shape[1] < 1:
        expected = f"an ({n}, q) matrix (n = {n} states)"
        raise InvalidArgumentError("disturbance E", expected, f"shape {e_mat.shape}")
    if not np.all(np.isfinite(e_mat)):
        raise InvalidArgumentError("disturbance E", "finite values", "NaN or inf")
    w_max = disturbance[1]
    if isinstance(w_max, bool) or not isinstance(w_max, int | float | np.floating | np.integer):
        raise ArgumentTypeError("disturbance w_max", "a number >= 0", type(w_max).__name__)
    if not (np.isfinite(w_max) and w_max >= 0.0):
        raise InvalidArgumentError("disturbance w_max", "a finite bound >= 0", repr(w_max))
    lam = disturbance[2] if len(disturbance) == 3 else None
    if lam is not None:
        if isinstance(lam, bool) or not isinstance(lam, int | float | np.floating | np.integer):
            raise ArgumentTypeError("disturbance lam", "None or a number in (0, 1)", type(lam).__name__)
        if not 0.0 < lam < 1.0:
            raise InvalidArgumentError("disturbance lam", "a contraction factor in (0, 1)", repr(lam))
        lam = float(lam)
    e_mat.setflags(write=False)
    return Disturbance(e_mat, float(w_max), lam)


def form_options(
    *,
    n_states: int,
    input_constraint: str | None,
    has_output: bool,
    lyapunov: Any = "common",
    cost: Any = "worst_case",
    free_moves: Any = 0,
    saturation: Any = None,
    soft: Any = None,
    disturbance: Any = None,
    horizon: Any = 1,
    step_gains: Any = "common",
    unsaturated_weight: Any = None,
    n_inputs: int | None = None,
    n_outputs: int | None = None,
) -> FormOptions:
    """Check every option and every combination; return the :class:`FormOptions`.

    ``n_inputs``/``n_outputs``: the plant's inputs and bounded outputs, the lengths of per-component
    soft weights and limits (:mod:`lmi.forms.soft`; ``None``: not checked here); ``n_inputs`` is
    also checked against :data:`MAX_SATURATION_INPUTS` with ``lyapunov="saturation_dependent"``.

    Raises
    ------
    InvalidArgumentError, ArgumentTypeError
        Naming the option (and, for a combination that does not exist, both options).
    """
    _choice(lyapunov, LYAPUNOV_FORMS, "lyapunov")
    _choice(cost, COSTS, "cost")
    if isinstance(free_moves, bool | np.bool_) or not isinstance(free_moves, int | np.integer):
        found = f"{type(free_moves).__name__} {free_moves!r}"
        raise ArgumentTypeError("free_moves", "the integer 0 or 1", found)
    if free_moves not in (0, 1):
        raise InvalidArgumentError("free_moves", "0 or 1", repr(free_moves))
    _choice(saturation, SATURATIONS, "saturation")
    soft_weights = check_soft(soft, input_constraint=input_constraint, has_output=has_output,
                              n_inputs=n_inputs, n_outputs=n_outputs, max_weight=MAX_SOFT_WEIGHT)
    dist = _disturbance(disturbance, n_states)
    steps = _steps(horizon, step_gains)
    _step_combinations(steps, lyapunov, cost, free_moves, saturation, soft_weights, dist)
    weight = _unsaturated_weight(unsaturated_weight)
    _saturation_combinations(lyapunov, saturation, weight, free_moves, dist, n_inputs)
    if steps[0] > 1 and (lyapunov == "saturation_dependent" or weight is not None):
        name, value = (("lyapunov", lyapunov) if lyapunov == "saturation_dependent"
                       else ("unsaturated_weight", weight))
        raise InvalidArgumentError(
            f"horizon, {name}", f"horizon=1 with {name}={value!r} (the forms with steps are written for "
            "one Lyapunov matrix per vertex and Cao & Lin's saturation)",
            f"horizon={steps[0]!r}, {name}={value!r}")
    if saturation == "auxiliary" and input_constraint != "peak":
        raise InvalidArgumentError(
            "saturation, input_constraint",
            "saturation='auxiliary' with input_constraint='peak' (the saturation is componentwise)",
            f"input_constraint={input_constraint!r}",
        )
    if free_moves == 1 and dist is not None and dist.w_max > 0.0:
        raise InvalidArgumentError(
            "free_moves, disturbance",
            "free_moves=0 with a disturbance (the free move's prediction has no disturbance bound)",
            f"free_moves=1, w_max={dist.w_max!r}",
        )
    return FormOptions(
        str(lyapunov), str(cost), int(free_moves), saturation, soft_weights, dist,  # type: ignore[arg-type]
        *steps,  # type: ignore[arg-type]
        weight,
    )


# -- the forms with steps: Li, Shi, Sun & Wang (2008) and Shi, Su & Chu (2013) -----------------------

#: ``"common"``: the gain of a later step does not depend on the plant of the step before (Shi, Su
#: & Chu's N steps, each with its own ``G_t, Y_t`` and Lyapunov matrices); ``"vertex"``: the second
#: step's gain ``Y_v`` depends on the vertex ``v`` of the first (Li, Shi, Sun & Wang's two steps).
STEP_GAINS: tuple[str, ...] = ("common", "vertex")

#: The largest ``horizon``. The variables and blocks grow linearly with it: each step adds its own
#: ``G_t``/``Y_t``/``Z_t`` and Lyapunov matrices (``n_v n (n + 1) / 2 + n^2 + 2 m n`` variables with
#: ``"vertex_pairs"`` and the auxiliary saturation) and its cost, input and output blocks
#: (``n_v^2 2^m + m n_v + p n_v 2^m``), and the interior-point iteration grows faster than
#: linearly in the variables. Measured with MUP's ``shi`` (``"vertex_pairs"``, auxiliary
#: saturation), median of 7 warm solves on a 2-core machine shared with other jobs: Kothare's
#: example 2 (44 variables and 10 blocks per step) 0.11 s at 3 steps (133 variables), 0.61 s at 6
#: (265), 2.4 s at 8 (353 variables, 82 blocks), its gamma 189.45, 157.88 and 157.45 (0.3 % from 6
#: to 8 steps); MUP's demo system (17 variables and 33 blocks per step) 0.24 s at 8 steps (137
#: variables, 267 blocks), its gamma the same to 1e-8 relative from 4 steps on. Beyond 8 steps the
#: solve time keeps growing for a gamma that has stopped moving, so 8 is the limit.
MAX_HORIZON = 8


def _steps(horizon: Any, step_gains: Any) -> tuple[int, str]:
    if isinstance(horizon, bool | np.bool_) or not isinstance(horizon, int | np.integer):
        found = f"{type(horizon).__name__} {horizon!r}"
        raise ArgumentTypeError("horizon", f"an integer from 1 to MAX_HORIZON = {MAX_HORIZON}", found)
    if not 1 <= horizon <= MAX_HORIZON:
        raise InvalidArgumentError(
            "horizon", f"an integer from 1 to MAX_HORIZON = {MAX_HORIZON} (the steps with gains of their "
            "own before the terminal ellipsoid)", repr(horizon))
    _choice(step_gains, STEP_GAINS, "step_gains")
    return int(horizon), str(step_gains)


def _step_combinations(steps: tuple[int, str], lyapunov: Any, cost: Any, free_moves: Any, saturation: Any,
                       soft: dict[str, float] | None, dist: Disturbance | None) -> None:
    """The forms with steps that exist: Li et al.'s (``horizon=2, step_gains="vertex"`` with one
    Lyapunov function) and Shi et al.'s (``horizon=N`` with any Lyapunov form, with or without the
    auxiliary saturation); each other option is refused naming it."""
    horizon, step_gains = steps
    if step_gains == "vertex":
        li = "step_gains='vertex' (Li et al.'s two-step form) with "
        if horizon != 2:
            raise InvalidArgumentError("step_gains, horizon", li + "horizon=2",
                                       f"step_gains={step_gains!r}, horizon={horizon!r}")
        if lyapunov != "common":
            raise InvalidArgumentError("step_gains, lyapunov", li + "lyapunov='common'",
                                       f"step_gains={step_gains!r}, lyapunov={lyapunov!r}")
        if saturation is not None:
            raise InvalidArgumentError("step_gains, saturation", li + "saturation=None",
                                       f"step_gains={step_gains!r}, saturation={saturation!r}")
    if horizon == 1:
        return
    given = {"cost": (cost, "worst_case"), "free_moves": (free_moves, 0), "soft": (soft, None),
             "disturbance": (None if dist is None or dist.w_max == 0.0 else dist.w_max, None)}
    for name, (value, default) in given.items():
        if value != default:
            raise InvalidArgumentError(
                f"horizon, {name}", f"horizon=1 with {name}={value!r} (the forms with steps bound the "
                f"worst-case cost, with no free move, soft bound or disturbance), or {name}={default!r}",
                f"horizon={horizon!r}, {name}={value!r}")


#: The largest weight ``beta`` of Huang et al.'s objective ``gamma + beta gamma_s``
#: (``unsaturated_weight``); a larger one is refused, as :data:`MAX_SOFT_WEIGHT` for the same
#: reason: the objective spans ``beta`` from ``gamma``'s coefficient 1, and the solvers lose
#: ``gamma`` beside ``beta gamma_s``. Measured with huang, wan_huang and mao_huang on Kothare's
#: examples 1 and 2 and MUP's demo system: certified ``"optimal"`` at every weight from 1e3 to
#: 1e14 (``gamma`` growing as ``sqrt(beta)`` while ``gamma_s`` settles at its own minimum); the
#: first failures at 1e16 (example 2, all three; MUP's demo, huang and wan_huang: ``numerical_error``,
#: then phase one's point, ``"inaccurate"``, ``gamma_s`` 2.3 to 260 times its minimum). 1e14 keeps
#: a factor of 100 from them.
MAX_UNSATURATED_WEIGHT = 1e14

#: The most inputs ``lyapunov="saturation_dependent"`` takes: its LMIs hold ``2^m`` Lyapunov
#: matrices and ``N 4^m`` cost blocks (``m`` inputs, ``N`` vertices), 1024 per vertex at ``m = 5``.
#: The size guard of :class:`lmi.forms.FormProblem` (:data:`lmi.forms.problem.MAX_COEFFICIENT_BYTES`)
#: refuses smaller forms whose blocks do not fit.
MAX_SATURATION_INPUTS = 5


def _unsaturated_weight(weight: Any) -> float | None:
    if weight is None:
        return None
    number = int | float | np.floating | np.integer
    if isinstance(weight, bool | np.bool_) or not isinstance(weight, number):
        raise ArgumentTypeError("unsaturated_weight", "None or a number >= 0", type(weight).__name__)
    if not (np.isfinite(weight) and weight >= 0.0):
        raise InvalidArgumentError("unsaturated_weight", "a finite weight >= 0", repr(weight))
    if weight > MAX_UNSATURATED_WEIGHT:
        raise InvalidArgumentError(
            "unsaturated_weight",
            f"a weight <= MAX_UNSATURATED_WEIGHT = {MAX_UNSATURATED_WEIGHT:g} (beyond it the solvers cannot "
            "resolve gamma next to beta gamma_s; see the page on the forms)", repr(weight))
    return float(weight)


def _saturation_combinations(lyapunov: Any, saturation: Any, weight: float | None, free_moves: Any,
                             dist: Disturbance | None, n_inputs: int | None) -> None:
    """Huang et al.'s weight and Zhang et al.'s Lyapunov function: only with the auxiliary
    saturation, whose sign patterns they are written on."""
    if weight is not None and saturation != "auxiliary":
        raise InvalidArgumentError(
            "unsaturated_weight, saturation",
            "unsaturated_weight with saturation='auxiliary' (it weighs the cost bound of the unsaturated "
            "sign pattern)", f"unsaturated_weight={weight!r}, saturation={saturation!r}",
        )
    if lyapunov != "saturation_dependent":
        return
    if saturation != "auxiliary":
        raise InvalidArgumentError(
            "lyapunov, saturation",
            "lyapunov='saturation_dependent' with saturation='auxiliary' (one Lyapunov matrix per sign "
            "pattern of the saturation)", f"lyapunov={lyapunov!r}, saturation={saturation!r}",
        )
    if free_moves:
        raise InvalidArgumentError(
            "lyapunov, free_moves",
            "free_moves=0 with lyapunov='saturation_dependent' (the free move's prediction is not "
            "written for this form)", f"lyapunov={lyapunov!r}, free_moves={free_moves!r}",
        )
    if dist is not None and dist.w_max > 0.0:
        raise InvalidArgumentError(
            "lyapunov, disturbance",
            "no disturbance with lyapunov='saturation_dependent' (its S-procedure is not written for "
            "this form)", f"lyapunov={lyapunov!r}, w_max={dist.w_max!r}",
        )
    if n_inputs is not None and n_inputs > MAX_SATURATION_INPUTS:
        raise InvalidArgumentError(
            "lyapunov, plant",
            f"at most MAX_SATURATION_INPUTS = {MAX_SATURATION_INPUTS} inputs with "
            "lyapunov='saturation_dependent' (2^m Lyapunov matrices, N 4^m cost blocks)",
            f"{n_inputs} inputs",
        )
