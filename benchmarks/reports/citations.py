"""What is known of each reference paper, and the one-line citation the reports print.

The toolkit reproduces five papers, called by letter: P (robust MPC with a model reference
adaptive system for a three-axis satellite, the main reference), S (a survey of flexible
satellites), W (adaptive actuator-failure compensation on a spacecraft attitude simulator), M
(command-filtered modular adaptive backstepping in modified Rodrigues parameters) and V
(time-varying sliding surface and active vibration control of a flexible spacecraft). All five
are written in Persian. Their source documents give some of each paper's identity and not the
rest; a :class:`Reference` holds what they give and names what they do not, so that a report
says "not known" rather than inventing it. ``docs/citing.rst`` lists the same papers.

Examples
--------
>>> from benchmarks.reports.citations import REFERENCES, citation
>>> REFERENCES["S"].authors
('Mohammad Fathi', 'Hossein Bolandi')
>>> REFERENCES["M"].unknown
('authors', 'title', 'venue', 'year')
>>> print(citation("W"))  # doctest: +NORMALIZE_WHITESPACE
Paper W: design and experimental implementation of an adaptive backstepping actuator-failure
compensator for a spacecraft attitude control simulator (in Persian, with an English abstract;
authors, title, venue and year not known).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from toolkit_common.errors import InvalidArgumentError

__all__ = ["REFERENCES", "Reference", "citation", "citation_line"]

#: The fields a source document may or may not give, in citation order.
FIELDS = ("authors", "title", "venue", "year")


@dataclass(frozen=True)
class Reference:
    """What the source documents give of one reference paper.

    Parameters
    ----------
    key : str
        The paper's letter (``"P"``, ``"S"``, ``"W"``, ``"M"``, ``"V"``).
    subject : str
        What the paper is about, from its English abstract (or its text when it has none).
    language : str
        The language it is written in, and whether it has an English abstract.
    authors : tuple of str
        The authors as the documents give them; empty when not known.
    affiliations : tuple of str
        Each author's affiliation, in the same order; empty when not known.
    title : str or None
        The title; ``None`` when not known.
    title_note : str or None
        What the title is, when it is not the paper's own words (an English rendering of a
        Persian title).
    venue : str or None
        Journal, volume and number; ``None`` when not known.
    year : str or None
        The year as the documents give it; ``None`` when not known.
    """

    key: str
    subject: str
    language: str
    authors: tuple[str, ...] = ()
    affiliations: tuple[str, ...] = ()
    title: str | None = None
    title_note: str | None = None
    venue: str | None = None
    year: str | None = None

    def __post_init__(self) -> None:
        if self.affiliations and len(self.affiliations) != len(self.authors):
            raise InvalidArgumentError(
                "affiliations",
                f"one per author of paper {self.key} ({len(self.authors)}), or none",
                f"{len(self.affiliations)}",
            )
        if self.title_note is not None and self.title is None:
            raise InvalidArgumentError("title_note", "no note without a title", repr(self.title_note))

    @property
    def unknown(self) -> tuple[str, ...]:
        """The fields of ``FIELDS`` (authors, title, venue, year) the source documents do not give."""
        given = {"authors": bool(self.authors), "title": self.title is not None,
                 "venue": self.venue is not None, "year": self.year is not None}
        return tuple(f for f in FIELDS if not given[f])


def _names(authors: tuple[str, ...]) -> str:
    if len(authors) <= 2:
        return " and ".join(authors)
    return ", ".join(authors[:-1]) + " and " + authors[-1]


#: The reference papers by key (read-only).
REFERENCES: Mapping[str, Reference] = MappingProxyType({
    "P": Reference(
        key="P",
        subject=(
            "robust MPC improved by a model reference adaptive system (CRMPC) for a three-degree-of-freedom "
            "satellite, robust to inertia uncertainty and external disturbance, compared with generalized "
            "incremental predictive control (GIPC)"
        ),
        language="in Persian, with an English abstract",
        authors=("Fatemeh Pirouzmand", "Nematollah Ghahramani", "Mohammadreza Arvan"),
        affiliations=(
            "Islamic Azad University, Science and Research Branch, Borujerd",
            "Malek Ashtar University of Technology, Tehran",
            "Malek Ashtar University of Technology, Tehran",
        ),
        title=(
            "Design of a robust predictive controller using linear matrix inequalities for a satellite "
            "attitude control system"
        ),
        title_note="English rendering of the Persian title, not the paper's own",
        venue=(
            "Tabriz Journal of Electrical Engineering (Journal of Electrical Engineering, University of "
            "Tabriz), Vol. 44, No. 4, serial No. 70"
        ),
        year="Winter 2014",
    ),
    "S": Reference(
        key="S",
        subject=(
            "a survey of flexible satellites: dynamic analysis, challenges and attitude control strategies"
        ),
        language="in Persian, with an English abstract",
        authors=("Mohammad Fathi", "Hossein Bolandi"),
        affiliations=(
            "Iran University of Science and Technology, Electrical Engineering Department",
            "Iran University of Science and Technology, Electrical Engineering Department",
        ),
        title="Survey on flexible satellite: dynamic analysis, challenges and attitude control strategies",
    ),
    "W": Reference(
        key="W",
        subject=(
            "design and experimental implementation of an adaptive backstepping actuator-failure compensator "
            "for a spacecraft attitude control simulator"
        ),
        language="in Persian, with an English abstract",
    ),
    "M": Reference(
        key="M",
        subject=(
            "command-filtered modular adaptive backstepping attitude control in modified Rodrigues "
            "parameters with a nonlinear extended state observer"
        ),
        language="in Persian, with no English metadata",
    ),
    "V": Reference(
        key="V",
        subject=(
            "a time-varying sliding surface and robust active vibration control by PZT patches on the "
            "flexible appendages of a spacecraft, compared with conventional sliding mode control"
        ),
        language="in Persian, with an English abstract",
    ),
})


def citation(key: str) -> str:
    """The one-line citation of paper ``key``: what is known of it, and what is not.

    Parameters
    ----------
    key : str
        A key of :data:`REFERENCES` (``"P"``, ``"S"``, ``"W"``, ``"M"`` or ``"V"``).

    Returns
    -------
    str
        ``Paper <key>: <authors>, "<title>" (<title note>), <venue>, <year> (<language>; <unknown>
        not known).``, each part only when known; without a title, the paper's subject stands in
        its place.

    Examples
    --------
    >>> print(citation("S"))  # doctest: +NORMALIZE_WHITESPACE
    Paper S: Mohammad Fathi and Hossein Bolandi, "Survey on flexible satellite: dynamic analysis,
    challenges and attitude control strategies" (in Persian, with an English abstract; venue and year
    not known).
    """
    if not isinstance(key, str) or key not in REFERENCES:
        raise InvalidArgumentError("key", f"one of {', '.join(sorted(REFERENCES))}", repr(key))
    ref = REFERENCES[key]
    parts = []
    if ref.authors:
        parts.append(_names(ref.authors))
    if ref.title is not None:
        parts.append(f'"{ref.title}"' + (f" ({ref.title_note})" if ref.title_note else ""))
    else:
        parts.append(ref.subject)
    if ref.venue is not None:
        parts.append(ref.venue)
    if ref.year is not None:
        parts.append(ref.year)
    notes = [ref.language]
    if ref.unknown:
        notes.append(f"{_names(ref.unknown)} not known")
    return f"Paper {key}: " + ", ".join(parts) + f" ({'; '.join(notes)})."


def citation_line(*keys: str) -> str:
    """The line a report prints under its title: the citation of each paper it reproduces.

    Parameters
    ----------
    *keys : str
        The papers' keys, in the order the report names them; at least one.

    Examples
    --------
    >>> citation_line("P").startswith("Paper P: Fatemeh Pirouzmand, Nematollah Ghahramani and ")
    True
    """
    if not keys:
        raise InvalidArgumentError("keys", "at least one paper's key", "none")
    return " ".join(citation(k) for k in keys)
