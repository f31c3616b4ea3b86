"""The literature's robust MPC methods by name: MUP's method keys mapped onto the toolkit's forms.

MUP (Oravec & Bakosova's MATLAB toolbox for robust MPC, the field's reference implementation)
names each method by a key (``rmpc_methods/feas_<key>.m``). :meth:`rmpc.RMPC.from_method`
accepts those keys; each maps onto the orthogonal options of :class:`~rmpc.RMPC`
(:mod:`lmi.forms`):

=============  =====================================================  =================================
key            method                                                 options
=============  =====================================================  =================================
``kothare``    Kothare, Balakrishnan & Morari (1996)                  the defaults
``cuzzola``    Cuzzola, Geromel & Morari (2002)                       ``lyapunov="vertex"``
``mao``        Mao (2003)                                             ``lyapunov="vertex_pairs"``
``wan``        Wan & Kothare (2003)                                   ``cost="nominal"``
``cao``        Cao & Lin (2005)                                       ``saturation="auxiliary"``
``mao_cao``    Mao (2003) with Cao & Lin (2005)                       ``lyapunov="vertex_pairs"``,
                                                                      ``saturation="auxiliary"``
``wan_cao``    Wan & Kothare (2003) with Cao & Lin (2005)             ``cost="nominal"``,
                                                                      ``saturation="auxiliary"``
``li``         Li, Shi, Sun & Wang (2008)                             ``horizon=2``,
                                                                      ``step_gains="vertex"``,
                                                                      ``lyapunov="common"``
``shi``        Shi, Su & Chu (2013)                                   ``horizon=3`` (MUP's demo; the
                                                                      caller may give another),
                                                                      ``lyapunov="vertex_pairs"``,
                                                                      ``saturation="auxiliary"``
``ding``       Ding, Xi, Cychowski & O'Mahony (2007)                  ``cost="nominal"``,
                                                                      ``lyapunov="vertex_pairs"``
``huang``      Huang, Li, Lin & Xi (2011)                             ``saturation="auxiliary"``,
                                                                      ``unsaturated_weight`` (given)
``zhang``      Zhang, Wang & Li (2013)                                ``saturation="auxiliary"``,
                                                                      ``lyapunov="saturation_dependent"``
``wan_huang``  Wan & Kothare (2003) with Huang et al. (2011)          ``cost="nominal"``,
                                                                      ``saturation="auxiliary"``,
                                                                      ``unsaturated_weight`` (given)
``mao_huang``  Mao (2003) with Huang et al. (2011)                    ``lyapunov="vertex_pairs"``,
                                                                      ``saturation="auxiliary"``,
                                                                      ``unsaturated_weight`` (given)
``wan_zhang``  Wan & Kothare (2003) with Zhang et al. (2013)          ``cost="nominal"``,
                                                                      ``saturation="auxiliary"``,
                                                                      ``lyapunov="saturation_dependent"``
=============  =====================================================  =================================

Huang et al.'s keys take the weight ``beta`` as ``unsaturated_weight`` from the caller (MUP's own
code stops with "Parameter BETA was not defined" without it; its demo sets ``beta = 1e3``).

MUP's four soft-constrained keys (Oravec & Bakošová, 2016) stand for the form of their base key
with soft limits the caller gives; the hard bounds stay hard:

======================  ===================================================
key                     options
======================  ===================================================
``kothare_soft_con``    the defaults
``wan_soft_con``        ``cost="nominal"``
``cao_soft_con``        ``saturation="auxiliary"``
``wan_cao_soft_con``    ``cost="nominal"``, ``saturation="auxiliary"``
======================  ===================================================

The caller gives MUP's ``u_sl, y_sl, Wsu, Wsy, Esu, Esy`` as ``soft={"u": [w_1, ..., w_m],
"u_limit": [l_1, ..., l_m]}`` and/or ``"y": [...]``, ``"y_limit": [...]`` (one entry per input /
output of ``output_matrix``; a weight ``0`` and a limit ``0`` for a component not softened;
:mod:`lmi.forms.soft`).

As in MUP, the input bound is per component (``input_constraint="peak"``) unless the caller
gives ``input_constraint``. Every one of MUP's 19 keys has a form here; where the toolkit's LMIs
differ from MUP's own code (``trace(X)`` in MUP's objectives, its strictness margins, the
terminal ellipsoid of ``shi``, ``Y - E_j Z`` of MUP's ``sdp_shi.m`` as the auxiliary saturation
with ``H = Y - Z``, output bounds at every step and vertex, one family of Lyapunov matrices for
``zhang``, no ``C_v`` factor in ``ding``'s invariance blocks, one block per component for the
soft limits) the page on the forms says so, form by form.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

__all__ = ["METHODS", "NEEDS", "NOT_YET", "SOFT_CON_KEYS", "Method", "method_options"]


@dataclass(frozen=True)
class Method:
    """One method key: who published it and the :class:`~rmpc.RMPC` options it stands for."""

    key: str
    source: str
    options: MappingProxyType
    #: options the key sets unless the caller gives them (shi's ``horizon``)
    defaults: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))


def _method(key: str, source: str, **options: Any) -> Method:
    return Method(key, source, MappingProxyType(options))


#: MUP's keys the toolkit carries exactly, in MUP's order.
METHODS: MappingProxyType = MappingProxyType({m.key: m for m in (
    _method("kothare", "Kothare, Balakrishnan & Morari (1996)"),
    _method("cuzzola", "Cuzzola, Geromel & Morari (2002)", lyapunov="vertex"),
    _method("mao", "Mao (2003)", lyapunov="vertex_pairs"),
    _method("wan", "Wan & Kothare (2003)", cost="nominal"),
    _method("cao", "Cao & Lin (2005)", saturation="auxiliary"),
    _method("mao_cao", "Mao (2003) with Cao & Lin (2005)", lyapunov="vertex_pairs", saturation="auxiliary"),
    _method("wan_cao", "Wan & Kothare (2003) with Cao & Lin (2005)", cost="nominal", saturation="auxiliary"),
    _method("li", "Li, Shi, Sun & Wang (2008)", horizon=2, step_gains="vertex", lyapunov="common"),
    Method("shi", "Shi, Su & Chu (2013)",
           MappingProxyType({"lyapunov": "vertex_pairs", "saturation": "auxiliary"}),
           MappingProxyType({"horizon": 3})),
    _method("kothare_soft_con", "Kothare et al. (1996) with Oravec & Bakosova's soft constraints (2016)"),
    _method("wan_soft_con", "Wan & Kothare (2003) with Oravec & Bakosova's soft constraints (2016)",
            cost="nominal"),
    _method("cao_soft_con", "Cao & Lin (2005) with Oravec & Bakosova's soft constraints (2016)",
            saturation="auxiliary"),
    _method("wan_cao_soft_con", "Wan & Kothare (2003) with Cao & Lin (2005) and Oravec & Bakosova's soft "
            "constraints (2016)", cost="nominal", saturation="auxiliary"),
    _method("ding", "Ding, Xi, Cychowski & O'Mahony (2007)", cost="nominal", lyapunov="vertex_pairs"),
    _method("huang", "Huang, Li, Lin & Xi (2011)", saturation="auxiliary"),
    _method("zhang", "Zhang, Wang & Li (2013)", saturation="auxiliary", lyapunov="saturation_dependent"),
    _method("wan_huang", "Wan & Kothare (2003) with Huang et al. (2011)", cost="nominal",
            saturation="auxiliary"),
    _method("mao_huang", "Mao (2003) with Huang et al. (2011)", lyapunov="vertex_pairs",
            saturation="auxiliary"),
    _method("wan_zhang", "Wan & Kothare (2003) with Zhang et al. (2013)", cost="nominal",
            saturation="auxiliary", lyapunov="saturation_dependent"),
)})

#: MUP's soft-constrained keys: the caller gives the soft limits (``soft`` with ``"u_limit"``
#: and/or ``"y_limit"``).
SOFT_CON_KEYS: frozenset[str] = frozenset(
    {"kothare_soft_con", "wan_soft_con", "cao_soft_con", "wan_cao_soft_con"}
)

#: The keys whose tuning parameter the caller gives (MUP's code has no default either).
NEEDS: MappingProxyType = MappingProxyType({
    "huang": "unsaturated_weight", "wan_huang": "unsaturated_weight", "mao_huang": "unsaturated_weight",
})

#: MUP's keys without a form here (none: every key has one; kept for callers that look keys up).
NOT_YET: MappingProxyType = MappingProxyType({})


def method_options(key: Any, given: dict[str, Any]) -> dict[str, Any]:
    """The :class:`~rmpc.RMPC` keyword arguments of MUP's method ``key`` merged with ``given``.

    Raises
    ------
    InvalidArgumentError
        For a key that is not MUP's (the message lists the keys), a key without a form here yet
        (with the nearest option), an option in ``given`` that the key already sets
        differently, or a tuning parameter the key needs (:data:`NEEDS`) not given.
    """
    if not isinstance(key, str):
        raise ArgumentTypeError("key", "a method key (str)", type(key).__name__)
    if key in NOT_YET:
        raise InvalidArgumentError("key", f"one of {list(METHODS)} (available here)",
                                   f"{key!r}: {NOT_YET[key]}")
    if key not in METHODS:
        raise InvalidArgumentError("key", f"one of MUP's method keys {list(METHODS)}", repr(key))
    options = dict(METHODS[key].options)
    for name, value in options.items():
        if name in given and given[name] != value:
            raise InvalidArgumentError(
                name, f"{value!r} (method {key!r} sets it) or no {name} argument", repr(given[name])
            )
    needed = NEEDS.get(key)
    if needed is not None and given.get(needed) is None:
        raise InvalidArgumentError(
            needed, f"a value for method {key!r} (e.g. {needed}=1e3, MUP's demo; 0 gives 'cao')", "none given"
        )
    merged = {"input_constraint": "peak", **METHODS[key].defaults, **given, **options}
    _check_soft_con(key, merged.get("soft"))
    return merged


def _check_soft_con(key: str, soft: Any) -> None:
    """MUP's ``*_soft_con`` keys need the caller's soft limits (the weights and limits themselves
    are checked by :func:`lmi.forms.options.form_options`)."""
    if key not in SOFT_CON_KEYS:
        return
    if not isinstance(soft, dict) or not ({"u_limit", "y_limit"} & set(soft)):
        raise InvalidArgumentError(
            "soft", f"MUP's soft limits for {key!r}: {{'u': [w_1, ..., w_m], 'u_limit': [l_1, ..., l_m]}} "
            "and/or {'y': [...], 'y_limit': [...]} (a weight and a limit per component, 0 and 0 where not "
            "softened)",
            repr(soft))
