"""
What a result file carries: format tags, units and long names
==============================================================

- **Format tags** (:func:`format_parts`, :func:`tagged`): every result kind's files carry
  ``"virtspec-mi <word> <version>"`` — ``result`` (hemispherical), ``gonio``, ``sphere`` —
  in the JSON object (``format``) and in every dataset (attributes ``format`` and
  ``result_json``, the whole result as JSON). :func:`tagged` finds the tag and the data of
  what :func:`virtspec_mi.results.io.read` read, also in files written before every kind
  had one (a goniophotometer dataset's ``gonio_json``; a sphere result's
  ``"kind": "sphere_result"`` layout, tagged ``"virtspec-mi sphere 0"``).
- **Units and long names** (:data:`VARIABLES`, :func:`annotate`): one table of
  ``(units, long_name)`` for the variables and coordinates every result shares, and each
  kind's own table of its variables (its ``VARIABLES``, in its instrument's folder)
  (UDUNITS spellings: ``nm``, ``degree``, ``sr``, ``1/sr``, ``1`` for fractions and counts).

References
----------
CF Conventions 1.11, Sect. 3.1 (``units``) and 3.2 (``long_name``); xarray / NetCDF conventions.
"""

from __future__ import annotations

import json
import re
from typing import Any, Mapping

from virtspec_mi.results.integrity import unsealed

__all__ = ["VARIABLES", "TABLE_ATTRIBUTE", "describe_variable", "annotate", "format_parts", "tagged"]

_TAG = re.compile(r"^virtspec-mi (?P<word>[a-z]+(?: [a-z]+)*) (?P<version>\d+)$")

_COUNT = "1"
VARIABLES: dict[str, tuple[str, str]] = {
    # coordinates
    "wavelength": ("nm", "wavelength"),
    "theta_i": ("degree", "polar angle of incidence"),
    "point": ("1", "parameter point"),
    # exact counts
    "rays": (_COUNT, "rays traced per reading (N)"),
    "reflected": (_COUNT, "rays reflected into the upper hemisphere"),
    "transmitted": (_COUNT, "rays transmitted into the lower hemisphere"),
    "capped": (_COUNT, "random walks stopped by the specimen's step cap (in no fate)"),
    "invalid_directions": (_COUNT, "rays the BSDF sent in an invalid direction (in no fate)"),
    "weight_violations": (_COUNT, "rays whose BSDF weight was outside [0, 1] beyond rounding"),
    "rounded_weights": (_COUNT, "rays whose BSDF weight was rounded into [0, 1]"),
    "specular_reflected": (_COUNT, "reflected rays whose sampled event was a delta event"),
    "regular_transmitted": (_COUNT, "transmitted rays whose sampled event was a delta event"),
    "largest_weight": ("1", "largest violating BSDF weight (NaN: none)"),
    "done": ("1", "the reading has finished (1) or not yet (0)"),
}
"""
``(units, long_name)`` of the labels and the exact counts that every result kind shares
(what a kind derives from them: its ``DERIVED`` table, :mod:`virtspec_mi.results.variables`).
"""


def describe_variable(name: str, parameters: Mapping[str, str] | None = None,
                      own: Mapping[str, tuple[str, str]] | None = None) -> tuple[str, str]:
    """
    ``(units, long_name)`` of a dataset variable or coordinate: from :data:`VARIABLES` or
    the kind's ``own`` table, a two-stage pilot's ``pilot_<count>``, or a swept specimen
    parameter (``parameters``: name → ``mi.traverse`` key; its unit is the specimen
    plugin's own, not known here). ``KeyError`` for any other name.
    """

    table = {**VARIABLES, **(own or {})}
    if name in table:
        return table[name]
    if name.startswith("pilot_") and name[6:] in table:
        units, long_name = table[name[6:]]
        return units, f"two-stage pilot (spent, not in the estimates): {long_name}"
    if parameters is not None and name in parameters:
        return "as in the specimen plugin", f"specimen parameter {name} (mi.traverse key {parameters[name]})"
    raise KeyError(f"no units and long_name for the dataset variable {name!r}: add it to "
                   "virtspec_mi.results.formats.VARIABLES or the kind's own VARIABLES")


def annotate(dataset: Any, parameters: Mapping[str, str] | None = None,
             own: Mapping[str, tuple[str, str]] | None = None) -> Any:
    """
    ``dataset`` with ``units`` and ``long_name`` on every variable and coordinate
    (:func:`describe_variable`; ``own``: the result kind's own table).
    """

    for name in (*dataset.data_vars, *dataset.coords):
        units, long_name = describe_variable(str(name), parameters, own)
        dataset[name].attrs.update(units=units, long_name=long_name)
    return dataset


# -- format tags ----------------------------------------------------------------------


def format_parts(tag: Any) -> tuple[str, int]:
    """
    ``("gonio", 1)`` of ``"virtspec-mi gonio 1"`` (a word may be several, ``"virtspec-mi albedo table 1"``);
    ``ValueError`` for anything else.
    """

    match = _TAG.match(tag) if isinstance(tag, str) else None
    if match is None:
        raise ValueError(f"not a virtspec-mi result (format {tag!r})")
    return match["word"], int(match["version"])


TABLE_ATTRIBUTE: str = "virtspec_table"
"""The attribute of a sweep's Zarr table that holds its labels, settings and format (JSON; :mod:`virtspec_mi.results.zarr`)."""


def tagged(content: tuple[str, Any]) -> tuple[str, Any]:
    """
    ``(format tag, data)`` of what :func:`virtspec_mi.results.io.read` read: the JSON
    object (``"plain"``), a dataset's (``"dataset"``; a CSV file's, ``"rows"``)
    ``result_json`` attribute, or a sweep's Zarr table (``"table"``: the dataset itself
    is the data, tagged by its :data:`TABLE_ATTRIBUTE`). Files written before the tags
    of every kind: a goniophotometer dataset's ``gonio_json``; a sphere result's
    ``"kind": "sphere_result"`` JSON object or its NetCDF dataset (``json`` attribute and
    the counts as variables) are tagged ``"virtspec-mi sphere 0"`` (the dataset itself is
    the data); a comparison's JSON object without a tag (its figures: ``measured_source``,
    ``residuals``, ``within``, ``rmse``) ``"virtspec-mi comparison 0"``; an application's NetCDF file written before the result family (a fit, an
    albedo table, a Klems sidecar: a ``format`` attribute, no ``result_json``) by its
    ``format`` (the dataset itself is the data, read by the kind's ``_from_plain``).
    ``ValueError`` if it is no result.
    """

    kind, value = content
    if kind == "plain":
        if value.get("kind") == "sphere_result":
            return "virtspec-mi sphere 0", value
        if "format" not in value and {"measured_source", "residuals", "within", "rmse"} <= set(value):
            return "virtspec-mi comparison 0", value  # `virtspec compare --json` before the comparison had a tag
        return str(value.get("format")), value
    attrs = value.attrs
    names = (TABLE_ATTRIBUTE,) if kind == "table" else ("result_json", "gonio_json")
    for name in names:
        if name in attrs:
            try:
                data = json.loads(attrs[name])
            except (TypeError, json.JSONDecodeError, RecursionError) as error:
                raise ValueError(f"not a virtspec-mi result (its {name} attribute is not JSON: {error})") from None
            if not isinstance(data, dict):
                raise ValueError(f"not a virtspec-mi result (its {name} attribute is not a JSON object)")
            return str(data.get("format")), (value if kind == "table" else unsealed(attrs[name], data))
    if "json" in attrs and "rays" in attrs and "sphere" in attrs:
        return "virtspec-mi sphere 0", value
    if kind == "dataset" and isinstance(attrs.get("format"), str) and _TAG.match(attrs["format"]):
        return attrs["format"], value  # a kind's NetCDF file written before its result_json (a fit, a table, Klems)
    raise ValueError("not a virtspec-mi result (no result_json attribute)")
