"""
Every result kind, by its format tag: :func:`read_result`
=========================================================

One table (:data:`KINDS`) of the result kinds of :mod:`virtspec_mi.results` —
hemispherical (:class:`~virtspec_mi.results.hemispherical.Result`, format
``"virtspec-mi result 1"``), goniophotometer
(:class:`~virtspec_mi.results.goniophotometer.GonioResult`, ``"virtspec-mi gonio 1"``) and
integrating sphere (:class:`~virtspec_mi.results.sphere.SphereResult`,
``"virtspec-mi sphere 1"``) — and :func:`read_result`, which reads a file of any of them
(NetCDF, CSV, JSON, Zarr; also ``virtspec measure --json`` output and files written
before every kind had a tag) by the tag it carries
(:func:`virtspec_mi.results.base.tagged`). A new kind is one module and one row here.

References
----------
xarray / NetCDF conventions; :mod:`virtspec_mi.results.io`.
"""

from __future__ import annotations

import os
from typing import Any

from virtspec_mi.results import io as results_io
from virtspec_mi.results.base import ResultBase
from virtspec_mi.results.formats import format_parts, tagged
from virtspec_mi.results.goniophotometer import GonioResult
from virtspec_mi.results.hemispherical import Result
from virtspec_mi.results.integrity import read_file
from virtspec_mi.results.sphere import SphereResult

__all__ = ["KINDS", "kind_of", "read_result", "result_from"]

KINDS: dict[str, type[ResultBase]] = {format_parts(kind.FORMAT)[0]: kind for kind in (Result, GonioResult,
                                                                                      SphereResult)}
"""Each result kind by the word of its format tag (``"result"``, ``"gonio"``, ``"sphere"``)."""


def kind_of(tag: str) -> type[ResultBase]:
    """The result kind of a format tag; ``ValueError`` naming the kinds for any other."""

    word, _ = format_parts(tag)
    if word not in KINDS:
        raise ValueError(f"not a virtspec-mi result kind: format {tag!r} (kinds: "
                         f"{', '.join(kind.FORMAT for kind in KINDS.values())})")
    return KINDS[word]


def result_from(content: tuple[str, Any]) -> ResultBase:
    """The result of what :func:`virtspec_mi.results.io.read` read (``("dataset", …)`` or ``("plain", …)``)."""

    tag, data = tagged(content)
    return kind_of(tag).from_tagged(tag, data)


def read_result(path: str | os.PathLike) -> Any:
    """
    The result in ``path``, whatever its kind (a hemispherical reading or sweep, a
    goniophotometer reading, a sphere reading): ``.nc``, ``.csv``, ``.json`` or ``.zarr``
    as written by its ``write`` (or printed by ``virtspec measure --json``), checked by
    every rule of :mod:`virtspec_mi.results.integrity`: ``FileNotFoundError`` if it is
    missing, a one-line ``ValueError`` naming the file and the field if it is not a result
    or breaks a rule.
    """

    return read_file(path, results_io.read, result_from)
