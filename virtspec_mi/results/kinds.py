"""
Every result kind, by its format tag: :func:`read_result`
=========================================================

The result kinds (:data:`virtspec_mi.results.base.KINDS`: every class that declares a
format tag registers itself there when defined — hemispherical
(:class:`~virtspec_mi.results.readings.Result`, format ``"virtspec-mi result 1"``),
goniophotometer (:class:`~virtspec_mi.instruments.goniophotometer.result.GonioResult`,
``"virtspec-mi gonio 1"``), integrating sphere
(:class:`~virtspec_mi.instruments.sphere.result.SphereResult`, ``"virtspec-mi sphere 1"``) and any
instrument's own, e.g. the gloss meter's; the applications' records, :mod:`virtspec_mi.results.records`:
a certified target, a fit, an albedo table, Klems matrices, a comparison) and :func:`read_result`, which reads a file of
any of them (NetCDF, CSV, JSON, Zarr; also ``virtspec measure --json`` output and files
written before every kind had a tag) by the tag it carries
(:func:`virtspec_mi.results.formats.tagged`). :func:`virtspec_mi.read_result` loads the
instruments' and the applications' registries first, so that every kind is known.

References
----------
xarray / NetCDF conventions; :mod:`virtspec_mi.results.io`.
"""

from __future__ import annotations

import os
from typing import Any

from virtspec_mi.results import io as results_io
from virtspec_mi.results import readings  # noqa: F401  (the shared kind registers; the instruments register theirs)
from virtspec_mi.results.base import KINDS, ResultBase, holder
from virtspec_mi.results.formats import format_parts, tagged
from virtspec_mi.results.integrity import read_file

__all__ = ["KINDS", "kind_of", "read_result", "result_from"]


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
    every rule of :mod:`virtspec_mi.results.integrity`; an export that a result file
    accompanies (a Klems XML file, an albedo table's ``.npy``) is read from that file
    (:data:`~virtspec_mi.results.base.COMPANIONS`): ``FileNotFoundError`` if it is
    missing, a one-line ``ValueError`` naming the file and the field if it is not a result
    or breaks a rule.
    """

    return read_file(holder(path), results_io.read, result_from)
