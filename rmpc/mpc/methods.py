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

As in MUP, the input bound is per component (``input_constraint="peak"``) unless the caller
gives ``input_constraint``. MUP's other keys (``ding``, ``li``, ``shi`` and the ``*_soft_con``
variants, whose soft limits are separate from the hard bounds with one slack per component) have
no form here yet: asked for by name they are refused with the nearest option the toolkit has.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

__all__ = ["METHODS", "NEEDS", "NOT_YET", "Method", "method_options"]


@dataclass(frozen=True)
class Method:
    """One method key: who published it and the :class:`~rmpc.RMPC` options it stands for."""

    key: str
    source: str
    options: MappingProxyType


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
    _method("huang", "Huang, Li, Lin & Xi (2011)", saturation="auxiliary"),
    _method("zhang", "Zhang, Wang & Li (2013)", saturation="auxiliary", lyapunov="saturation_dependent"),
    _method("wan_huang", "Wan & Kothare (2003) with Huang et al. (2011)", cost="nominal",
            saturation="auxiliary"),
    _method("mao_huang", "Mao (2003) with Huang et al. (2011)", lyapunov="vertex_pairs",
            saturation="auxiliary"),
    _method("wan_zhang", "Wan & Kothare (2003) with Zhang et al. (2013)", cost="nominal",
            saturation="auxiliary", lyapunov="saturation_dependent"),
)})

#: The keys whose tuning parameter the caller gives (MUP's code has no default either).
NEEDS: MappingProxyType = MappingProxyType({
    "huang": "unsaturated_weight", "wan_huang": "unsaturated_weight", "mao_huang": "unsaturated_weight",
})

#: MUP's keys without a form here yet, with the nearest option the toolkit has.
NOT_YET: MappingProxyType = MappingProxyType({
    "ding": "cost='nominal' with lyapunov='vertex_pairs' (Ding et al. 2007) is not a form yet; "
            "nearest: 'wan' or 'mao'",
    "li": "the two-step gains of Li et al. (2008) are not a form yet; nearest: 'mao'",
    "shi": "the N-step chained Lyapunov matrices of Shi et al. (2013) are not a form yet; nearest: 'mao'",
    "kothare_soft_con": "MUP's soft limits (separate from the hard bounds, one slack per component) "
                        "are not a form yet; nearest: 'kothare' with soft={'u': w_u, 'y': w_y} (the "
                        "bounds themselves softened, one slack per family)",
    "wan_soft_con": "MUP's per-component soft limits are not a form yet; nearest: 'wan' with soft=...",
    "cao_soft_con": "MUP's per-component soft limits are not a form yet; nearest: 'cao' with soft=...",
    "wan_cao_soft_con": "MUP's per-component soft limits are not a form yet; "
                        "nearest: 'wan_cao' with soft=...",
})


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
    merged = {"input_constraint": "peak", **given, **options}
    return merged
