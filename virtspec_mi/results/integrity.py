"""
What a result file must hold: the rules checked when one is read
================================================================

Every result file — any kind (hemispherical, goniophotometer, sphere, an application's), any format
(NetCDF, CSV, JSON, Zarr, ``virtspec measure --json`` output) — is read as strictly as
user input: one rule is written once, here, and every kind and format goes through it.
A file that breaks one raises a one-line ``ValueError`` naming the file and the field,
e.g. ``result file x.nc: 'reflected' holds a count above 'rays' (reading
wavelength=551, theta_i=30)``. The rules:

1. **Counts are whole numbers** ≥ 0 (:func:`whole_counts`): not fractions, text,
   booleans, NaN or infinities, and within ``int64``.
2. **Labels are finite numbers** (:func:`finite_labels`); a dim's labels are one per
   position; wavelengths lie in :data:`~virtspec_mi.base.checks.WAVELENGTH_RANGE` and θi in
   [0°, 90°]; the labels of θi and of a parameter grid are distinct, a list of points
   is numbered 0 … n − 1 (:func:`check_labels`). Labels are kept in the order they
   were asked for (a reading's wavelengths need not be sorted, nor distinct: a
   reading may repeat one).
3. **Shapes match the dims**: every stored array has one entry per label of each of its
   dims (:func:`check_shapes`).
4. **Counts add up as the kind says** (:func:`check_counts`, with each kind's
   :class:`CountRules`): every part between 0 and its whole (reflected ≤ rays, specular
   reflected ≤ reflected, a goniophotometer's bins of each hemisphere ≤ its reflected
   or transmitted rays …), parts that must sum to the rays do (a sphere
   configuration's fates), rays ≥ 1.
5. **The format tag and version** are the kind's (:meth:`~virtspec_mi.results.base.ResultBase.from_tagged`).
6. **What the file shows agrees with what it rebuilds** (:func:`check_agreement`): every
   count a file holds besides the data it is rebuilt from — a dataset's count variables
   and coordinates, a CSV file's rows, a JSON object's derived ``absorbed`` (each kind's
   ``_check_stored``) — equals the rebuilt result's, so an edited variable is refused
   rather than silently ignored; a kind that shows more than counts (an application's
   record, :mod:`virtspec_mi.results.records`) checks every value and attribute it shows
   (its ``_agreement``).
7. **The checksum** (:func:`checksum`): files written by this version carry the SHA-256
   of their content (``checksum``); content changed after writing (an edit, a damaged
   file) no longer matches and is refused — checked last, so a broken rule is named
   first. Files without one (written before, or by hand) are read by the rules alone.

:func:`read_file` applies them to a file (and names it in every message).

References
----------
xarray / NetCDF conventions; FIPS 180-4 (SHA-256).
"""

from __future__ import annotations

import errno
import fnmatch
import hashlib
import json
import os
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from virtspec_mi.base.checks import WAVELENGTH_RANGE

__all__ = [
    "CountRules",
    "whole_counts",
    "finite_labels",
    "optional_numbers",
    "parameters_of",
    "source_of",
    "field_value",
    "check_labels",
    "check_shapes",
    "check_counts",
    "reading_at",
    "check_result",
    "check_settings",
    "agree_stored",
    "CHECKSUM",
    "checksum",
    "sealed_text",
    "unsealed",
    "check_checksum",
    "check_agreement",
    "agree_values",
    "read_file",
    "MissingFile",
]

_INT64 = np.iinfo(np.int64).max
_EXACT = 2.0**53  # floats hold every whole number up to here


# -- 1. counts ------------------------------------------------------------------------


def whole_counts(values: Any, field_name: str) -> np.ndarray:
    """
    ``values`` (nested lists, an array of any dtype) as an ``int64`` array when every
    entry is a whole number ≥ 0 (an integral float, e.g. 3.0, is one); else
    ``ValueError`` naming ``field_name``, the entry and its position, e.g. ``'reflected'
    holds 18.5 at index [1, 2, 0], not a whole number``.
    """

    try:
        array = np.asarray(values)
    except (ValueError, TypeError):
        raise ValueError(f"{_quoted(field_name)} is not an array of counts (ragged or not numbers)") from None
    kind = array.dtype.kind
    listed = isinstance(values, (list, tuple))
    if kind in "USOb" or (listed and _holds_bool(values)):  # text, null, true/false or mixed: entry by entry
        return _whole_objects(np.array(values, dtype=object) if listed else array.astype(object), field_name)
    if kind not in "iuf":
        raise ValueError(f"{_quoted(field_name)} holds {array.dtype} values, not counts")
    with np.errstate(invalid="ignore"):
        finite = np.isfinite(array) if kind == "f" else np.ones(array.shape, dtype=bool)
        rules = ((~finite, "not a whole number"), (array < 0, "a negative count"),
                 (finite & (array != np.floor(array)) if kind == "f" else ~finite, "not a whole number"),
                 (array > (_EXACT if kind == "f" else _INT64), "beyond the counts a file holds exactly"))
    for bad, why in rules:
        if np.any(bad):
            raise ValueError(_entry(field_name, array, bad, why))
    return array.astype(np.int64)


def _holds_bool(values: Any) -> bool:
    """Whether nested lists hold a ``bool`` (numpy would take ``True`` for 1): one pass over their entries' types."""

    try:
        objects = np.array(values, dtype=object)
    except (ValueError, TypeError):
        return False
    return bool({bool, np.bool_} & set(map(type, objects.ravel().tolist())))


def _whole_objects(array: np.ndarray, field_name: str) -> np.ndarray:
    """Counts of mixed Python values (JSON lists): each an int (not a bool) or an integral float."""

    out = np.empty(array.shape, dtype=np.int64)
    for index, value in np.ndenumerate(array):
        why = None
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            why = "not a count"
        elif isinstance(value, (float, np.floating)) and (not np.isfinite(value) or value != int(value)):
            why = "not a whole number"
        elif value < 0:
            why = "a negative count"
        elif value > (_EXACT if isinstance(value, (float, np.floating)) else _INT64):
            why = "beyond the counts a file holds exactly"
        if why is not None:
            raise ValueError(_entry(field_name, array, index, why))
        out[index] = int(value)
    return out


def _entry(field_name: str, array: np.ndarray, where: Any, why: str) -> str:
    """``'name' holds VALUE at index [i, j], WHY`` of the entry at ``where`` (an index, or the first of a mask)."""

    if isinstance(where, np.ndarray):
        where = tuple(int(i) for i in np.argwhere(np.atleast_1d(where))[0]) if array.ndim else ()
    value = array[where] if array.ndim else array[()]
    value = value.item() if hasattr(value, "item") else value
    shown = _short(value) if not isinstance(value, int) or abs(value) < 10**30 else "a number of " \
        f"{len(str(abs(value)))} digits"
    at = f" at index {list(where)}" if where else ""
    return f"{_quoted(field_name)} holds {shown}{at}, {why}"


def _first(array: np.ndarray, bad: np.ndarray) -> str:
    """`` (… at index […])`` of the first flagged entry."""

    index = tuple(int(i) for i in np.argwhere(bad)[0]) if array.ndim else ()
    value = array[index] if array.ndim else array[()]
    shown = repr(value.item() if hasattr(value, "item") else value)
    return f" ({shown}" + (f" at index {list(index)})" if index else ")")


def _quoted(name: str) -> str:
    return name if name.startswith(("'", "the ", "counts[", "pilot")) else f"'{name}'"


# -- 2. labels ------------------------------------------------------------------------


def finite_labels(values: Any, field_name: str) -> np.ndarray:
    """``values`` as a ``float64`` array of finite numbers (not text, not true/false); else ``ValueError`` naming ``field_name``."""

    array = optional_numbers(values, field_name)
    bad = ~np.isfinite(array)
    if np.any(bad):
        raise ValueError(_entry(field_name, array, bad, "not a finite number"))
    return array


def optional_numbers(values: Any, field_name: str) -> np.ndarray:
    """``values`` as a ``float64`` array of real numbers, ``None`` (JSON's null) and NaN as NaN; else ``ValueError``."""

    try:
        array = np.asarray(values)
    except (ValueError, TypeError):
        raise ValueError(f"{_quoted(field_name)} must hold numbers or null (got {_short(values)})") from None
    listed = isinstance(values, (list, tuple))
    if array.dtype.kind in "iuf" and not (listed and _holds_bool(values)):
        return array.astype(np.float64)
    objects = np.array(values, dtype=object) if listed else array.astype(object)
    if set(map(type, objects.ravel().tolist())) <= {int, float, type(None)}:  # JSON's numbers and nulls
        try:
            return np.where(np.equal(objects, None), np.nan, objects).astype(np.float64)
        except OverflowError:  # an int beyond the float range: named below
            pass
    for index, value in np.ndenumerate(objects):
        if value is None:
            continue
        if isinstance(value, (bool, np.bool_)) or not _real(value) or not abs(value) <= sys.float_info.max:
            raise ValueError(_entry(field_name, objects, index, "not a number or null"))
    raise ValueError(f"{_quoted(field_name)} must hold numbers or null")


_KINDS: dict[str, tuple[str, Callable[[Any], bool]]] = {
    "text": ("text", lambda v: isinstance(v, str)),
    "flag": ("true or false", lambda v: isinstance(v, (bool, np.bool_))),
    "object": ("an object", lambda v: isinstance(v, Mapping)),
    "seconds": ("a finite number >= 0", lambda v: _real(v) and np.isfinite(v) and v >= 0),
    "number or null": ("a finite number or null", lambda v: v is None or (_real(v) and np.isfinite(v))),
}


def _real(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def field_value(data: Mapping[str, Any], key: str, kind: str) -> Any:
    """
    ``data[key]`` when it is of ``kind`` — ``text``, ``flag``, ``object``, ``seconds`` (a
    finite number ≥ 0), ``number or null`` —; ``KeyError`` if missing, else ``ValueError``
    naming the field.
    """

    value = data[key]
    words, test = _KINDS[kind]
    if not test(value):
        raise ValueError(f"'{key}' must be {words} (got {_short(value)})")
    return dict(value) if kind == "object" else value


def _short(values: Any) -> str:
    text = repr(values)
    return text if len(text) <= 60 else text[:57] + "..."


def parameters_of(parameters: Any) -> dict | None:
    """A result's swept parameters (``None``, or an object with distinct ``names``); else ``ValueError``."""

    if parameters is None:
        return None
    names = parameters.get("names") if isinstance(parameters, Mapping) else None
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names) or len(set(names)) != len(names):
        raise ValueError(f"'parameters' must be null or an object with distinct 'names' (got {_short(parameters)})")
    return dict(parameters)


def source_of(source: Any) -> dict | None:
    """
    A result's scene source (``None`` — files written before it was recorded — or an object
    with a ``scene`` name and its ``defines``, names to strings); else ``ValueError``.
    """

    if source is None:
        return None
    defines = source.get("defines") if isinstance(source, Mapping) else None
    if (not isinstance(source, Mapping) or set(source) != {"scene", "defines"} or not isinstance(source["scene"], str)
            or not isinstance(defines, Mapping)
            or not all(isinstance(k, str) and isinstance(v, str) for k, v in defines.items())):
        raise ValueError(f"'source' must be null or an object of a 'scene' name and its 'defines' (names to strings) "
                         f"(got {_short(source)})")
    return {"scene": source["scene"], "defines": dict(defines)}


_LABEL_RANGES: dict[str, tuple[float, float, str]] = {
    "wavelength": (*WAVELENGTH_RANGE, "nm"),
    "theta_i": (0.0, 90.0, "degrees"),
}


def check_labels(dims: tuple[str, ...], coords: Mapping[str, Any], parameters: Mapping[str, Any] | None,
                 kind_dims: tuple[str, ...] = ()) -> None:
    """
    The labels of a result (rule 2 of the module docstring): every dim has a 1-d
    coordinate of at least one label, every other coordinate is a scalar (or lies along
    ``point``), wavelengths and θi in range, θi and parameter grid labels distinct,
    points numbered 0 … n − 1. ``kind_dims``: the kind's own dims (checked by the kind).
    """

    if len(set(dims)) != len(dims) or not all(isinstance(d, str) for d in dims):
        raise ValueError(f"'dims' must be distinct names (got {list(dims)})")
    names = set(() if parameters is None else parameters.get("names", ()))
    for dim in dims:
        if dim not in coords:
            raise ValueError(f"dim {dim!r} has no coordinate")
    for name, values in coords.items():
        if name in kind_dims:
            continue
        array = np.asarray(values)
        along = (name,) if name in dims else ("point",) if "point" in dims and name in names else ()
        if array.ndim != len(along):
            expected = f"one label per position of {along[0]!r}" if along else "one number (a scalar label)"
            raise ValueError(f"coordinate {name!r} must be {expected} (got an array of shape {array.shape})")
        if along and not len(array):
            raise ValueError(f"coordinate {name!r} holds no label")
        if name in _LABEL_RANGES:
            low, high, unit = _LABEL_RANGES[name]
            bad = (array < low) | (array > high)
            if np.any(bad):
                raise ValueError(f"coordinate {name!r} must satisfy {low:g} <= {name} <= {high:g} {unit}"
                                 f"{_first(array, bad)}")
        if name == "point" and name in dims:
            if not np.array_equal(array, np.arange(len(array))):
                raise ValueError(f"coordinate 'point' must number the points 0 ... {len(array) - 1} "
                                 f"(got {_short(array.tolist())})")
        elif name in dims and name != "wavelength" and len(np.unique(array)) != len(array):
            raise ValueError(f"coordinate {name!r} must hold distinct labels (got {_short(array.tolist())})")


# -- 3. shapes ------------------------------------------------------------------------


def check_shapes(arrays: Mapping[str, tuple[tuple[str, ...], Any]], sizes: Mapping[str, int]) -> None:
    """Every array (name → (its dims, values)) has one entry per label of each of its dims."""

    for name, (array_dims, values) in arrays.items():
        expected = tuple(sizes[d] for d in array_dims)
        shape = np.shape(values)
        if shape != expected:
            over = " x ".join(f"{d} ({n})" for d, n in zip(array_dims, expected)) or "no dim (a scalar)"
            raise ValueError(f"{_field(name)} has shape {shape}; its dims {over} give {expected}")


def _field(name: str) -> str:
    """``counts.sample.rays`` → ``counts['sample'] 'rays'``; ``counts.reflected`` → ``'reflected'``."""

    head, _, rest = name.partition(".")
    if not rest:
        return f"'{name}'"
    if head == "counts" and "." not in rest:
        return f"'{rest}'"
    if head == "result":
        return _field(rest)
    group, _, leaf = rest.rpartition(".")
    return f"{head}[{group!r}] '{leaf}'" if group else f"{head} '{leaf}'"


# -- 4. counts add up -----------------------------------------------------------------


@dataclass(frozen=True)
class CountRules:
    """
    How a group of counts (name → array over the readings' dims) adds up, as a kind says.

    Attributes
    ----------
    total : str or None
        The count every part is a share of (``rays``): it must be ≥ 1 (``None``: no such count).
    parts : dict
        part → whole: 0 ≤ part ≤ whole (another count of the group) per reading.
    sums : tuple
        ``(parts, whole, exact)``: the parts (names; ``fnmatch`` patterns such as
        ``lost_*``) add up to the whole (``exact``) or to at most it, per reading.
    fractions : tuple of str
        Values of the group (not counts) that lie in [0, 1] per reading (a wall reflectance).
    """

    total: str | None = "rays"
    parts: Mapping[str, str] = field(default_factory=dict)
    sums: tuple[tuple[tuple[str, ...], str, bool], ...] = ()
    fractions: tuple[str, ...] = ()


def check_counts(group: str, counts: Mapping[str, np.ndarray], rules: CountRules,
                 where: Callable[[tuple[int, ...]], str]) -> None:
    """
    ``ValueError`` for the first rule of ``rules`` that ``counts`` break (naming the
    ``group`` — ``""``, ``"pilot"``, ``"counts['standard']"`` —, the fields and the
    reading, ``where(index)``), or for a count the rules name that the group lacks.
    """

    prefix = f"{group} " if group else ""

    def get(name: str) -> np.ndarray:
        if name not in counts:
            raise ValueError(f"{prefix}lacks the count '{name}'")
        return np.asarray(counts[name])

    if rules.total is not None:
        _fail(prefix, get(rules.total) < 1, f"'{rules.total}' must be at least 1", where)
    for part, whole in rules.parts.items():
        _fail(prefix, get(part) > get(whole), f"'{part}' holds a count above '{whole}'", where)
    for patterns, whole, exact in rules.sums:
        names = [n for p in patterns for n in (fnmatch.filter(counts, p) if "*" in p else [p])]
        added = sum((get(n) for n in names), np.zeros_like(get(whole)))
        words = " + ".join(f"'{n}'" for n in names)
        if exact:
            _fail(prefix, added != get(whole), f"{words} must add up to '{whole}'", where)
        else:
            _fail(prefix, added > get(whole), f"{words} add up to more than '{whole}'", where)
    for name in rules.fractions:
        _fail(prefix, ~((get(name) >= 0) & (get(name) <= 1)), f"'{name}' must satisfy 0 <= {name} <= 1", where)


def _fail(prefix: str, bad: np.ndarray, what: str, where: Callable[[tuple[int, ...]], str]) -> None:
    if np.any(bad):
        index = tuple(int(i) for i in np.argwhere(np.atleast_1d(bad))[0]) if np.ndim(bad) else ()
        raise ValueError(f"{prefix}{what} ({where(index)})")


def reading_at(dims: tuple[str, ...], coords: Mapping[str, Any]) -> Callable[[tuple[int, ...]], str]:
    """``where(index)``: the labels of the reading at ``index`` over ``dims`` (``"reading wavelength=551, …"``)."""

    def where(index: tuple[int, ...]) -> str:
        labels = [f"{d}={_label(np.asarray(coords[d])[k])}" for d, k in zip(dims, index)]
        labels += [f"{n}={_label(v)}" for n, v in coords.items() if n not in dims and np.ndim(v) == 0]
        return "reading " + ", ".join(labels) if labels else "the reading"

    return where


def _label(value: Any) -> str:
    value = value.item() if hasattr(value, "item") else value
    return f"{value:g}" if isinstance(value, float) else str(value)


def check_result(result: Any, sized: bool = True) -> None:
    """
    Rules 2 to 4 for a result of any kind: its labels (:func:`check_labels`), the shapes of
    its arrays (:func:`check_shapes`), its counts (:func:`check_counts` of every group the
    kind declares, ``result._count_groups()``) and its settings (:func:`check_settings`;
    ``sized=False``: readings whose rays were sized by something else than their settings'
    μ, e.g. a certified target's, whose rays follow the target's weights).
    """

    check_labels(result.dims, result.coords, result.parameters, result.KIND_DIMS)
    sizes = {d: len(np.atleast_1d(result.coords[d])) for d in result.dims}
    check_shapes(result._labelled(), sizes)
    for group, counts, rules, dims in result._count_groups():
        check_counts(group, counts, rules, reading_at(dims, result.coords))
    check_settings(result, sized)


def check_settings(result: Any, sized: bool = True) -> None:
    """
    The settings a result states agree with its labels and counts: its wavelengths are the
    wavelength labels, its θi the θi label of readings at one incidence (a selection of readings restates both:
    :meth:`~virtspec_mi.results.labels.Labelled.isel`), and a μ the rays it sized can
    certify — no rule of :mod:`virtspec_mi.budgets` holds a fraction within μ with N ≤ 1/μ
    rays (the binomial bound's ε − 1/N > 0; Hoeffding's N = ln(2/δ)/(2μ²) is larger).
    """

    settings = getattr(result, "settings", None)
    if settings is None or not hasattr(settings, "wavelengths") or "wavelength" not in result.coords:
        return
    labels = [float(w) for w in np.atleast_1d(result.coords["wavelength"])]
    if [float(w) for w in settings.wavelengths] != labels:
        raise ValueError(f"the settings' wavelengths {_short(list(settings.wavelengths))} are not the wavelength "
                         f"labels {_short(labels)}")
    angles = np.atleast_1d(result.coords.get("theta_i", []))
    if len(angles) == 1 and float(settings.theta_i) != float(angles[0]):  # one incidence: the settings' own
        raise ValueError(f"the settings' theta_i {settings.theta_i:g} is not the theta_i label {float(angles[0]):g} "
                         "of the readings")
    rays = np.asarray(getattr(result, "rays", np.array([])), dtype=np.float64)
    if sized and getattr(settings, "rays", 0) is None and rays.size and np.any(rays * float(settings.mu) <= 1.0):
        raise ValueError(f"mu = {float(settings.mu):g} ({settings.bound}) cannot be certified with "
                         f"{int(rays.min()):,} rays a reading (no rule holds a fraction within mu with N <= 1/mu)")
    adaptive = getattr(settings, "adaptive", False)
    if adaptive and hasattr(result, "pilot") and result.pilot is None:  # two-stage: sized by a pilot, which it keeps
        raise ValueError(f"the settings say {settings.bound} (each reading sized by a pilot batch) but the file holds "
                         "no pilot counts: its certificate (mu) would rest on nothing it shows")


# -- 6. agreement ---------------------------------------------------------------------


def check_agreement(content: tuple[str, Any], result: Any) -> None:
    """
    Rule 6 for a dataset: the count variables and the coordinates a file holds besides the
    data its result is rebuilt from equal the rebuilt result's (``result._count_variables()``,
    what its ``to_dataset`` writes): a NetCDF file's or a Zarr store's (``"dataset"``; a
    sweep's Zarr table, ``"table"``, over its grid), a CSV file's rows (``"rows"``). A
    JSON object's own derived counts are checked as it is read
    (:meth:`~virtspec_mi.results.base.ResultBase.from_dict`).
    """

    kind, value = content
    own = getattr(result, "_agreement", None)  # a kind that shows more than counts checks all it shows
    if own is not None:
        own(kind, value)
        return
    if kind not in ("dataset", "table", "rows"):
        return
    rebuilt = result
    for name in ("wavelength", "theta_i") if kind == "table" else ():  # a table holds a reading over the grid
        rebuilt = rebuilt if name in rebuilt.dims else rebuilt._expanded(name)
    counts = rebuilt._count_variables()
    if kind == "rows":
        _agree_rows(value, counts, rebuilt)
        return
    for name, (dims, values) in counts.items():
        if name in value.variables:
            theirs = value[name]
            if tuple(theirs.dims) != tuple(dims) or theirs.shape != np.shape(values):
                raise ValueError(f"variable {name!r} has dims {tuple(theirs.dims)} and shape {theirs.shape}; the result "
                                 f"it holds gives {tuple(dims)} and {np.shape(values)}")
            _agree_values(name, theirs.values, np.asarray(values), "variable")
    for name, values in rebuilt.coords.items():
        if name in value.variables:
            theirs = value[name]
            if theirs.shape != np.shape(values):
                raise ValueError(f"coordinate {name!r} has shape {theirs.shape}; the result it holds gives "
                                 f"{np.shape(values)}")
            _agree_values(str(name), theirs.values, np.asarray(values), "variable")


def agree_values(name: str, theirs: Any, ours: Any, what: str = "variable") -> None:
    """``ValueError`` naming ``what`` ``name`` and the first entry where a file's values differ from the result's."""

    _agree_values(name, np.asarray(theirs), np.asarray(ours), what)


def agree_stored(name: str, stated: Any, computed: Any, exact: bool = False) -> None:
    """
    Rule 6 for a value a file states beside the counts it is rebuilt from (a JSON object's
    ``rays_spent``, ``certified_mu``): it must be what the counts give — exactly for counts,
    to 1e-9 relative for a derived number (its text form's rounding); NaN (null) only
    where the counts give NaN. Else ``ValueError`` naming the field, the index and both values.
    """

    stated = np.atleast_1d(np.asarray(stated, dtype=np.float64))
    computed = np.atleast_1d(np.asarray(computed, dtype=np.float64))
    both_nan = np.isnan(stated) & np.isnan(computed)
    close = stated == computed if exact else np.isclose(stated, computed, rtol=1e-9, atol=0.0)
    same = both_nan | close
    if not np.all(same):
        index = tuple(int(i) for i in np.argwhere(~same)[0])
        raise ValueError(f"{_quoted(name)} states {_plain_number(stated[index])!r} at index {list(index)} where the "
                         f"file's counts give {_plain_number(computed[index])!r} (the file was edited against its "
                         "counts)")


def _agree_values(name: str, theirs: np.ndarray, ours: np.ndarray, what: str) -> None:
    if ours.dtype.kind in "iuf":
        try:
            theirs_f = np.asarray(theirs, dtype=np.float64)
        except (ValueError, TypeError):
            raise ValueError(f"{what} {name!r} must hold numbers") from None
        if np.any(~np.isfinite(theirs_f)) and ours.dtype.kind != "f":
            bad = ~np.isfinite(theirs_f)
            raise ValueError(f"{what} {name!r} holds a value that is not a finite number{_first(theirs_f, bad)}")
        same = (theirs_f == ours) | (np.isnan(theirs_f) & np.isnan(np.asarray(ours, dtype=np.float64)))
    else:
        same = _texts(theirs) == _texts(ours)
    if not np.all(same):
        index = tuple(int(i) for i in np.argwhere(~np.atleast_1d(same))[0])
        shown = _plain_number(np.atleast_1d(theirs)[index])
        expected = _plain_number(np.atleast_1d(ours)[index])
        raise ValueError(f"{what} {name!r} holds {shown!r} at index {list(index)} where the result the file holds "
                         f"gives {expected!r} (the file was changed after it was written)")


def _plain_number(value: Any) -> Any:
    """A numpy value as Python's, a whole float as an int (a CSV file's counts are read as floats)."""

    value = value.item() if hasattr(value, "item") else value
    return int(value) if isinstance(value, float) and value.is_integer() and abs(value) < 2**63 else value


def _texts(values: Any) -> np.ndarray:
    """Labels as Python strings (numpy's fixed and variable-width string dtypes, objects)."""

    array = np.asarray(values, dtype=object)
    return np.array([str(v) for v in array.ravel()], dtype=object).reshape(array.shape)


def _agree_rows(rows: Any, counts: Mapping[str, tuple[tuple[str, ...], Any]], result: Any) -> None:
    """A CSV file's rows (one per cell of the result's dims, in their order) against the result's counts and labels."""

    import xarray as xr

    coords = {name: (result.coord_dims(name), values) for name, values in result.coords.items()}
    frame = xr.Dataset(dict(counts), coords=coords).to_dataframe(dim_order=list(result.dims)).reset_index()
    if rows.sizes.get("row", 0) != len(frame):
        raise ValueError(f"holds {rows.sizes.get('row', 0)} rows; the result in its header gives {len(frame)} "
                         "(a truncated or edited file)")
    for name in frame.columns:
        if name in rows.variables:
            _agree_values(str(name), rows[name].values, frame[name].to_numpy(), "column")


# -- 7. checksums ---------------------------------------------------------------------

CHECKSUM: str = "checksum"
"""The key of a file's checksum in its JSON object (``"sha256:…"``)."""


def checksum(data: Mapping[str, Any]) -> str:
    """``"sha256:<hex>"`` of ``data`` without its :data:`CHECKSUM`, in canonical JSON (sorted keys, compact)."""

    return _digest(_canonical({k: v for k, v in data.items() if k != CHECKSUM}))


def sealed_text(data: Mapping[str, Any]) -> str:
    """``data`` (without a :data:`CHECKSUM`) as compact JSON with its checksum added, encoded once."""

    text = _canonical(data)
    return text[:-1] + ("," if len(text) > 2 else "") + f'"{CHECKSUM}":"{_digest(text)}"}}'


_SEAL = re.compile(r',"checksum":"(sha256:[0-9a-f]{64})"\}\s*$')


def unsealed(text: str, data: dict[str, Any]) -> dict[str, Any]:
    """
    ``data`` (parsed from ``text``) without its :data:`CHECKSUM` when ``text`` is exactly
    what :func:`sealed_text` wrote — its checksum verified on the text itself, without
    encoding ``data`` again —, else ``data`` as it is (:func:`check_checksum` then checks it).
    """

    match = _SEAL.search(text, max(len(text) - 200, 0)) if CHECKSUM in data else None
    if match is not None and _digest(text[:match.start()] + "}") == match.group(1) == data[CHECKSUM]:
        return {k: v for k, v in data.items() if k != CHECKSUM}
    return data


def _canonical(data: Mapping[str, Any]) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), default=_plain, allow_nan=True)


def _digest(text: str) -> str:
    return "sha256:" + hashlib.sha256(text.encode("utf-8")).hexdigest()


def _plain(value: Any) -> Any:
    """numpy values as JSON (arrays as nested lists, NaN as ``None``) for :func:`checksum`."""

    if isinstance(value, np.ndarray):
        if value.dtype.kind == "f":
            return np.where(np.isnan(value), None, value).tolist()
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON: {type(value).__name__}")


def check_checksum(data: Mapping[str, Any]) -> None:
    """Rule 7: ``data``'s :data:`CHECKSUM`, when it has one, is :func:`checksum` of the rest."""

    if not isinstance(data, Mapping) or CHECKSUM not in data:
        return
    stored = data[CHECKSUM]
    try:
        computed = checksum(data)
    except (TypeError, ValueError):
        raise ValueError("its content is not plain JSON data") from None
    if stored != computed:
        raise ValueError(f"its content does not match its checksum ({_short(stored)}): the file was changed after "
                         "virtspec-mi wrote it (an edit, or damage); its counts cannot be trusted")


# -- reading a file -------------------------------------------------------------------


def read_file(path: str | os.PathLike, read: Callable[[Path], tuple[str, Any]],
              build: Callable[[tuple[str, Any]], Any]) -> Any:
    """
    The result in ``path``: ``read(path)`` gives its content (``("plain" | "dataset" |
    "rows" | "table", …)``), ``build(content)`` the result (checked by rules 1 to 5 and 7
    as it is built), then rule 6. Every ``ValueError`` becomes one line naming the file:
    ``result file PATH: …``; a missing file raises ``FileNotFoundError``.
    """

    path = Path(path)
    try:
        content = read(path)
        result = build(content)
        check_agreement(content, result)
    except FileNotFoundError:
        raise MissingFile(f"result file {path}: not found") from None
    except ValueError as error:
        raise ValueError(f"result file {path}: {_one_line(error)}") from None
    return result


class MissingFile(FileNotFoundError, ValueError):
    """A result file that is not there: a ``FileNotFoundError`` and, as every bad file, a ``ValueError``."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.errno = errno.ENOENT


def _one_line(error: BaseException) -> str:
    return " ".join(str(error).split())
