"""
Rows from outside packages: :func:`discovered`
==============================================

The registries of the package — instruments, applications and the rest — take rows from
installed packages the way xarray takes its backends: an entry point of the registry's
group whose value is the row's class. :func:`discovered` is the one reader of such a group.

References
----------
Python Packaging User Guide, "Entry points specification"; xarray, "How to add a new
backend" (the ``xarray.backends`` entry-point group).
"""

from __future__ import annotations

import warnings
from importlib.metadata import entry_points
from typing import Any

__all__ = ["discovered"]


def _package(point: Any) -> str:
    """``", package NAME"`` of an entry point, when its metadata says which (else nothing)."""

    dist = getattr(point, "dist", None)
    name = getattr(dist, "name", None) if dist is not None else None
    return f", package {name}" if name else ""


def discovered(group: str, builtin: tuple[type, ...], base: type) -> dict[str, type]:
    """
    The rows ``builtin`` and those of every installed package's entry point of ``group``,
    by their ``name``. An entry point that cannot be loaded (an import error, a
    ``sys.exit()`` at import), is not a subclass of ``base`` or takes a name already taken
    is left out with a ``RuntimeWarning`` naming it and its package (one broken package
    does not stop the tool).
    """

    word = base.__name__
    found = {row.name: row for row in builtin}
    for point in entry_points(group=group):
        named = f"{word.lower()} entry point {point.name!r} ({point.value}{_package(point)})"
        try:
            row = point.load()
        except KeyboardInterrupt:
            raise
        except BaseException as error:  # an outside package's import error, or its sys.exit(): reported, not fatal
            cause = f"it exited (SystemExit {error.code!r})" if isinstance(error, SystemExit) else \
                f"{type(error).__name__}: {error}"
            warnings.warn(f"{named} could not be loaded: {cause}; left out", RuntimeWarning, stacklevel=3)
            continue
        if not (isinstance(row, type) and issubclass(row, base)):
            warnings.warn(f"{named} is not a virtspec_mi {word} class: left out", RuntimeWarning, stacklevel=3)
        elif row.name in found:
            warnings.warn(f"{named} takes the name {row.name!r}, already taken: left out", RuntimeWarning,
                          stacklevel=3)
        else:
            found[row.name] = row
    return found
