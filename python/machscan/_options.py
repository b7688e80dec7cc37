"""What every options object of machscan shares (GrooveOptions, InspectionOptions, IcpCriteria):
a call's keyword changes made to it, with an error that names an unknown option."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields, replace
from typing import Any, TypeVar

__all__ = ["changed"]

Options = TypeVar("Options")


def changed(options: Options, changes: Mapping[str, Any], where: str) -> Options:
    """``dataclasses.replace(options, **changes)``; a name that is not a field of ``options`` is a
    ``TypeError`` naming it, ``where`` (the call it was given to) and the known ones."""
    if not changes:
        return options
    known = {f.name for f in fields(options)}  # type: ignore[arg-type]
    unknown = sorted(set(changes) - known)
    if unknown:
        raise TypeError(f"{where}: unknown option {unknown[0]!r}; the options are {', '.join(sorted(known))}")
    return replace(options, **changes)  # type: ignore[type-var]
