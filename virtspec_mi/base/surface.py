"""
Who reads a message: the Python API or the command line
========================================================

A message that names how to do something names it as its reader would write it: a
Python user reads ``vm.band('B04', tolerance=0.002)`` and ``result.readings``, a
command-line user ``--target band:B04,tolerance=0.002`` and ``--json``. The command
line runs its command inside :func:`command_line`; a message with two wordings is built
by :func:`spoken` (the one place that chooses), never by a test of its own. On the
command line a warning is one line, ``virtspec: warning: ...`` (not Python's file, line,
category and source line).
"""

from __future__ import annotations

import warnings
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Iterator

__all__ = ["command_line", "on_command_line", "spoken"]

_SURFACE: ContextVar[str] = ContextVar("virtspec_mi_surface", default="api")


@contextmanager
def command_line() -> Iterator[None]:
    """Within: messages are read on the command line (``virtspec``)."""

    token = _SURFACE.set("cli")
    shown = warnings.formatwarning
    warnings.formatwarning = _one_line
    try:
        yield
    finally:
        _SURFACE.reset(token)
        warnings.formatwarning = shown


def _one_line(message: Warning | str, category: type[Warning], filename: str, lineno: int,
              line: str | None = None) -> str:
    return f"virtspec: warning: {message}\n"


def on_command_line() -> bool:
    """Whether the message being built is read on the command line."""

    return _SURFACE.get() == "cli"


def spoken(api: str, cli: str) -> str:
    """``api`` (as Python writes it) or ``cli`` (as the command line writes it), for the reader of this call."""

    return cli if on_command_line() else api
