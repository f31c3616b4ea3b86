"""``save(path)`` for every controller a user designs (a mixin), and the hooks a class writes.

A class that inherits :class:`Saveable` writes :meth:`Saveable._design` (its design as JSON
values, :func:`rmpc.io.design.encode`) and :meth:`Saveable._from_design` (the class built back
from a :class:`~rmpc.io.design.Design` without designing or solving anything), and is listed in
:data:`rmpc.io.registry.KINDS`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Self

from rmpc.io.design import Design
from rmpc.io.format import write_file
from rmpc.io.registry import kind_of

__all__ = ["Saveable"]


class Saveable:
    """The ``save(path)`` of controllers and estimators; :func:`rmpc.load` reads the file back."""

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the design to ``path`` (a versioned JSON file, ``docs/save_load.rst``); ``rmpc.load(path)``
        builds the same controller back.

        The file holds the design (the plant polytope, weights, bounds, options, tables and
        gains), no solver object and no run-time state (warm starts, the last step, an
        adaptation's estimate): the loaded controller is as this one after ``reset()``. The
        file is written to a temporary file beside ``path`` and moved over it, so an
        interrupted save leaves no half file.

        Returns
        -------
        Path
            ``path``.

        Raises
        ------
        ControllerFileError
            When ``path`` is a directory, its folder does not exist or it cannot be written.
        InvalidArgumentError
            When there is nothing designed to save yet, or the design holds what a file cannot
            (a user's function, an object among the solver options).
        """
        kind = kind_of(self)
        return write_file(path, kind, self._design())

    def _design(self) -> dict[str, Any]:
        """The design as JSON values (:func:`rmpc.io.design.encode`)."""
        raise NotImplementedError(f"{type(self).__name__} does not write a design")

    @classmethod
    def _from_design(cls, design: Design) -> Self:
        """The object built back from ``design`` (every field read through its getters)."""
        raise NotImplementedError(f"{cls.__name__} does not read a design")
