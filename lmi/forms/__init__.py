"""The field's robust MPC forms on the toolkit's solver (see the page "The field's robust MPC forms").

:class:`FormProblem` solves, at each state, the LMIs of a form chosen by options
(:func:`~lmi.forms.options.form_options`): parameter-dependent Lyapunov functions, a nominal
cost, a free first move, saturation-aware gains, soft bounds and bounded disturbances.
"""

from lmi.forms.options import (
    COSTS,
    LYAPUNOV_FORMS,
    MAX_HORIZON,
    MAX_SATURATION_INPUTS,
    MAX_SOFT_WEIGHT,
    MAX_UNSATURATED_WEIGHT,
    SATURATIONS,
    STEP_GAINS,
    Disturbance,
    FormOptions,
    form_options,
)
from lmi.forms.problem import FormProblem

__all__ = [
    "COSTS",
    "LYAPUNOV_FORMS",
    "MAX_HORIZON",
    "MAX_SATURATION_INPUTS",
    "MAX_SOFT_WEIGHT",
    "MAX_UNSATURATED_WEIGHT",
    "SATURATIONS",
    "STEP_GAINS",
    "Disturbance",
    "FormOptions",
    "FormProblem",
    "form_options",
]
